"""The command line: summaries, files, and one-line errors with a non-zero exit (no traceback)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from mcdm_pin.cli import main

from .conftest import REPO, TWO_LINK


def cli(*args):
    proc = subprocess.run([sys.executable, "-m", "mcdm_pin.cli", *map(str, args)], cwd=REPO,
                          capture_output=True, text=True, timeout=300)
    return proc.returncode, proc.stdout, proc.stderr


def test_info_prints_robot_and_validation(capsys):
    assert main(["info", str(TWO_LINK)]) == 0
    out = capsys.readouterr().out
    assert "2 joints, 4 DoF, 8 cables" in out
    assert "shoulder  spherical    3  q1_x, q2_y, q3_z" in out
    assert "base[0.15, 0.0, 0.0] -> link1[0.05, 0.0, 0.1]" in out
    assert "[ok] mass matrix positive definite" in out
    # the paper's arm cannot twist link 1 about its own axis at q = 0 (all cables radial)
    assert "[warn] cables span only 3 of 4 DoF at q = 0" in out


def test_solve_prints_summary_and_writes_files(tmp_path, capsys):
    npz, csv = tmp_path / "run.npz", tmp_path / "run.csv"
    code = main(["solve", str(TWO_LINK), "--trajectory", "traj1", "--case", "3", "--samples", "21",
                 "--quiet", "--out", str(npz), "--out", str(csv)])
    assert code == 0
    out = capsys.readouterr().out
    assert "shoulder" in out and "all 21 instants solved" in out and "time per instant" in out
    with np.load(npz) as z:
        assert z["f"].shape == (21, 8)
        assert z["interaction_angle_deg"][:, 0].max() <= 30.0 + 1e-6
    assert csv.read_text().count("\n") == 22


def test_solve_reports_infeasible_instants(capsys):
    assert main(["solve", str(TWO_LINK), "-t", "traj2", "--case", "1", "-q"]) == 0
    out = capsys.readouterr().out
    assert "no valid answer at 1 of 101 instants" in out
    assert "t = 0.000 s  infeasible: bounds" in out


def test_weights_and_cones_from_the_command_line(capsys):
    assert main(["solve", str(TWO_LINK), "-t", "traj2", "--case", "3", "--cone", "all=25",
                 "--weights", "shoulder=1:0.5,elbow=0.1", "--samples", "11", "-q"]) == 0
    out = capsys.readouterr().out
    assert "InteractionCone('shoulder', 25.0" in out
    assert "'shoulder': 1.0" in out and "'elbow': 0.1" in out


@pytest.mark.parametrize("args, message", [
    (["solve", TWO_LINK, "-t", "traj1", "--case", "4"], "invalid choice"),
    (["solve", TWO_LINK, "-t", "nope"], "no trajectory 'nope'"),
    (["solve", TWO_LINK, "-t", "traj1", "--case", "3", "--cone", "elbow=10"], "spherical joints only"),
    (["solve", TWO_LINK, "-t", "traj1", "--case", "3", "--cone", "shoulder=95"], "(0, 90)"),
    (["solve", TWO_LINK, "-t", "traj1", "--case", "2", "--weights", "hip=1"], "unknown joint 'hip'"),
    (["solve", TWO_LINK, "-t", "traj1", "--case", "2", "--weights", "shoulder"], "NAME=VALUE"),
    (["solve", TWO_LINK, "-t", "traj1", "--out", "run.txt"], ".npz or .csv"),
    (["solve", TWO_LINK, "-t", "traj1", "--solver", "gurobi"], "unknown solver"),
    (["solve", TWO_LINK, "-t", "traj1", "--case", "1", "--cone", "shoulder=10"], "--case 3 only"),
    (["info", "missing.yaml"], "missing.yaml: file not found"),
    (["solve", TWO_LINK], "--trajectory"),
])
def test_bad_arguments_exit_2_with_one_line(args, message):
    code, out, err = cli(*args)
    assert code == 2
    assert message in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_bad_sidecar_in_info_is_one_line(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text(TWO_LINK.read_text().replace("f_min: 0.001", "f_min: -1", 1)
                   .replace("../urdf/", str(REPO / "urdf") + "/"))
    code, out, err = cli("info", bad)
    assert code == 2 and "cables[0].f_min" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
