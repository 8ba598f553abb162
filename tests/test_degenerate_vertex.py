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
from mcdm_pin.settings import DEFAULT, Settings

REPO = Path(__file__).resolve().parents[1]
DEGENERATE = (8, 20, 22, 28, 31, 34, 37)  # instants whose optimum has dependent free columns


def test_the_necks_degenerate_optima_are_answered_warm_and_exactly():
    """Along ``pitch``, the warm stage answers the degenerate instants, at Clarabel's optimum, when its
    first guess may use the whole pivot limit (every instant but the first on an Intel Xeon). With the
    default split of that limit (``warm_dual_after`` pivots, then the dual guess), which instants the
    first guess reaches in time depends on rounding: instant 37 needs 7-10 pivots with an Intel
    Xeon's OpenBLAS kernels and at most 6 with an AMD EPYC's, so there they only count. (A guess that
    verifies within fewer pivots verifies the same with more: the pivots are the same up to the
    limit, and the dual guess still follows a failure.)"""
    robot = Robot.load(REPO / "robots/caspr/8S_neck/8S_neck.yaml")
    traj = load_trajectory(robot, "pitch")
    whole = Settings(warm_dual_after=DEFAULT.warm_max_pivots)
    res = InverseDynamics.for_case(robot, 1, settings=whole).solve_trajectory(traj, progress=False)
    assert (res.status == "optimal").all()
    warm = res.stage == "warm_active_set"
    assert warm[list(DEGENERATE)].all() and warm.sum() >= 97
    # the default split: (82 warm before the Schur complement solved dependent free columns, 91 before
    # it solved a vertex's dependent rows: tests/test_vertex_dependent_rows.py; 97 on the Intel Xeon)
    default = InverseDynamics.for_case(robot, 1).solve_trajectory(traj, progress=False)
    assert (default.status == "optimal").all()
    assert (default.stage == "warm_active_set").sum() >= 96
    ref = InverseDynamics.for_case(robot, 1, solver="clarabel")
    scale = np.abs(res.f).max()
    for k in DEGENERATE:
        r = ref.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert r.status == "optimal"
        assert np.abs(res.f[k] - r.f).max() <= 1e-12 * scale
        assert np.abs(default.f[k] - r.f).max() <= 1e-12 * scale
