"""The compile step (mcdm_pin/jit.py): the entry points compile in several processes at once, the
stamp comes only after every worker and the final pass succeeded, and what the library calls at
runtime is exactly what the compile covered (no kernel compiles after ``mcdm-pin compile``)."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, jit, load_trajectory
from mcdm_pin.exceptions import SolverError

from .conftest import REPO


def test_compile_plan_splits_by_cost():
    """The calling process starts as a one-process compile does (the first module's entry points,
    then the heaviest); the others longest first, each to the least loaded group; every entry point
    in exactly one group."""
    names = ["m.a", "m.f", "s.b", "s.c", "s.d", "s.e"]
    costs = {"m.a": 1.0, "m.f": 2.0, "s.b": 100.0, "s.c": 40.0, "s.d": 30.0, "s.e": 35.0}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jit, "COMPILE_COST", costs)
        assert jit.compile_plan(names, 2) == [[0, 1, 2], [3, 5, 4]]
        assert jit.compile_plan(names, 1) == [[0, 1, 2, 3, 5, 4]]
        assert jit.compile_plan(names, 3) == [[0, 1, 2], [3], [5, 4]]
        assert sorted(i for g in jit.compile_plan(names, 9) for i in g) == list(range(6))
        assert len(jit.compile_plan(names, 9)) == 4 and jit.compile_plan([], 2) == []


def test_compile_plan_leads_the_anchor_by_the_registrys_first_entry_points():
    """Before its anchor (the interior-point method) the calling process compiles the registry's first
    entry points in order until their cost reaches the lead, so that another process caches the
    active-set solver the anchor shares before the anchor reaches it; the plan in one process is the
    same order."""
    names = ["m.a", "m.f", "o.x", "o.y", "s.b", "s.c", "s.d"]
    costs = {"m.a": 1.0, "m.f": 2.0, "o.x": 30.0, "o.y": 20.0, "s.b": 100.0, "s.c": 120.0, "s.d": 10.0}
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(jit, "COMPILE_COST", costs)
        mp.setattr(jit, "COMPILE_ANCHOR", "s.b")
        mp.setattr(jit, "COMPILE_LEAD", 25.0)
        assert jit.compile_plan(names, 2) == [[0, 1, 2, 4, 6], [5, 3]]
        assert jit.compile_plan(names, 1) == [[0, 1, 2, 4, 5, 3, 6]]
        mp.setattr(jit, "COMPILE_LEAD", 0.0)  # the first module's entry points only
        assert jit.compile_plan(names, 2)[0][:3] == [0, 1, 4]
    names = jit.entry_points()
    plan = jit.compile_plan(names, 2)
    lead = plan[0].index(names.index(jit.COMPILE_ANCHOR))  # the library's own plan: a prefix, then the anchor
    assert plan[0][:lead] == list(range(lead)) and lead > 1
    assert plan[1][0] == names.index("mcdm_pin.solvers._fast.active_set_answer")


def test_stamp_covers_modules_that_decorate_with_imported_decorators():
    """A module whose functions are compiled inline into kernels through a decorator it imports from
    another kernel module (``@register_jitable`` from wrapping_osim.py) is a kernel source too, as is
    one that imports ``njit`` from the package's jit.py (_ipm.py); one that only registers kernels
    defined elsewhere (ipm.py) is not: editing it needs no recompile. The modules of the structures the
    kernels take and return (_structs.py, kernel_structs.py: ``KERNEL_STRUCTURES``) are too: numba's
    cache would not see a changed field."""
    names = {p.name for p in jit.kernel_sources()}
    assert {"wrapping_osim_ellipsoid.py", "wrapping_osim.py", "_ipm.py", "_structs.py", "kernel_structs.py"} <= names
    assert "ipm.py" not in names


def test_the_note_names_the_compile_command_as_the_run_was_started(monkeypatch):
    """Under ``python -m mcdm_pin`` (the README's first command) the note before an uncompiled run
    names ``python -m mcdm_pin compile``: the ``mcdm-pin`` script's folder may not be on the shell's
    path there (pyenv's shims before a rehash); elsewhere ``mcdm-pin compile``."""
    import sys
    import types

    monkeypatch.setitem(sys.modules, "__main__", types.SimpleNamespace(__spec__=types.SimpleNamespace(
        name="mcdm_pin.__main__")))
    assert jit._compile_command() == "python -m mcdm_pin compile"
    monkeypatch.setitem(sys.modules, "__main__", types.SimpleNamespace(__spec__=None))  # the script
    assert jit._compile_command() == "mcdm-pin compile"


def test_workers_setting(monkeypatch):
    monkeypatch.setenv(jit.WORKERS_ENV, "3")
    assert jit.compile_workers() == 3
    monkeypatch.setenv(jit.WORKERS_ENV, "zero")
    with pytest.raises(SolverError, match=jit.WORKERS_ENV):
        jit.compile_workers()
    monkeypatch.delenv(jit.WORKERS_ENV)
    assert jit.compile_workers() >= 1


def _stand_in(monkeypatch, tmp_path, child_code):
    """Two stand-in entry points; the worker process runs ``child_code`` (a real process)."""
    def model(): pass

    def solver(): pass

    model.__module__, solver.__module__ = "stand_in.model", "stand_in.solver"  # two modules: two groups
    calls = [(model, ()), (solver, ())]
    monkeypatch.setattr(jit, "cache_dir", lambda: tmp_path)
    monkeypatch.setattr(jit, "_all_calls", lambda: calls)
    monkeypatch.setattr(jit, "_dispatchers", lambda: [])
    monkeypatch.setattr(jit, "_COMPILED", False)
    monkeypatch.setattr(jit, "_CHILD_CODE", child_code)
    (tmp_path / jit.STAMP).write_text("an old compile's stamp\n")


def test_failed_worker_leaves_no_stamp(tmp_path, monkeypatch):
    """A worker that fails (or is interrupted) fails the compile: no stamp, nothing loaded."""
    _stand_in(monkeypatch, tmp_path, "import sys; print('numba says no', file=sys.stderr); sys.exit(3)")
    with pytest.raises(SolverError, match="numba says no"):
        jit.compile_now(quiet=True, workers=2)
    assert not (tmp_path / jit.STAMP).exists() and not jit.compiled()


def test_workers_then_stamp(tmp_path, monkeypatch):
    """Workers that succeed: the final pass runs here, then the stamp is written, whole."""
    code = "import sys; print('x.k 1.0 0.5'); print('total 0.7')"
    _stand_in(monkeypatch, tmp_path, code)
    jit.compile_now(quiet=True, workers=2)
    assert jit.stamp_current() and jit.compiled() and not list(tmp_path.glob("*.tmp"))
    assert jit.LAST_COMPILE["workers"] == 2 and jit.LAST_COMPILE["cpu"] >= 0.7
    assert [e[3] for e in jit.LAST_COMPILE["entries"]].count(1) == 1


def _signatures():
    return {f"{d.py_func.__module__}.{d.py_func.__name__}": set(map(str, d.signatures))
            for d in jit._dispatchers()}


def test_no_kernel_compiles_at_runtime(monkeypatch, tmp_path):
    """After the compile, solving the bundled robots (cases 1-3, warm and cold instants, the
    interior-point method, cones, the human arm's muscles, the neck, MyoSuite's elbow and arm: wraps,
    MuJoCo muscles and couplings; the thoracoscapular shoulder: OpenSim's paths and its closed loop)
    adds no specialisation to any kernel: the compile covered every type the library passes (the
    shoulder's loop once compiled a second ``loop_instant`` at its first solve, for the loop's
    read-only identity basis)."""
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its log where it runs
    jit.prepare(policy="wait")
    before = _signatures()
    arm = Robot.load(REPO / "robots" / "two_link_sr.yaml")
    for traj_name in ("traj1", "traj2"):
        traj = load_trajectory(arm, traj_name).subsample(6)
        for case in (1, 2, 3):
            InverseDynamics.for_case(arm, case).solve_trajectory(traj, progress=False)
    for robot_file, traj_name, cases in (("human_arm.yaml", "abduct", (2, 3)),
                                         ("caspr/8S_neck/8S_neck.yaml", "roll", (1, 3)),
                                         ("myosuite/myoelbow.yaml", "flexion", (1, 2))):
        robot = Robot.load(REPO / "robots" / robot_file)
        traj = load_trajectory(robot, traj_name).subsample(4)
        for case in cases:
            cones = {j.name: 15.0 for j in robot.joints} if case == 3 and "neck" in robot_file else None
            ident = InverseDynamics.for_case(robot, case, cones=cones)
            ident.solve_trajectory(traj, progress=False)
            ident.reset()
            ident.solve(traj.q[1], traj.qd[1], traj.qdd[1])
    # MyoSuite's arm (couplings, reserves) and the thoracoscapular shoulder (OpenSim's wraps and
    # muscles, a closed loop without couplings, RMR's problem with its unweighted reserves)
    arm = Robot.load(REPO / "robots" / "myosuite" / "myoarm.yaml")
    traj = load_trajectory(arm, "abduction").subsample(10)
    for case in (1, 3):
        InverseDynamics.for_case(arm, case).solve_trajectory(traj, progress=False)
    from mcdm_pin.osim.motion import read_table
    from mcdm_pin.osim.rmr import RATE, frame_rows, frame_states, rmr_problem, rmr_robot
    from mcdm_pin.trajectory import Trajectory

    shoulder = rmr_robot("abd01")
    files = tuple(REPO / "robots" / "opensim" / "motions" / "abd01" / f"Kinematics_{k}.sto"
                  for k in ("q", "u", "dudt"))
    t = read_table(files[0]).time
    rows = frame_rows(files)
    rows = rows[np.isin(np.round(rows / RATE, 9), np.round(t, 9))][:4]
    q, v, a = frame_states(shoulder, files, rows)
    traj = Trajectory(name="abd01", t=rows / RATE, q=q, qd=v, qdd=a)
    InverseDynamics.for_case(shoulder, 3).solve_trajectory(traj, progress=False)
    InverseDynamics(shoulder, rmr_problem(shoulder, True)).solve_trajectory(traj, progress=False)
    after = _signatures()
    grown = {k: sorted(v - before.get(k, set())) for k, v in after.items() if v - before.get(k, set())}
    assert not grown, grown
    # (an entry point may hold a second specialisation that another kernel's compile made for its own
    # call, e.g. a literal argument; what counts here is that nothing compiled at runtime)
