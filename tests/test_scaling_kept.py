"""Along a trajectory the scaled solver keeps the last optimal instant's factors where the copy they
make of the next problem is well scaled (mcdm_pin/scaling.py, ``ScaledSolver._scale``): the answers
are the instants' own to rounding, and factors that do not fit, or leave the copy badly scaled, give
way to the instant's own."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, load_trajectory
from mcdm_pin import scaling as S
from mcdm_pin.problem import Context

from .conftest import REPO

pytest.importorskip("mujoco")
ELBOW = REPO / "robots" / "myosuite" / "myoelbow.yaml"


def _kept_flags(monkeypatch):
    flags = []
    own = S.ScaledSolver._scale

    def spy(self, qp):
        out = own(self, qp)
        if out[1] is not None:
            flags.append(out[2])
        return out

    monkeypatch.setattr(S.ScaledSolver, "_scale", spy)
    return flags


def test_kept_factors_give_each_instants_answer(monkeypatch):
    robot = Robot.load(ELBOW)
    traj = load_trajectory(robot, "flexion")
    ident = InverseDynamics.for_case(robot, 1)
    flags = _kept_flags(monkeypatch)
    warm = ident.solve_trajectory(traj, progress=False)
    # (89 of the 101 instants are scaled; the first makes its own factors, the others keep them)
    assert len(flags) >= 80 and not flags[0] and sum(flags) >= len(flags) - 2
    cold = []
    for k in range(len(traj)):
        ident.reset()  # (no kept factors: each instant its own)
        cold.append(ident.solve(traj.q[k], traj.qd[k], traj.qdd[k]))
    assert [r.status for r in cold] == list(warm.status)
    f = np.array([r.f for r in cold])
    assert np.abs(warm.f - f).max() <= 1e-9 * np.abs(f).max()


def test_factors_that_do_not_fit_or_scale_badly_give_way():
    robot = Robot.load(ELBOW)
    traj = load_trajectory(robot, "flexion")
    ident = InverseDynamics.for_case(robot, 1)
    terms = ident.evaluate(traj.q[50], traj.qd[50], traj.qdd[50])
    qp = ident.problem.assemble(terms, Context(robot))
    solver = ident.solver
    own = S.scale_problem(qp, quick=False)[1]
    assert own is not None  # (the elbow's problem is scaled: the test is about which factors)
    solver.reset()
    solver._kept = own
    scaled, scaling, kept = solver._scale(qp)
    assert kept and scaling is own
    solver._kept = dataclasses.replace(own, d=own.d * 2.0**20)  # the copy's columns 1e6 too large
    assert not solver._scale(qp)[2]
    solver._kept = dataclasses.replace(own, r=own.r[:-1])  # another problem's shapes
    assert not solver._scale(qp)[2]
    solver.reset()
    assert solver._kept is None and not solver._scale(qp)[2]
