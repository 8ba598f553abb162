"""A verified answer's cone duals point along the held cone's force (mcdm_pin/solvers/_fast.py,
``answer_duals`` and ``held_direction``; mcdm_pin/solvers/active_set.py, ``active_solution``).

The active-set solver judges stationarity with the held cone's force direction at its point, but
its Newton steps on the surface stop once the force is on it to ``surface_tol``, and the surface
direction the active set carries then lags the force's own by up to ~1e-5. Duals aimed along that
lagging direction made a verified answer fail the chain's KKT check (stationarity 4.5e-6 on the
human arm's ``abduct``, case 3, once a pivot reached such a set): a verified point reported as
``inaccurate`` (docs/speed.md, "The equations' rank through a pivot")."""

from __future__ import annotations

import numpy as np
import pytest

from mcdm_pin import InverseDynamics, Robot, jit
from mcdm_pin.problem import Context
from mcdm_pin.solvers import active_set as AS
from mcdm_pin.solvers.check import numpy_kkt_residuals
from mcdm_pin.trajectory import load_trajectory

from .conftest import REPO


def _one_cone(rng, n=6, angle=20.0):
    """A held cone ``F = G x + g`` with axis ``z`` and half-angle ``angle``; ``x`` puts its force on
    the surface at a random azimuth; returns the kernels' cone arrays, ``x`` and the direction."""
    G = rng.normal(size=(1, 3, n))
    x = rng.uniform(1.0, 2.0, n)
    az = rng.uniform(0, 2 * np.pi)
    tn = np.tan(np.radians(angle))
    d = np.array([np.cos(az), np.sin(az), 0.0])
    F = 5.0 * (np.array([0.0, 0.0, 1.0]) + tn * d)
    g = (F - G[0] @ x)[None, :]
    ax = np.array([[0.0, 0.0, 1.0]])
    basis = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
    cosr = np.array([np.cos(np.radians(angle))])
    return G, g, ax, np.array([tn]), basis, cosr, x, d


@pytest.mark.parametrize("kernel_modules", [True, False], indirect=True)
def test_the_duals_follow_the_force_not_the_carried_direction(kernel_modules):
    """``answer_duals`` with a carried direction 1e-4 off the force's: the dual's part across the
    axis is ``-z0`` times the force's own direction (to rounding), its size ``mu / cos(rho)``; the
    carried direction stands only where the force's part across the axis is of rounding size."""
    fast = kernel_modules("solvers._fast")
    from mcdm_pin.solvers._structs import QP, Cones

    rng = np.random.default_rng(7)
    for _ in range(20):
        G, g, ax, tn, basis, cosr, x, d = _one_cone(rng)
        n = x.size
        qp = QP(np.eye(n), np.zeros(0), np.zeros((0, n)), np.zeros(n), 0.0, np.zeros((0, n)), np.zeros(0), np.zeros(n),
                np.full(n, 9.0), False)
        cones = Cones(G, g, ax, tn, np.array([[1.0, 0.0, 0.0]]), cosr, basis)
        off = d + np.array([-d[1], d[0], 0.0]) * 1e-4
        off /= np.linalg.norm(off)
        mus = np.array([3.0])
        z, zc, _, held = fast.answer_duals(qp, cones, x, np.zeros(n), np.zeros(n, np.int8), np.ones(1, np.bool_),
                                           mus, off[None, :])
        assert held[0] and zc[0, 0] == pytest.approx(3.0 / cosr[0], rel=1e-15)
        np.testing.assert_allclose(zc[0, 1:], -zc[0, 0] * d[:2], rtol=0, atol=1e-12 * zc[0, 0])
        assert np.abs(zc[0, 1:] + zc[0, 0] * off[:2]).max() > 1e-5 * zc[0, 0]  # (not the carried one)
        # on the axis (a part across it of rounding size): the carried direction
        g0 = (np.array([0.0, 0.0, 5.0]) - G[0] @ x)[None, :]
        cones0 = Cones(G, g0, ax, tn, np.array([[1.0, 0.0, 0.0]]), cosr, basis)
        zc0 = fast.answer_duals(qp, cones0, x, np.zeros(n), np.zeros(n, np.int8), np.ones(1, np.bool_), mus,
                                off[None, :])[1]
        np.testing.assert_allclose(zc0[0, 1:], -zc0[0, 0] * off[:2], rtol=1e-15, atol=0)


def test_verified_answers_with_a_held_cone_pass_the_chains_check():
    """The human arm's ``abduct``, case 3, every 4th instant warm, and the neck's ``roll`` with 15 deg
    cones: every answer the active-set solver verified with a cone held has, by the chain's own KKT
    measure (``numpy_kkt_residuals``), stationarity within the active-set tolerance (1e-8), so the
    chain's check, skipped for verified answers, would pass them."""
    jit.prepare(policy="wait")
    neck = "caspr/8S_neck/8S_neck.yaml"
    held = 0
    for robot_file, traj in (("human_arm.yaml", "abduct"), (neck, "roll")):
        robot = Robot.load(REPO / "robots" / robot_file)
        tr = load_trajectory(robot, traj)
        options = {} if robot_file != neck else dict(
            alpha={j: 0.125 for j in robot.joint_names}, beta={j: 0.0 for j in robot.joint_names},
            cones={j: 15.0 for j in robot.joint_names})
        idp = InverseDynamics.for_case(robot, 3, **options)
        prev = None
        for k in range(0, len(tr.t), 4):
            terms = idp.evaluate(tr.q[k], tr.qd[k], tr.qdd[k])
            qp = idp.problem.assemble(terms, Context(robot, None))
            if prev is not None:
                out = AS.try_active_set(qp, prev, 50)
                if out is not None and (out.z_cone[:, 0] > 0).any():
                    held += 1
                    r = numpy_kkt_residuals(qp, out)
                    assert r["stationarity"] <= 1e-8 and r["complementarity"] <= 1e-9, (robot_file, k, r)
            sol = idp.solver.solve(qp)
            assert sol.status == "optimal", (robot_file, k, sol.message)
            prev = sol.active
    assert held > 20, held
