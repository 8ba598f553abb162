"""One path, one answer: before ``mcdm-pin compile`` the kernels run as their own Python code
(mcdm_pin/jit.py), and every status and force equals the compiled kernels' (forces to 1e-6 of the
largest, the tolerance of tests/test_one_answer.py; the KKT check itself holds to 1e-9).

The cases: the 2-link arm's two trajectories in cases 1-3 (traj1 at t = 0.5 s: the arm at rest, the
equation of motion of rank 3 of 4; traj2 at t = 0: infeasible), its infeasible and softened 5 deg
cone, the human arm (a flat optimal face: the least-norm stage), the CASPR neck (cones held), and the
interior-point method's hard problems of tests/test_solvers.py."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, jit, load_trajectory
from mcdm_pin.solvers import get_solver

from .conftest import REPO
from .test_solvers import _weak_factor_problem


def _both(make):
    """``make()`` on the compiled kernels, then on their Python code (the compiled ones stay cached)."""
    jit.prepare(policy="wait")
    compiled = make()
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("MCDM_PIN_JIT", "off")
        mp.setattr(jit, "_COMPILED", False)
        plain = make()
    assert jit.compiled()
    return compiled, plain


def _same_x(x_plain, x_compiled, what):
    scale = max(float(np.nanmax(np.abs(x_compiled), initial=0.0)), 1e-300)
    np.testing.assert_allclose(x_plain, x_compiled, rtol=0, atol=1e-6 * scale, err_msg=str(what))


@pytest.mark.parametrize("traj_name", ["traj1", "traj2"])
@pytest.mark.parametrize("case", [1, 2, 3])
def test_trajectories_answer_alike_compiled_or_not(two_link, traj_name, case):
    traj = load_trajectory(two_link, traj_name).subsample(51)
    compiled, plain = _both(lambda: InverseDynamics.for_case(two_link, case).solve_trajectory(
        traj, progress=False))
    assert list(plain.status) == list(compiled.status)
    _same_x(plain.f, compiled.f, (traj_name, case))
    # the same chain answers; the stage may differ where rounding decides (fastmath reassociates the
    # compiled interior-point method's sums: at traj2's infeasible t = 0 it stops at its iteration
    # limit compiled, and Clarabel proves infeasibility, where uncompiled it finds the certificate)
    same = np.mean([a == b for a, b in zip(plain.stage, compiled.stage)])
    assert same >= 0.9, same


NECK = "caspr/8S_neck/8S_neck.yaml"


@pytest.mark.parametrize("robot_file, traj_name, case", [("human_arm.yaml", "abduct", 2),
                                                         ("human_arm.yaml", "abduct", 3),
                                                         (NECK, "roll", 1), (NECK, "roll", 3)])
def test_larger_robots_answer_alike(robot_file, traj_name, case):
    """The human arm (a flat optimal face: the least-norm stage) and the CASPR neck with the paper's
    weights and 15 deg cones, some held (benchmarks/_common.py)."""
    robot = Robot.load(REPO / "robots" / robot_file)
    traj = load_trajectory(robot, traj_name).subsample(11)
    options = {} if robot_file != NECK else dict(
        alpha={j: 0.125 for j in robot.joint_names}, beta={j: 0.0 for j in robot.joint_names},
        cones={j: 15.0 for j in robot.joint_names})
    compiled, plain = _both(lambda: InverseDynamics.for_case(robot, case, **options).solve_trajectory(
        traj, progress=False))
    assert list(plain.status) == list(compiled.status)
    _same_x(plain.f, compiled.f, (robot_file, case))


def test_infeasible_and_softened_cone_alike(two_link):
    traj = load_trajectory(two_link, "traj1")
    k = 10  # a 5 deg cone cannot be met at t = 0.1 s (tests/test_solvers.py)

    def make():
        state = (traj.q[k], traj.qd[k], traj.qdd[k])
        return [InverseDynamics.for_case(two_link, 3, cones={"shoulder": 5.0}, soften=soft).solve(*state)
                for soft in (False, True)]

    compiled, plain = _both(make)
    assert [r.status for r in plain] == [r.status for r in compiled] == ["infeasible", "softened"]
    assert plain[0].message == compiled[0].message
    assert plain[1].softened_deg == pytest.approx(compiled[1].softened_deg, rel=1e-6)
    _same_x(plain[1].f, compiled[1].f, "softened")


@pytest.mark.parametrize("cone", [False, True])
def test_interior_point_hard_problems_alike(cone):
    """tests/test_solvers.py's nearly rank-deficient objective factors, on the compiled chain."""
    def make():
        return [get_solver("compiled").solve(_weak_factor_problem(seed, cone)) for seed in range(4)]

    compiled, plain = _both(make)
    for seed, (a, b) in enumerate(zip(compiled, plain)):
        assert a.status == b.status == "optimal", (seed, b.message)
        _same_x(b.x, a.x, seed)


def test_uncompiled_kernels_call_no_dispatcher(monkeypatch):
    """Every uncompiled kernel's globals name uncompiled kernels only (so running them compiles
    nothing), and the kernels answer uncompiled under ``MCDM_PIN_JIT=off`` even when compiled ones are
    cached."""
    jit.prepare(policy="wait")
    monkeypatch.setattr(jit, "_COMPILED", False)
    assert not jit.prepare(policy="off") and not jit.compiled()
    import importlib

    for module in ("model.kernels", "solvers._fast", "solvers._kkt", "solvers._kkt_eq", "solvers._kkt_verify",
                   "solvers._kkt_linalg", "solvers._ipm", "solvers._ipm_direction", "solvers._ipm_newton",
                   "solvers._ipm_structure", "solvers._ipm_linalg", "solvers._unique"):
        real = importlib.import_module(f"mcdm_pin.{module}")
        plain = jit.kernels(module)
        names = [k for k, v in vars(real).items()
                 if jit._is_kernel(v) and v.py_func.__module__ == real.__name__]
        assert names, module
        for name in names:
            f = getattr(plain, name)
            assert not jit._is_kernel(f), (module, name)
            g = f.__wrapped__.__globals__
            assert g is not vars(real) and not [k for k, v in g.items() if jit._is_kernel(v)], (module, name)
