"""Issue 27: workspace stores that are verified before they are trusted, created once, interrupted
cleanly; OpenSim names made legal and files read back; the time budget inside a back-end call; one
clear line instead of a traceback."""

from __future__ import annotations

import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from mcdm_pin.cli import main
from mcdm_pin.workspace import Grid, Setup, WorkspaceError, compute_workspace, open_workspace

from .conftest import REPO, TWO_LINK

ENV = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""),
           MCDM_PIN_JIT="off")


# ------------------------------------------------------------------------------- workspace stores
@pytest.fixture(scope="module")
def store(tmp_path_factory, two_link):
    """A complete store of 4 chunks (case 1, so needed_cone_deg is NaN throughout)."""
    path = tmp_path_factory.mktemp("ws") / "arm.zarr"
    poses = Grid(two_link, {"q1_x": (-1.2, 1.2, 5), "q4_x": (-1.5, 1.5, 4)}, at={"q2_y": 0.1})
    compute_workspace(two_link, poses, path, Setup(case=1), chunk=6, scheduler="inline", progress=False)
    return path, poses


def _copy(store, tmp_path, name="copy.zarr"):
    path, poses = store
    copy = tmp_path / name
    shutil.copytree(path, copy)
    return copy, poses


def test_resume_recomputes_a_chunk_flagged_done_whose_data_is_missing(store, two_link, tmp_path):
    copy, poses = _copy(store, tmp_path)
    (copy / "f" / "1.0").unlink()  # chunk 1's forces lost; its flag still says done
    report = compute_workspace(two_link, poses, copy, Setup(case=1), chunk=6, scheduler="inline",
                               resume=True, progress=False)
    assert report.computed_chunks == 1 and list(report.recomputed) == [1]
    assert "f: its data is missing" in report.recomputed[1]
    f = open_workspace(copy)["f"].values
    np.testing.assert_array_equal(f, open_workspace(store[0])["f"].values)  # one process: bit for bit
    assert not np.isnan(f[open_workspace(copy)["status"].values == "optimal"]).any()


def test_a_corrupted_chunk_is_named_on_reading_and_recomputed_on_resume(store, two_link, tmp_path, capsys):
    copy, poses = _copy(store, tmp_path)
    (copy / "status" / "2").write_bytes(b"\x02\x01torn chunk" * 4)
    with pytest.raises(WorkspaceError, match=r"copy\.zarr: chunk 2 is flagged done but status: unreadable"):
        open_workspace(copy)
    code = main(["plot", str(copy), "--out", str(tmp_path / "figs")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "copy.zarr: chunk 2 is flagged done but status: unreadable" in err and "--resume" in err
    code = main(["workspace", str(TWO_LINK), "--grid", "q1_x=-1.2:1.2:5", "--grid", "q4_x=-1.5:1.5:4",
                 "--at", "q2_y=0.1", "--scheduler", "inline", "--chunk", "6", "--out", str(copy),
                 "--resume", "-q"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "chunk 2 was flagged done but status: unreadable" in err and "computed 1 of 4 chunks" in out
    assert (open_workspace(copy)["status"].values == open_workspace(store[0])["status"].values).all()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_unreachable_scheduler_leaves_no_store_behind(two_link, tmp_path, monkeypatch):
    from mcdm_pin.workspace import schedule

    monkeypatch.setattr(schedule, "CONNECT_TIMEOUT_S", 1, raising=False)
    path = tmp_path / "arm.zarr"
    poses = Grid(two_link, {"q1_x": (-1.0, 1.0, 3)})
    with pytest.raises(WorkspaceError, match=r"cannot connect"):
        compute_workspace(two_link, poses, path, scheduler=f"tcp://127.0.0.1:{_free_port()}", progress=False)
    assert not path.exists() and not list(tmp_path.iterdir())
    compute_workspace(two_link, poses, path, scheduler="inline", progress=False)  # the rerun works


def test_two_runs_creating_one_store_end_in_one_store_and_a_clear_error(store, two_link, tmp_path,
                                                                        monkeypatch):
    """The other run finishes creating the store between this run's check and its rename."""
    import zarr

    winner, poses = _copy(store, tmp_path, "winner.zarr")
    path = tmp_path / "arm.zarr"
    real = zarr.consolidate_metadata

    def meanwhile(where, *a, **k):
        result = real(where, *a, **k)
        if not path.exists():
            shutil.copytree(winner, path)
        return result

    monkeypatch.setattr(zarr, "consolidate_metadata", meanwhile)
    with pytest.raises(WorkspaceError, match=r"arm\.zarr: created by another run meanwhile"):
        compute_workspace(two_link, poses, path, Setup(case=1), chunk=6, scheduler="inline", progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.zarr", "winner.zarr"]  # no leftovers
    np.testing.assert_array_equal(open_workspace(path)["f"].values, open_workspace(winner)["f"].values)


def _group_ends(pgid: int, within_s: float) -> bool:
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline:
        try:
            os.killpg(pgid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    return False


def _ctrl_c_at_default():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def test_ctrl_c_on_a_dask_workspace_is_one_line_that_says_what_was_kept(tmp_path):
    out = tmp_path / "arm.zarr"
    args = [sys.executable, "-m", "mcdm_pin", "workspace", str(TWO_LINK), "--random", "3000",
            "--chunk", "30", "--scheduler", "local", "--workers", "2", "--out", str(out), "-q"]
    # the run starts as from a terminal, with Ctrl-C at its default disposition: a test process that
    # was itself started in the background of a non-interactive shell (as a CI runner may start it)
    # ignores SIGINT, its children inherit that, and Python then installs no KeyboardInterrupt handler
    proc = subprocess.Popen(args, cwd=tmp_path, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True, preexec_fn=_ctrl_c_at_default)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            flags = out / "chunk_done"
            if flags.is_dir() and len([p for p in flags.iterdir() if p.name.isdigit()]) >= 2:
                break
            time.sleep(0.05)
        assert proc.poll() is None, proc.communicate()
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
        _, err = proc.communicate(timeout=60)
        assert _group_ends(proc.pid, 20.0), "worker processes outlived the interrupted run"
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait(timeout=30)
    assert proc.returncode == 130
    assert len(err.strip().splitlines()) == 1, err
    m = re.fullmatch(r"mcdm-pin: workspace interrupted: (.*) keeps (\d+) of 100 chunks; give --resume to "
                     r"complete it", err.strip())
    assert m and m.group(1) == str(out), err
    assert int(m.group(2)) == int((open_workspace(out)["chunk_done"].values == 1).sum()) >= 2


# ---------------------------------------------------------------------------------- OpenSim export
def _hostile_names_robot(tmp_path):
    """The 2-link arm with a link and a joint named with spaces and non-ASCII letters, a joint (ours)
    with a slash, and cable names with NUL and an XML markup character."""
    import yaml

    urdf = (REPO / "urdf" / "two_link_sr.urdf").read_text()
    urdf = urdf.replace('"link2"', '"Unterarm ä"').replace('"q4_x"', '"Ellbogen beugen"')
    (tmp_path / "arm.urdf").write_text(urdf, encoding="utf-8")
    sc = yaml.safe_load(TWO_LINK.read_text())
    sc["urdf"] = "arm.urdf"
    sc.pop("trajectories", None)
    sc["joints"] = {("elbow/ö" if k == "elbow" else k): v for k, v in sc["joints"].items()}
    sc["joints"]["elbow/ö"]["urdf_joints"] = ["Ellbogen beugen"]
    for c in sc["cables"]:
        for p in c["route"]:
            p["link"] = "Unterarm ä" if p["link"] == "link2" else p["link"]
    sc["cables"][0]["name"] = "c\x00one"
    sc["cables"][1]["name"] = "c<two>&"
    sc["cables"][2]["name"] = "c_one"  # what the first one would become: kept, the first gets #2
    (tmp_path / "arm.yaml").write_text(yaml.safe_dump(sc, sort_keys=False, allow_unicode=True),
                                       encoding="utf-8")
    return tmp_path / "arm.yaml"


def test_export_opensim_makes_every_name_legal_and_reads_the_file_back(tmp_path):
    from xml.etree import ElementTree

    pytest.importorskip("opensim", reason="OpenSim not installed (optional)")
    sidecar = _hostile_names_robot(tmp_path)
    out = tmp_path / "arm.osim"
    run = subprocess.run([sys.executable, "-m", "mcdm_pin", "export-opensim", str(sidecar), str(out),
                          "--check", "3"], cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    for line in ["body 'Unterarm ä' -> Unterarm_a", "joint 'elbow/ö' -> elbow_o",
                 "coordinate 'Ellbogen beugen' -> Ellbogen_beugen", "cable 'c\\x00one' -> c_one#2",
                 "cable 'c<two>&' -> c_two__"]:
        assert line in run.stdout, run.stdout
    assert "moment arms" in run.stdout and "warning" not in run.stdout
    model = ElementTree.parse(out).getroot().find("Model")  # XML, read back
    names = {tag: [e.get("name") for e in model.find(f"{tag}/objects")] for tag in ("BodySet", "JointSet", "ForceSet")}
    assert names["BodySet"] == ["link1", "Unterarm_a"] and names["JointSet"] == ["shoulder", "elbow_o"]
    assert names["ForceSet"][:3] == ["c_one#2", "c_two__", "c_one"]
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


def test_names_made_legal_are_unique_and_keep_legal_spellings():
    from mcdm_pin.export.osim_names import legal_names

    m = legal_names(["a b", "a_b", "a/b", "", "..", "ﬁx\x00", "ground"], taken={"ground"})
    assert m == {"a b": "a_b#2", "a_b": "a_b", "a/b": "a_b#3", "": "_", "..": "_..", "ﬁx\x00": "fix_",
                 "ground": "ground#2"}


# ------------------------------------------------------------------------------ the time budget
def _tiny_bounds_robot(tmp_path):
    """The 2-link arm without gravity, every cable bounded to 1e-100..1e-90 N (the smallest bounds the
    limits let through: docs/limits.md)."""
    import yaml

    from mcdm_pin import Robot

    sc = yaml.safe_load(TWO_LINK.read_text())
    sc["urdf"] = str((TWO_LINK.parent / sc["urdf"]).resolve())
    sc["gravity"] = [0.0, 0.0, 0.0]
    for c in sc["cables"]:
        c["f_min"], c["f_max"] = 1e-100, 1e-90
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    return Robot.load(tmp_path / "tiny.yaml")


@pytest.mark.parametrize("solver", ["proxqp", "default"])
def test_the_budget_holds_inside_a_proxqp_call(tmp_path, solver):
    """At t = 0.25 s of traj1 the forces cannot move the arm; with bounds of 1e-300..1e-290 N,
    ProxQP's one call ran 1.5 million inner iterations (58 s) past a 1 s budget before it stopped at
    its iteration limit. Such bounds are refused as input now (docs/limits.md), so the instant's
    problem gets them after assembly: the back-end's own budget is what is tested."""
    import numpy as np

    from mcdm_pin.model.terms import TermsEvaluator
    from mcdm_pin.problem import Context, case_problem
    from mcdm_pin.settings import Settings
    from mcdm_pin.solvers import get_solver
    from mcdm_pin.trajectory import load_trajectory

    robot = _tiny_bounds_robot(tmp_path)
    k = 1
    traj = load_trajectory(robot, "traj1").subsample(5)
    terms = TermsEvaluator(robot)(traj.q[k], traj.qd[k], traj.qdd[k])
    qp = case_problem(robot, 1).assemble(terms, Context(robot))
    qp = qp.replace(lb=np.full(robot.m, 1e-300), ub=np.full(robot.m, 1e-290))
    t0 = time.perf_counter()
    r = get_solver(solver, Settings(budget_s=0.3)).solve(qp)
    elapsed = time.perf_counter() - t0
    assert elapsed < 0.3 + 0.5, (elapsed, r.status, r.message)
    assert r.status in ("budget", "infeasible"), (r.status, r.message)


def test_force_bounds_below_the_underflow_limit_are_refused(tmp_path):
    """Bounds of 1e-300..1e-290 N were solved with f = f_min and called inaccurate (f^T f underflows):
    now the sidecar, and a CableSet built in code, refuse them, naming the key."""
    import numpy as np
    import yaml

    from mcdm_pin.exceptions import ModelError, SidecarError
    from mcdm_pin.model.cables import Cable, CableSet
    from mcdm_pin import Robot

    sc = yaml.safe_load(TWO_LINK.read_text())
    sc["urdf"] = str((TWO_LINK.parent / sc["urdf"]).resolve())
    for c in sc["cables"]:
        c["f_min"], c["f_max"] = 1e-300, 1e-290
    (tmp_path / "tiny.yaml").write_text(yaml.safe_dump(sc, sort_keys=False))
    with pytest.raises(SidecarError, match=r"cables\[0\]\.f_min: expected 0 or at least 1e-100 N"):
        Robot.load(tmp_path / "tiny.yaml")
    robot = _tiny_bounds_robot(tmp_path)  # 1e-100..1e-90: the limit itself loads, and at rest
    from mcdm_pin import InverseDynamics  # f = f_min is the answer of every case

    for case in (1, 2, 3):
        res = InverseDynamics.for_case(robot, case).solve(np.zeros(robot.nv))
        assert res.status == "optimal" and np.allclose(res.f, 1e-100, rtol=1e-9, atol=0), (case, res.message)
    cable = robot.cables.cables[0]
    with pytest.raises(ModelError, match="at least 1e-100 N"):
        CableSet(robot.model, [Cable("c", cable.route, 1e-300, 1e-290)])


# ------------------------------------------------------------------------------------ clean words
CASPR = REPO / "tests" / "data" / "caspr" / "SR_model"


def _one_error_line(capsys, argv) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err.strip()


@pytest.mark.parametrize("out, match", [
    ("afile/sub", r"--out: afile/sub: cannot be made, .*afile is a file"),
    ("/proc/mcdm_pin_out", r"--out: /proc/mcdm_pin_out: cannot be written"),
])
def test_import_caspr_into_an_unwritable_place_is_one_line(tmp_path, capsys, monkeypatch, out, match):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("a file, not a folder")
    err = _one_error_line(capsys, ["import-caspr", str(CASPR / "SR_model_bodies.xml"),
                                   str(CASPR / "SR_model_cables.xml"), "--out", out])
    assert re.search(match, err), err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


def test_import_caspr_errors_name_the_caspr_element_not_a_temporary_file(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    cables = (CASPR / "SR_model_cables.xml").read_text()
    (tmp_path / "c.xml").write_text(cables.replace("<location>0.05 0 0</location>",
                                                   "<location>1e300 0 0</location>", 1))
    err = _one_error_line(capsys, ["import-caspr", str(CASPR / "SR_model_bodies.xml"), "c.xml", "--out", "out"])
    assert ".import-caspr" not in err and ".yaml" not in err, err
    assert err.startswith("mcdm-pin: error: c.xml: cable_set[id='SR_8_cables_2']/cable_ideal[1, name='cable 1']"
                          "/attachments/attachment[2]: expected a number of magnitude at most 1e+100"), err
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module")
def run_npz(tmp_path_factory, two_link):
    """A small solved run of the 2-link arm (5 instants of traj1, case 1)."""
    from mcdm_pin import InverseDynamics, load_trajectory

    path = tmp_path_factory.mktemp("run") / "run.npz"
    traj = load_trajectory(two_link, "traj1").subsample(5)
    InverseDynamics.for_case(two_link, 1, solver="clarabel").solve_trajectory(traj, progress=False).save(path)
    return path


def test_verify_with_the_wrong_robot_names_the_file_in_plain_words(run_npz, capsys):
    err = _one_error_line(capsys, ["verify", str(REPO / "robots" / "two_link_sr_ball.yaml"), str(run_npz)])
    assert "np.str_" not in err and "''s" not in err, err
    assert (f"mcdm-pin: error: {run_npz}: the results file's coordinates ['q1_x', 'q2_y', 'q3_z', 'q4_x'] do "
            f"not match those of robot two_link_sr_ball") in err and err.endswith("wrong robot?"), err


@pytest.mark.parametrize("argv, expected", [
    (["bogus"], "mcdm-pin: error: argument COMMAND: invalid choice: 'bogus'"),
    (["solve", str(TWO_LINK), "--case", "7"], "mcdm-pin: error: solve: argument --case: invalid choice: 7"),
])
def test_argument_errors_say_mcdm_pin_once(capsys, argv, expected):
    err = _one_error_line(capsys, argv)
    assert err.startswith(expected) and err.count("mcdm-pin") == 1, err


def test_view_given_a_results_file_as_the_robot_says_so(run_npz, capsys):
    err = _one_error_line(capsys, ["view", str(run_npz)])
    assert err == (f"mcdm-pin: error: ROBOT: {run_npz} is a results file, not a robot; give the robot's "
                   f"sidecar and the results with --results: mcdm-pin view ROBOT.yaml --results {run_npz}")
