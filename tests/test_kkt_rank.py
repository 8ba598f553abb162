"""The large chains' warm starts (mcdm_pin/solvers/_kkt_rank.py, mcdm_pin/solvers/_kkt.py): a pivot
that fixes cables whose columns the equations need frees, for each direction lost, a fixed cable
that pulls along it; the Newton steps on a held cone's surface do not stop short of it; the held
cones' surfaces count among the rows whose rank is kept. Without them the 96-DoF
chain's warm starts failed at 53 of 100 instants in case 2, each after losing the rank, and at 76 in
case 3 (docs/speed.md, "The equations' rank through a pivot")."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from .conftest import REPO


def _rank(A, free):
    sv = np.linalg.svd(A[:, free], compute_uv=False)
    return int((sv > 1e-10 * sv[0]).sum()) if len(sv) else 0


A = np.array([[1.0, 2.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0],
              [0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
              [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0],
              [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0]])
B = np.array([3.0, 1.0, 1.0, 1.0])
LB, UB = np.zeros(8), np.full(8, 10.0)
GRAD = np.array([0.0, 0.0, 0.0, 0.0, 2.0, 1.0, 0.5, 0.5])  # (the fixed cables' multipliers)
BEFORE = np.array([0, 0, 0, 0, 1, 1, 0, 0], dtype=np.int8)  # 0 free, 1 at the lower bound


def _problem(G=None, gc=None, tan=0.5):
    """The kernels' QP of ``A f = B`` within ``[LB, UB]`` and its cones: none, or one of axis z and
    half-angle ``atan(tan)`` whose force is ``G f + gc``."""
    from mcdm_pin.solvers._structs import QP, Cones

    n = A.shape[1]
    qp = QP(np.zeros((n, n)), np.zeros(0), np.zeros((0, n)), np.zeros(n), 0.0, A, B, LB, UB, False)
    if G is None:
        return qp, Cones(np.zeros((0, 3, n)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3)),
                         np.zeros(0), np.zeros((0, 2, 3)))
    c = 1.0 / np.sqrt(1.0 + tan * tan)
    return qp, Cones(G[None], gc[None], np.array([[0.0, 0.0, 1.0]]), np.array([tan]), np.array([[1.0, 0.0, 0.0]]),
                     np.array([c]), np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]))


def test_a_pivot_that_loses_the_rank_frees_a_cable_along_the_lost_direction(kernel_modules):
    """Four equations, eight cables: cables 0 and 1 alone reach row 0, and a pivot fixes both. The
    guard frees a fixed cable that reaches row 0 (4 or 5; 5 binds less for its pull), whose move
    off its bound closes the row's residual; the cables the pivot fixed stay fixed, and the free
    columns span the equations again. A pivot that keeps the rank, or fixes nothing, is left alone."""
    restore_rank = kernel_modules("solvers._kkt_rank").restore_rank
    qp, cones = _problem()
    none, dirs = np.zeros(0, dtype=np.bool_), np.zeros((0, 3))
    state = BEFORE.copy()
    state[[0, 1]] = 1
    assert _rank(A, state == 0) == 3
    assert restore_rank(qp, cones, BEFORE, state, GRAD, none, none, dirs) == 1
    assert state[0] == state[1] == 1 and state[5] == 0 and state[4] == 1
    assert _rank(A, state == 0) == 4
    kept = BEFORE.copy()
    kept[2] = 1  # (rows 1-3 still reached by the others)
    assert _rank(A, kept == 0) == 4 and restore_rank(qp, cones, BEFORE, kept, GRAD, none, none, dirs) == 0
    assert restore_rank(qp, cones, BEFORE, BEFORE.copy(), GRAD, none, none, dirs) == 0


def test_a_cone_taken_whose_surface_the_free_cables_cannot_reach_frees_a_cable(kernel_modules):
    """The same equations and a cone whose surface along ``x`` (``w = (1, 0, -tan)``) gives the row
    ``A[1] + e_5``: over the free cables (all but 4 and 5) it repeats equation 1. A pivot that takes
    the cone and fixes nothing frees cable 5, the only fixed one that pulls along the lost direction,
    and the equations with the surface's row span the free columns again; the cone held before the
    pivot, or a surface row the free cables reach, leaves the set alone."""
    restore_rank = kernel_modules("solvers._kkt_rank").restore_rank
    row = A[1].copy()
    row[5] += 1.0
    G = np.zeros((3, 8))
    G[0] = row  # (w^T G = row: only the force's x component moves)
    gc = np.array([-(B[1] + 1.0), 0.0, 0.0])  # (the surface's right-hand side B[1] + 1: cable 5 moves up)
    qp, cones = _problem(G, gc)
    dirs = np.array([[1.0, 0.0, 0.0]])
    off, on = np.zeros(1, dtype=np.bool_), np.ones(1, dtype=np.bool_)
    rows = np.vstack([A, row])
    state = BEFORE.copy()
    assert _rank(rows, state == 0) == 4
    assert restore_rank(qp, cones, BEFORE, state, GRAD, off, on, dirs) == 1
    assert state[5] == 0 and state[4] == 1 and _rank(rows, state == 0) == 5
    assert restore_rank(qp, cones, BEFORE, BEFORE.copy(), GRAD, on, on, dirs) == 0  # (held before: no change)
    G2 = G.copy()
    G2[0, 7] += 1.0  # (a free cable reaches the surface: the rank is kept)
    qp2, cones2 = _problem(G2, gc)
    assert _rank(np.vstack([A, G2[0]]), BEFORE == 0) == 5
    assert restore_rank(qp2, cones2, BEFORE, BEFORE.copy(), GRAD, off, on, dirs) == 0


@pytest.fixture(scope="module")
def chain96(tmp_path_factory):
    sys.path.insert(0, str(REPO / "benchmarks"))
    from scaling import build

    return build(tmp_path_factory.mktemp("chain96"), 32, 288, 101)


def test_the_96_dof_chains_warm_starts_keep_the_rank(chain96):
    """The 96-DoF, 288-cable chain of ``benchmarks/scaling.py`` along its 101-instant sweep, case 2:
    the warm start answers at least 97 instants (99; 47 before the guard, 93 while a failure near
    its answer halved the next pivot limit), every answer optimal, and the warm answers equal
    Clarabel's optimum (objective to 1e-6) at a few of them."""
    _check_sweep(*chain96, 2, at_least=97)


def _check_sweep(robot, traj, case, at_least):
    """``case`` along ``traj``: every answer optimal, at least ``at_least`` instants answered warm,
    and the warm answers' objective equal to Clarabel's (1e-6) at four of them."""
    from mcdm_pin import InverseDynamics

    res = InverseDynamics.for_case(robot, case).solve_trajectory(traj, progress=False)
    assert (res.status == "optimal").all()
    warm = np.flatnonzero(res.stage == "warm_active_set")
    assert len(warm) >= at_least, len(warm)
    ref = InverseDynamics.for_case(robot, case, solver="clarabel")
    for k in warm[:: max(1, len(warm) // 4)]:
        r = ref.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        assert r.status == "optimal"
        assert res.objective[k] == pytest.approx(r.objective, rel=1e-6, abs=1e-8)


def test_the_96_dof_chains_warm_starts_with_cones_reach_their_surfaces(chain96):
    """The same sweep in case 3 (15 deg cones on every joint): no warm start ends because its Newton
    steps stopped short of a held cone's surface with nothing left to exchange (23 of 48 failures
    before the steps' prediction waited for the surfaces), at least 90 instants answer warm (99
    with the held cones' surfaces among the guard's rows, 75 without, 52 before the surfaces' steps,
    25 before the guard), every answer optimal, and the warm answers equal Clarabel's optimum
    (objective to 1e-6) at a few of them."""
    from mcdm_pin.solvers import active_set as AS

    AS.MISSES.clear()
    _check_sweep(*chain96, 3, at_least=90)
    assert "a held cone's force off its surface" not in AS.MISSES, dict(AS.MISSES)
