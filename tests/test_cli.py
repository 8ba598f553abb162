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
def test_bad_arguments_exit_2_with_one_line(args, message, capsys, tmp_path, monkeypatch):
    """In this process (``main``, as ``python -m mcdm_pin.cli`` runs it; argparse's own errors leave
    by ``SystemExit``): the next test runs the real command for both kinds of error."""
    monkeypatch.chdir(tmp_path)
    try:
        code = main(list(map(str, args)))
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2
    assert message in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not any(tmp_path.iterdir())  # nothing written on the way out


@pytest.mark.parametrize("args, message", [
    (["solve", TWO_LINK, "-t", "traj1", "--case", "4"], "invalid choice"),  # argparse's
    (["solve", TWO_LINK, "-t", "traj1", "--case", "3", "--cone", "shoulder=95"], "(0, 90)"),  # ours
])
def test_the_command_exits_2_with_one_line(args, message):
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


def _variant(tmp_path, old, new, name="variant.yaml"):
    text = TWO_LINK.read_text()
    assert old in text
    path = tmp_path / name
    path.write_text(text.replace(old, new).replace("../urdf/", str(REPO / "urdf") + "/"))
    return path


def test_info_checks_every_trajectory_and_says_where_it_fails(tmp_path, capsys):
    """info used to check only the zero pose: a sidecar whose trajectory has a q_start of the wrong
    length passed (exit 0), and a routing that holds q = 0 but fails along the motion passed too."""
    bad = _variant(tmp_path, "q_start: [0.2, -0.2, -0.1, 0.2]", "q_start: [0.2, -0.2, -0.1]")
    assert main(["info", str(bad)]) == 1
    out = capsys.readouterr().out
    assert "[fail] trajectory traj2: cannot be built:" in out and "q_start: expected 4 values" in out
    assert "[ok] trajectory traj1: 101 instants over 1 s; case 1 feasible at all 11 instants checked" in out
    # cables of at most 30 N hold the zero pose but not the fast part of traj1 (case 1 needs 53.8 N)
    weak = _variant(tmp_path, "f_max: 1000.0", "f_max: 30.0")
    assert main(["info", str(weak)]) == 0  # infeasible instants are a warning: the robot is valid
    out = capsys.readouterr().out
    assert "[ok] holds the zero pose against gravity" in out
    line = next(x for x in out.splitlines() if "trajectory traj1" in x)
    assert line.startswith("  [warn]") and "case 1 has no answer at 6 of 11 instants checked (t = 0.1, 0.2, 0.3" in line
    assert "a common f_max of 42.8448 N would suffice" in line


def test_info_given_a_urdf_or_a_results_file_says_what_it_is(tmp_path):
    code, out, err = cli("info", REPO / "urdf" / "two_link_sr.urdf")
    assert code == 2 and "is a URDF" in err and "robots/two_link_sr.yaml" in err and "YAML at line" not in err
    npz = tmp_path / "run.npz"
    np.savez(npz, t=np.zeros(2))
    code, out, err = cli("info", npz)
    assert code == 2 and "is a results file (.npz" in err and "codec" not in err


def test_no_library_module_imports_the_command_line():
    """The command line is a package on top: nothing below imports it (or argparse), so that it can
    change without touching the library (``python -m mcdm_pin`` is its entry point)."""
    import ast

    offenders = []
    for path in (REPO / "mcdm_pin").rglob("*.py"):
        rel = path.relative_to(REPO / "mcdm_pin")
        if rel.parts[0] == "cli" or rel.name == "__main__.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):  # the module and each name imported from it
                base = "." * node.level + (node.module or "")
                names = [base] + [f"{base}.{a.name}".replace("..", ".") if node.module else base + a.name
                                  for a in node.names]
            else:
                continue
            for name in names:
                parts = name.lstrip(".").split(".")
                if name == "argparse" or "mcdm_pin.cli" in name or (name.startswith(".") and "cli" in parts[:1]):
                    offenders.append(f"{rel}: {name}")
    assert not offenders, offenders


@pytest.mark.parametrize("command", ["info", "solve", "import-caspr", "view", "plot", "verify", "compile"])
def test_every_command_has_help(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0 and "usage: mcdm-pin" in capsys.readouterr().out


def test_stage_counts_name_the_stage_behind_a_constant_objective():
    """``mcdm-pin solve``'s last line counts the answering stages; where the objective is a constant
    (``flat_objective``, every weight zero) it says so and counts the stages that answered the
    least-norm feasible problem."""
    from types import SimpleNamespace

    from mcdm_pin.cli.solve import stage_counts

    flat = SimpleNamespace(stage=np.array(["flat_objective>warm_active_set"] * 3 + ["flat_objective>ipm>polish"]),
                           iterations=np.array([1, 2, 1, 13]))
    assert stage_counts(flat) == (
        "the objective is a constant (every weight is zero): the forces are the least-norm feasible ones\n"
        "answered by warm_active_set at 3 instants (median 1 KKT solves), ipm at 1 (median 13 interior-point "
        "iterations)")
    usual = SimpleNamespace(stage=np.array(["warm_active_set", "warm_active_set", "ipm>polish"]),
                            iterations=np.array([2, 2, 7]))
    assert stage_counts(usual) == ("answered by warm_active_set at 2 instants (median 2 KKT solves), ipm at 1 "
                                   "(median 7 interior-point iterations)")
    cold = SimpleNamespace(stage=np.array(["dual_active_set", "warm_active_set", "warm_active_set"]),
                           iterations=np.array([6, 1, 1]))
    assert stage_counts(cold) == ("answered by warm_active_set at 2 instants (median 1 KKT solves), dual_active_set "
                                  "at 1 (median 6 Newton steps and KKT solves)")
