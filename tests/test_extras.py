"""The core without its extras, and ProxQP warm-started through ``update``.

A child interpreter blocks every optional package (numba, Dask, Zarr, xarray, pandas, Meshcat, its
packing, Pillow, matplotlib, MuJoCo, OpenSim) by ``sys.modules`` poisoning, then loads a robot and
solves case 1 on ProxQP, on Clarabel and on the default chain (the uncompiled kernels): the answers
agree with each other, and asking for what an extra brings raises ``MissingPackageError`` naming it.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, load_trajectory
from mcdm_pin.solvers import ProxQPSolver, make_solver

REPO = Path(__file__).resolve().parents[1]
BLOCKED = ("numba", "dask", "distributed", "zarr", "xarray", "pandas", "meshcat", "umsgpack", "PIL",
           "matplotlib", "mujoco", "opensim", "example_robot_data")

CHILD = r"""
import json, sys
for name in BLOCKED:
    sys.modules[name] = None  # "import name" raises ImportError
from mcdm_pin import InverseDynamics, Robot, jit, load_trajectory
from mcdm_pin.exceptions import MissingPackageError
from mcdm_pin.extras import optional
robot = Robot.load(ROBOT)
traj = load_trajectory(robot, "traj1")
out = {"loaded": sorted(m for m in sys.modules if m.split(".")[0] in BLOCKED and sys.modules[m] is not None)}
for solver in ("proxqp", "clarabel", "default"):
    res = InverseDynamics.for_case(robot, 1, solver=solver).solve(traj.q[5], traj.qd[5], traj.qdd[5])
    out[solver] = [res.status, res.stage, list(res.f)]
errors = {}
for what, call in [("compile", jit.compile_now),
                   ("viewer", lambda: optional("meshcat", "the viewer")),
                   ("plots", lambda: optional("matplotlib.figure", "the figures")),
                   ("batch", lambda: InverseDynamics.for_case(robot, 1).solve_trajectory(traj, workers=2))]:
    try:
        call()
        errors[what] = None
    except MissingPackageError as exc:
        errors[what] = str(exc)
out["errors"] = errors
print(json.dumps(out))
"""


def test_core_loads_and_solves_without_any_extra(tmp_path):
    code = f"BLOCKED = {BLOCKED!r}\nROBOT = {str(REPO / 'robots' / 'two_link_sr.yaml')!r}\n" + CHILD
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]),
               MCDM_PIN_JIT="auto")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["loaded"] == []
    forces = {}
    for solver in ("proxqp", "clarabel", "default"):
        status, stage, f = out[solver]
        assert status == "optimal", (solver, stage)
        forces[solver] = np.array(f)
    # case 1 is strictly convex: one optimum, whichever back-end finds it
    assert np.allclose(forces["proxqp"], forces["clarabel"], atol=1e-6)
    assert np.allclose(forces["default"], forces["clarabel"], atol=1e-6)
    for what, extra in (("compile", "numba"), ("viewer", "viewer"), ("plots", "plots"), ("batch", "workspace")):
        assert out["errors"][what] is not None and f"pip install 'mcdm-pin[{extra}]'" in out["errors"][what], what


@pytest.mark.parametrize("case", [1, 3])
def test_proxqp_warm_started_through_update_answers_as_a_new_workspace(two_link, case):
    traj = load_trajectory(two_link, "traj2")
    runs = {}
    for reuse in (False, True):
        ident = InverseDynamics.for_case(two_link, case, solver=ProxQPSolver(active_set=False, fallback=False,
                                                                             reuse=reuse))
        runs[reuse] = (ident.solve_trajectory(traj, progress=False), ident.solver.inner.stage("proxqp").runner)
    (fresh, r0), (kept, r1) = runs[False], runs[True]
    assert np.array_equal(fresh.status, kept.status) and fresh.found.sum() >= len(traj) - 1
    ok = fresh.found
    assert np.allclose(kept.f[ok], fresh.f[ok], atol=1e-8)
    assert np.allclose(kept.objective[ok], fresh.objective[ok], rtol=1e-10)
    assert r0.created >= ok.sum()  # a new workspace per solve
    if case == 1:  # one shape all along (no cuts): every instant after the first goes through update
        assert r1.created <= 2
    else:
        assert r1.created < r0.created


def test_proxqp_is_a_first_class_back_end():
    chain = make_solver("proxqp")
    # (flat_objective first: a constant objective's least-norm problem, through the same stages)
    assert [s.name for s in chain.stages][:3] == ["flat_objective", "proxqp", "sqp_polish"]
    assert chain.stage("proxqp").runner.reuse  # --solver proxqp warm-starts through update
