"""An active set whose free cables are fewer than the equations and whose columns are themselves
dependent (two cables along one line): the neck's ``pitch``, case 1, has such optima, where the free
cables' columns span 18 of the 24 equations. The equations alone do not determine those cables
(mcdm_pin/solvers/_kkt_linalg.py, ``determined_solve``, finds them dependent); with a diagonal free
block the rows' Schur complement solves the KKT system, a dependent row's multiplier zero
(``schur_solve``, reached from ``_kkt_eq._solve_rows``). The warm stage then answers those instants
with the exact KKT point, the one Clarabel's answer polishes to."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mcdm_pin import InverseDynamics, Robot, load_trajectory

REPO = Path(__file__).resolve().parents[1]


def test_the_necks_degenerate_optima_are_answered_warm_and_exactly():
    robot = Robot.load(REPO / "robots/caspr/8S_neck/8S_neck.yaml")
    traj = load_trajectory(robot, "pitch")
    res = InverseDynamics.for_case(robot, 1).solve_trajectory(traj, progress=False)
    assert (res.status == "optimal").all()
    warm = res.stage == "warm_active_set"
    # (82 before the Schur complement solved dependent free columns, 91 before it solved a vertex's
    # dependent rows: tests/test_vertex_dependent_rows.py)
    assert warm.sum() >= 97
    ref = InverseDynamics.for_case(robot, 1, solver="clarabel")
    scale = np.abs(res.f).max()
    for k in (8, 20, 22, 28, 31, 34, 37):  # degenerate optima the warm stage now answers
        assert warm[k]
        r = ref.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert r.status == "optimal"
        assert np.abs(res.f[k] - r.f).max() <= 1e-12 * scale
