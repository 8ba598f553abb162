r"""Compiled primal-dual interior-point method for the instant's cone program, specialised to its
structure (the kernels of :mod:`.ipm`).

.. math::

    \min\ \tfrac12 x^T P x + c^T x \ \text{ s.t. }\ A x = b,\ \ x_i + s^u_i = u_i,\ -x_i + s^l_i = -l_i,
    \ \ -T_k x + s^c_k = t_k,\ \ s^u, s^l \ge 0,\ s^c_k \in \mathcal Q^3,

with ``P = diag(d) + F^T F`` (``F`` of few rows: the interaction objective's weighted wrench rows).
Mehrotra's predictor-corrector with Nesterov-Todd scaling (Vandenberghe, "The CVXOPT linear and
quadratic cone program solvers", 2010, sections 3-4; the same steps as CVXOPT's ``coneqp``).

**The Newton system** is solved through the problem's structure (:mod:`._ipm_newton`, on rows made
once per solve by :mod:`._ipm_structure`; the direction and step: :mod:`._ipm_direction`): with the
bounds' multipliers eliminated and the cones' kept, one symmetric positive definite system of size
``rank(F) + 3K + k_eq`` (the neck: 24 in case 1, 48 in case 2, 72 in case 3, or 48 with each cone
folded into its joint's force rows) instead of a Cholesky
factor of the ``n x n`` Hessian and a Schur complement on ``A``; the cones enter through ``W_k^2``,
never through ``W_k^{-2}`` (whose entries grow like ``1/mu`` on an active cone: the dense form's
breakdowns, "the step vanished", on 2 % of the neck's case-3 instants). A pivot is dropped as a
dependent equation only in the equations' rows, and only at rounding level of its own row
(:func:`._ipm_linalg.chol_inplace`).

**The start** is CVXOPT's: ``x`` from the Newton system with the identity scaling (the least-squares
point of the slacks, with the objective: the middle of the box), ``s = h - G x``, ``z = -s``, each
shifted into its cone. The steps from there are long from the first iteration on (on the neck 11
iterations to the crossover in all three cases); a start at the least-squares forces on the
equations (~1 N, where the optimum reaches 20 N) took 25-45 short steps in cases 2 and 3. Without
cones the bounds weigh ``box_weight`` (:attr:`~mcdm_pin.settings.Settings.ipm_start_box_weight`, 0.2) instead of one in that least-squares problem
(the start nearer the objective's own optimum; ``s = -z / 0.2``): iterations to the crossover, mean
over 14 instants (neck: ``roll`` with the paper's weights; 2-link arm: ``traj1``; human arm:
``abduct``), weight 1 -> 0.2: neck case 1 10.9 -> 9.3, case 2 10.6 -> 9.8; 2-link 8.6 -> 7.5 and
5.8 -> 4.9; human arm 6.4 -> 5.1 and 7.0 -> 6.0. With cones the weight stays one: on the neck's
case 3 (eight 15 deg cones) the nearer start lies outside the cones, and the shift into them moves
every slack: 11.2 -> 11.9 iterations (other cone weights, or each cone shifted on its own, did no
better).

**Centrality correctors** (Gondzio): after Mehrotra's corrector, while the step is below 0.9, at most
``ncorr`` corrections of the bounds' complementarity targets towards ``[0.1, 10] sigma mu`` at a
longer trial step, each kept only when it lengthens the step.

**Crossover.** Once the relative duality gap is below ``crossover_gap``, the active set read off the
iterate (bounds whose slack is below their multiplier, cones whose slack is nearer the cone's
boundary than its multiplier is to zero: Tapia's indicators) is handed to the compiled active-set
solver (:func:`._kkt.active_set_run`), whose point is accepted only if it passes the full KKT check.
That turns an interior point accurate to ~1e-6 into the exact optimum (to rounding) a few
iterations early. After the first attempt, an active set is tried only once it reads the same at two
successive iterations (or when the iterations have converged): each attempt solves the active set's
whole KKT system, whose cost grows with the cube of the problem's size, and while the indicators
still change from one iteration to the next the attempt fails (at 96 DoF and 288 cables, one attempt
per iteration from a gap of 1e-3 took 4-6 times as long as the iterations themselves: docs/speed.md,
"The first stage of a cold instant").

**Infeasibility.** A primal infeasibility certificate (``y``, ``z`` in the dual cone with
``A^T y + G^T z = 0`` and ``b^T y + h^T z < 0``, relative residual below ``eps``) ends the run with
``INFEASIBLE``; the iterates of an infeasible-start method tend to one when the problem is infeasible.
Otherwise the run ends at the iteration limit and the caller falls back to another stage.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from . import _ipm_linalg as la
from . import _ipm_newton as newton
from ._ipm_direction import barrier, cone_scalings, direction, newton_step
from ._ipm_structure import structure
from . import _kkt
from ._structs import ActiveSetRun, IPMRun, NewtonSystem, Scaling, Slacks

# return codes
SOLVED, CROSSOVER, INFEASIBLE_CERT, MAX_ITER, NUMERICAL = 0, 1, 2, 3, 4

_dot = la.dot


@njit(cache=True, nogil=True, error_model="numpy")
def _shift_into_cones(su, sl, sc):
    """Shift a point into the interior (CVXOPT's initial point): if its smallest eigenvalue ``m``
    is not positive, add ``(1 - m) e``."""
    m = 1e300
    nrm = 0.0
    for i in range(su.shape[0]):
        m = min(m, su[i])
        nrm += su[i] * su[i]
    for i in range(sl.shape[0]):
        m = min(m, sl[i])
        nrm += sl[i] * sl[i]
    for k in range(sc.shape[0]):
        m = min(m, sc[k, 0] - np.sqrt(sc[k, 1] ** 2 + sc[k, 2] ** 2))
        nrm += sc[k, 0] ** 2 + sc[k, 1] ** 2 + sc[k, 2] ** 2
    if m == 1e300:
        return
    if m <= 1e-8 * max(np.sqrt(nrm), 1.0):
        shift = 1.0 - m
        su += shift
        sl += shift
        for k in range(sc.shape[0]):
            sc[k, 0] += shift


@njit(cache=True, nogil=True, error_model="numpy")
def _residuals(qp, T, t, x, y, slacks, iu, il, res):
    """At ``(x, y, slacks)`` of ``qp`` (cone rows ``T``, ``t``): the dual residual
    ``rx = P x + c + A^T y + G^T z``, the equations' ``ry = A x - b``, the slacks' ``rz = G x + s - h``
    (in place in ``res = (Px, rx, ry, rzu, rzl, rzc, fx)``; ``Px`` (n,), ``fx`` (r,) work); returns
    the objective."""
    d0, Fm, c, A, b, lb, ub = qp.d0, qp.F, qp.c, qp.A, qp.b, qp.lb, qp.ub
    su, zu, sl, zl, sc, zc = slacks
    Px, rx, ry, rzu, rzl, rzc, fx = res
    K = T.shape[0]
    n = x.shape[0]
    T2 = T.reshape((3 * K, n))
    newton.apply_P(x, d0, Fm, Px, fx)
    for i in range(n):
        rx[i] = Px[i] + c[i]
    la.rows_axpy(A, np.int64(0), A.shape[0], y, np.int64(0), 1.0, rx)
    for q in range(iu.shape[0]):
        rx[iu[q]] += zu[q]
    for q in range(il.shape[0]):
        rx[il[q]] -= zl[q]
    la.rows_axpy(T2, np.int64(0), 3 * K, zc.reshape(3 * K), np.int64(0), -1.0, rx)
    rz2 = rzc.reshape(3 * K)
    la.rows_dot(T2, np.int64(0), 3 * K, x, rz2, np.int64(0))
    for k in range(K):
        for e in range(3):
            rzc[k, e] = -rzc[k, e] + sc[k, e] - t[k, e]
    la.rows_dot(A, np.int64(0), A.shape[0], x, ry, np.int64(0))
    for a in range(A.shape[0]):
        ry[a] -= b[a]
    for q in range(iu.shape[0]):
        rzu[q] = x[iu[q]] + su[q] - ub[iu[q]]
    for q in range(il.shape[0]):
        rzl[q] = -x[il[q]] + sl[q] + lb[il[q]]
    return 0.5 * _dot(Px, x) + _dot(c, x)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _start(qp, T, t, iu, il, system, M0inv, floor, fw, ws, box_weight, drop_rel):
    """CVXOPT's initial point: ``x, y`` of the Newton system with the identity scaling (the least
    squares point of the slacks on the equations, with the objective; without cones the bounds
    weigh ``box_weight``, module docstring), ``s = h - G x``, ``z = -s`` (``-w s``),
    each shifted into its cone's interior when it is not (:func:`_shift_into_cones`). Starting from
    the middle of the box costs nothing in iterations: every step is long (on the neck 11-13
    iterations to the crossover, where a start at the least-squares forces took 25-45 short ones).
    ``system``: the Newton system (:class:`._structs.NewtonSystem`, with ``M0inv`` the inverse its
    factor needs); ``fw``, ``ws``: the factor's and the solves' work arrays (:func:`ipm_solve`);
    ``drop_rel``: the factor's pivot drop (``ipm_pivot_drop``)."""
    d0, c, b, lb, ub = qp.d0, qp.c, qp.b, qp.lb, qp.ub
    rf, Ct, cg, fold = system.rf, system.Ct, system.cg, system.fold
    n, nu, nl, K = c.shape[0], iu.shape[0], il.shape[0], T.shape[0]
    wb = box_weight if K == 0 else 1.0  # the bounds' weight (module docstring)
    one_u, one_l = np.ones(nu), np.ones(nl)
    Vc = np.zeros((K, 3, 3))
    for k in range(K):
        for e in range(3):
            Vc[k, e, e] = 1.0
    dbar, dinv = np.empty(n), np.empty(n)
    ru, rl = np.empty(nu), np.empty(nl)
    barrier(d0, iu, il, one_u, wb * one_u, one_l, wb * one_l, floor, dbar, dinv, ru, rl)
    Kb, Km, KFF, G1, gw = fw
    dropped = newton.factor(system.gram, rf, M0inv, Ct, cg, fold, Vc, dinv, drop_rel, gw, Kb, Km, KFF, G1)
    # refined only when the factor is not that of the exact system: a dropped equation, or a variable
    # whose D fell below the floor (without bounds or weight)
    refine = 1 if dropped else 0
    for i in range(n):
        if not dbar[i] >= floor:
            refine = 1
    hu = np.empty(nu)
    for q in range(nu):
        hu[q] = ub[iu[q]]
    hl = np.empty(nl)
    for q in range(nl):
        hl[q] = -lb[il[q]]
    x, y, zu, zl, zc = np.empty(n), np.empty(b.shape[0]), np.empty(nu), np.empty(nl), np.empty((K, 3))
    # the identity scaling (``W = W^-1 = W^2 = I``; lambda unused by a Newton step)
    newton_step((-c, b, hu, hl, t.copy()), system, Scaling(dinv, dbar, ru, rl, Vc, Vc, Vc, np.zeros((K, 3))), iu, il,
                refine, ws, (x, y, zu, zl, zc))
    su, sl, sc = -zu / wb, -zl / wb, -zc
    _shift_into_cones(su, sl, sc)
    _shift_into_cones(zu, zl, zc)
    return x, y, su, zu, sl, zl, sc, zc


@njit(cache=True, nogil=True, error_model="numpy")
def _gap(su, zu, sl, zl, sc, zc):
    g = _dot(su, zu) + _dot(sl, zl)
    for k in range(sc.shape[0]):
        g += sc[k, 0] * zc[k, 0] + sc[k, 1] * zc[k, 1] + sc[k, 2] * zc[k, 2]
    return g


@njit(cache=True, nogil=True, error_model="numpy")
def _certificate(qp, T, t, y, slacks, iu, il, eps, scales, certificate_rel):
    """Whether ``(y, z)`` (``z`` of ``slacks``) certifies that ``qp`` with the cone rows ``T``, ``t``
    is primal infeasible: ``A^T y + G^T z = 0`` (to ``eps``), ``b^T y + h^T z < 0`` by more than
    ``certificate_rel`` of the multipliers' size (``scales``: :func:`_scales`)."""
    A, b, lb, ub = qp.A, qp.b, qp.lb, qp.ub
    zu, zl, zc = slacks.zu, slacks.zl, slacks.zc
    bscale, hscale = scales[0], scales[1]
    hz = _dot(b, y)
    for q in range(iu.shape[0]):
        hz += ub[iu[q]] * zu[q]
    for q in range(il.shape[0]):
        hz -= lb[il[q]] * zl[q]
    for k in range(T.shape[0]):
        hz += t[k, 0] * zc[k, 0] + t[k, 1] * zc[k, 1] + t[k, 2] * zc[k, 2]
    if not hz < 0.0:
        return False
    g = A.T @ y
    for q in range(iu.shape[0]):
        g[iu[q]] += zu[q]
    for q in range(il.shape[0]):
        g[il[q]] -= zl[q]
    for k in range(T.shape[0]):
        for e in range(3):
            la.axpy(-zc[k, e], T[k, e], g)
    ysz = la.inf_norm(y) * bscale
    for q in range(iu.shape[0]):
        ysz = max(ysz, abs(zu[q]) * hscale)
    for q in range(il.shape[0]):
        ysz = max(ysz, abs(zl[q]) * hscale)
    return la.inf_norm(g) * hscale <= eps * -hz and -hz > certificate_rel * ysz


@njit(cache=True, nogil=True, error_model="numpy")
def _bounded(lb, ub):
    """The indices of the finite upper and lower bounds."""
    n = lb.shape[0]
    nu, nl = 0, 0
    for i in range(n):
        if np.isfinite(ub[i]):
            nu += 1
        if np.isfinite(lb[i]):
            nl += 1
    iu = np.empty(nu, dtype=np.int64)
    il = np.empty(nl, dtype=np.int64)
    a_, b_ = 0, 0
    for i in range(n):
        if np.isfinite(ub[i]):
            iu[a_] = i
            a_ += 1
        if np.isfinite(lb[i]):
            il[b_] = i
            b_ += 1
    return iu, il


@njit(cache=True, nogil=True, error_model="numpy")
def _scales(b, lb, ub, t, c, iu, il):
    bscale = max(1.0, la.inf_norm(b))
    hscale = 1.0
    for q in range(iu.shape[0]):
        hscale = max(hscale, abs(ub[iu[q]]))
    for q in range(il.shape[0]):
        hscale = max(hscale, abs(lb[il[q]]))
    for k in range(t.shape[0]):
        for e in range(3):
            hscale = max(hscale, abs(t[k, e]))
    return bscale, hscale, max(1.0, la.inf_norm(c))


@njit(cache=True, nogil=True, error_model="numpy")
def _primal_res(ry, rzu, rzl, rzc, bscale, hscale):
    pres = la.inf_norm(ry) / bscale
    pres = max(pres, la.inf_norm(rzu) / hscale)
    pres = max(pres, la.inf_norm(rzl) / hscale)
    for k in range(rzc.shape[0]):
        for e in range(3):
            pres = max(pres, abs(rzc[k, e]) / hscale)
    return pres


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _crossover(x, slacks, iu, il, qp, cones, limits, memo, anyway):
    """The active set the iterate points at, verified by the compiled active-set solver when it
    differs from the last one tried and either reads the same as at the last reading or ``anyway``
    (the first attempt, or converged iterations): ``(tried, run)``, ``run`` the solver's
    :class:`._structs.ActiveSetRun` (code -1 when not tried). ``memo`` (:func:`_guess_memo`) holds
    the last guess tried and the last one read, both updated here."""
    last_state, last_cact, seen_state, seen_cact = memo
    state, cact, cdir = _read_active_set(x, slacks, iu, il, cones)
    stable = not _new_guess(state, cact, seen_state, seen_cact)
    if not (stable or anyway) or not _new_guess(state, cact, last_state, last_cact):
        return 0, ActiveSetRun(-1, x, np.zeros(0), np.zeros(0), state, cact, np.zeros((0, 3)), state, np.zeros(0),
                               0, 0)
    # the Newton steps on the held cones start from the iterate and its cone duals' multipliers
    # (``z_cone[k, 0] = mu_k / cos(rho_k)``, :func:`mcdm_pin.solvers._fast.answer_duals`' convention)
    return 1, _kkt.active_set_run(qp, cones, state, cact, cdir, limits, x, slacks.zc[:, 0] * cones.cosr)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def ipm_solve(qp, T, t, cones, limits):
    """The interior-point method with crossover (module docstring).

    Args:
        qp: a :class:`._structs.QP`: ``H`` (n, n) is ``P`` (symmetric positive semidefinite; the
            crossover's active-set solver uses it), ``d0`` (n,), ``F`` (r, n) the same
            ``P = diag(d0) + F^T F`` (the Newton systems use it); the linear term ``c``, the
            equalities ``A x = b``, the bounds ``lb``, ``ub`` (may be infinite).
        T (K, 3, n), t (K, 3): cone rows ``s = T x + t`` in the second-order cone.
        cones: the same cones in the active-set solver's form (:class:`._structs.Cones`) for the
            crossover.
        limits: a :class:`._structs.Limits`: ``max_iter``, ``eps`` (iteration limit; relative
            residual and gap tolerance), ``crossover_gap`` (try the active set once the relative gap
            is below this; 0: never), ``max_pivots``, ``max_newton`` and the active-set tolerances
            (each crossover's), ``ncorr`` (correctors per iteration), ``rank_tol`` (relative residual
            below which a row of ``[F; T]`` counts as dependent), ``box_weight`` (the bounds' weight
            in the start without cones: module docstring, "The start"), and ``crossover_attempts``,
            ``pivot_drop``, ``refine_gap``, ``step_fraction``, ``min_step``, ``certificate_rel`` (each
            the :class:`~mcdm_pin.settings.Settings` field ``ipm_*`` of that name says).

    Returns an :class:`._structs.IPMRun` ``(code, x, y, z, z_cone, iterations, state, cact, mus, dirs)``:
    ``code`` one of SOLVED,
    CROSSOVER, INFEASIBLE_CERT (then ``y, zbox, zc`` are the certificate), MAX_ITER, NUMERICAL;
    ``z`` (n,) the bounds' multipliers (> 0 at an upper bound), ``z_cone`` (K, 3) the cones' duals;
    after a crossover ``state, cact, mus, dirs`` the verified active set (else empty).
    """
    d0, Fm, c, A, b, lb, ub = qp.d0, qp.F, qp.c, qp.A, qp.b, qp.lb, qp.ub
    max_iter, eps, crossover_gap = limits.max_iter, limits.eps, limits.crossover_gap
    n, K = c.shape[0], T.shape[0]
    iu, il = _bounded(lb, ub)
    deg = iu.shape[0] + il.shape[0] + K
    scales = _scales(b, lb, ub, t, c, iu, il)
    floor = _diagonal_floor(qp.H)
    B, rf, M0inv, Ct, cg, fold = structure(Fm, T, A, limits.rank_tol)
    fw, ws, res, scaling, rb, D = _work_arrays(n, A.shape[0], iu.shape[0], il.shape[0], K, B, rf, Ct, fold, Fm)
    resid = (res[1], res[2], res[3], res[4], res[5])  # (rx, ry, rzu, rzl, rzc)
    system = NewtonSystem(B, rf, Ct, cg, fold, fw[1], Fm, T, A, newton.gram_plan(B, n))
    x, y, su, zu, sl, zl, sc, zc = _start(qp, T, t, iu, il, system, M0inv, floor, fw, ws, limits.box_weight,
                                          limits.pivot_drop)
    slacks = Slacks(su, zu, sl, zl, sc, zc)
    attempts, end, it = 0, MAX_ITER, 0
    memo = _guess_memo(n, K)
    for it in range(max_iter):
        mu, gap_rel, pres, dres = _measures(qp, T, t, x, y, slacks, iu, il, res, deg, scales, eps)
        done = pres <= eps and dres <= eps and gap_rel <= eps
        if done or (crossover_gap > 0.0 and gap_rel <= crossover_gap and pres <= 1e3 * crossover_gap
                    and attempts < limits.crossover_attempts):
            # the active set the iterate points at, verified by the active-set solver
            if crossover_gap > 0.0:
                tried, run = _crossover(x, slacks, iu, il, qp, cones, limits, memo, done or attempts == 0)
                attempts += tried
                if run.code == _kkt.FOUND:
                    return IPMRun(CROSSOVER, run.f, run.y, -run.grad, zc, it, run.state, run.cact, run.mus, run.dirs)
            if done:
                return IPMRun(SOLVED, x, y, _zbox(zu, zl, iu, il, n), zc, it, np.zeros(0, dtype=np.int8),
                              np.zeros(0, dtype=np.bool_), np.zeros(0), np.zeros((0, 3)))
        if _certificate(qp, T, t, y, slacks, iu, il, eps, scales, limits.certificate_rel):
            return IPMRun(INFEASIBLE_CERT, x, y, _zbox(zu, zl, iu, il, n), zc, it, np.zeros(0, dtype=np.int8),
                          np.zeros(0, dtype=np.bool_), np.zeros(0), np.zeros((0, 3)))
        # ---- scaling and the factor of the Newton system
        cone_scalings(sc, zc, scaling.Wm, scaling.Winv, scaling.W2, scaling.lamc)
        barrier(d0, iu, il, su, zu, sl, zl, floor, scaling.dbar, scaling.dinv, scaling.ru, scaling.rl)
        dropped = newton.factor(system.gram, rf, M0inv, Ct, cg, fold, scaling.W2, scaling.dinv, limits.pivot_drop,
                                fw[4], fw[0], fw[1], fw[2], fw[3])
        refine = 1 if dropped or gap_rel < limits.refine_gap else 0
        j, a = direction(resid, slacks, mu, system, scaling, iu, il, refine, limits.ncorr, ws, rb, D)
        a = min(1.0, limits.step_fraction * a)
        if not (a > limits.min_step) or not np.isfinite(a):
            end = NUMERICAL
            break
        end = MAX_ITER
        _take_step(a, j, D, x, y, slacks)
    # no convergence: one last crossover from where the iterations stopped
    if crossover_gap > 0.0:
        tried, run = _crossover(x, slacks, iu, il, qp, cones, limits, memo, True)
        if run.code == _kkt.FOUND:
            return IPMRun(CROSSOVER, run.f, run.y, -run.grad, zc, it + 1, run.state, run.cact, run.mus, run.dirs)
    return IPMRun(end, x, y, _zbox(zu, zl, iu, il, n), zc, it + 1, np.zeros(0, dtype=np.int8),
                  np.zeros(0, dtype=np.bool_), np.zeros(0), np.zeros((0, 3)))


@njit(cache=True, nogil=True, error_model="numpy")
def _diagonal_floor(H):
    """The smallest diagonal entry the barrier's ``1 / (d + z/s)`` may divide by: 1e-12 of ``H``'s
    largest diagonal entry (1e-12 when that is not positive)."""
    hmax = 0.0
    for i in range(H.shape[0]):
        hmax = max(hmax, H[i, i])
    return 1e-12 * max(hmax, 1e-300) if hmax > 0.0 else 1e-12


@njit(cache=True, nogil=True, error_model="numpy")
def _work_arrays(n, neq, nu, nl, K, B, rf, Ct, fold, Fm):
    """Every work array of the iterations, made once (a small array made per iteration would cost
    more than its arithmetic):
    ``(fw, ws, res, scaling, rb, D)`` with the Newton system's factor work ``fw = (Kb, Km, KFF, G1,
    work)`` and solve work ``ws = (r1, u, rhs, wq)``, the residuals ``res = (Px, rx, ry, rzu, rzl,
    rzc, fx)``, the barrier's and the cones' :class:`._structs.Scaling` (the cones' ``W``, ``W^-1``,
    ``W^2``, ``lambda`` zero), the right-hand sides ``rb`` and two slots of directions
    ``D = (DX, DY, DZU, DZL, DZC, DSU, DSL, DSC)``."""
    folded = fold[0].shape[0] > 0  # the cones folded into their groups: no rows of their own
    p = rf + neq if folded else rf + 3 * K + neq
    Km = np.empty((p, p))
    Kb = np.empty((B.shape[0], B.shape[0])) if Ct.shape[0] and not folded else Km
    fw = (Kb, Km, np.empty((rf, rf)), np.empty((Ct.shape[0], rf)), np.empty((2, B.shape[1])))
    ws = (np.empty(n), np.empty(n), np.empty(p), np.empty(rf))
    res = (np.empty(n), np.empty(n), np.empty(neq), np.empty(nu), np.empty(nl), np.empty((K, 3)), np.empty(Fm.shape[0]))
    rb = (np.empty(n), np.empty(neq), np.empty(nu), np.empty(nl), np.empty(nu), np.empty(nl), np.empty((K, 3)))
    D = (np.empty((2, n)), np.empty((2, neq)), np.empty((2, nu)), np.empty((2, nl)), np.empty((2, K, 3)),
         np.empty((2, nu)), np.empty((2, nl)), np.empty((2, K, 3)))
    scaling = Scaling(np.empty(n), np.empty(n), np.empty(nu), np.empty(nl), np.zeros((K, 3, 3)), np.zeros((K, 3, 3)),
                      np.zeros((K, 3, 3)), np.zeros((K, 3)))
    return fw, ws, res, scaling, rb, D


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _measures(qp, T, t, x, y, slacks, iu, il, res, deg, scales, eps):
    """The iterate's residuals (into ``res``, :func:`_work_arrays`) and how far it is from optimal:
    ``(mu, gap_rel, pres, dres)``, the mean complementarity, the relative gap and the primal and
    dual relative residuals (``scales``: :func:`_scales`)."""
    _, rx, ry, rzu, rzl, rzc, _ = res
    pobj = _residuals(qp, T, t, x, y, slacks, iu, il, res)
    gap = _gap(slacks.su, slacks.zu, slacks.sl, slacks.zl, slacks.sc, slacks.zc)
    mu = gap / max(deg, 1)
    pres = _primal_res(ry, rzu, rzl, rzc, scales[0], scales[1])
    dres = la.inf_norm(rx) / scales[2]
    # relative to the objective; an objective below eps counts as zero (then the gap must reach
    # eps^2). (An absolute floor of 1e-3 (1e-13 / eps) stopped a scaled problem whose optimum is
    # 3.5e-11 at a gap of 1e-13, 1e-3 above its optimum, after its crossover attempts had been
    # spent at relative gaps of order one: tests/test_properties.py::
    # test_ipm_reaches_the_optimum_where_the_scaled_objective_is_tiny; an optimum of exactly
    # zero still stops: tests/test_solvers.py::test_ipm_stops_on_a_problem_whose_optimum_is_zero)
    gap_rel = gap / max(eps, abs(pobj), abs(pobj - gap))
    return mu, gap_rel, pres, dres


@njit(cache=True, nogil=True, error_model="numpy")
def _take_step(a, j, D, x, y, slacks):
    """The iterate ``(x, y, slacks)`` moved (in place) by ``a`` times the direction in slot ``j`` of
    ``D`` (:func:`._ipm_direction.direction`)."""
    su, zu, sl, zl, sc, zc = slacks
    DX, DY, DZU, DZL, DZC, DSU, DSL, DSC = D
    dx, dy, dzu, dzl, dzc, dsu, dsl, dsc = DX[j], DY[j], DZU[j], DZL[j], DZC[j], DSU[j], DSL[j], DSC[j]
    for i in range(x.shape[0]):
        x[i] += a * dx[i]
    for i in range(y.shape[0]):
        y[i] += a * dy[i]
    for q in range(su.shape[0]):
        su[q] += a * dsu[q]
        zu[q] += a * dzu[q]
    for q in range(sl.shape[0]):
        sl[q] += a * dsl[q]
        zl[q] += a * dzl[q]
    for k in range(sc.shape[0]):
        for e in range(3):
            sc[k, e] += a * dsc[k, e]
            zc[k, e] += a * dzc[k, e]


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _read_active_set(x, slacks, iu, il, cones):
    """The active set an interior iterate ``(x, slacks)`` points at (Tapia's indicators): a bound
    whose slack is below its multiplier, a cone whose slack is nearer the cone's boundary than its
    multiplier is to zero; a cone's surface direction from its force at ``x``."""
    su, zu, sl, zl, sc, zc = slacks
    G, gc, ax, basis0 = cones.G, cones.gc, cones.ax, cones.basis0
    n = x.shape[0]
    K = sc.shape[0]
    state = np.zeros(n, dtype=np.int8)
    for q in range(il.shape[0]):
        if sl[q] < zl[q]:
            state[il[q]] = 1
    for q in range(iu.shape[0]):
        if su[q] < zu[q]:
            state[iu[q]] = 2
    cact = np.zeros(K, dtype=np.bool_)
    cdir = np.zeros((K, 3))
    for k in range(K):
        smin = sc[k, 0] - np.sqrt(sc[k, 1] ** 2 + sc[k, 2] ** 2)
        znorm = np.sqrt(zc[k, 0] ** 2 + zc[k, 1] ** 2 + zc[k, 2] ** 2)
        if smin < znorm:
            cact[k] = True
        Fk = gc[k] + G[k] @ x
        al = ax[k, 0] * Fk[0] + ax[k, 1] * Fk[1] + ax[k, 2] * Fk[2]
        p0, p1, p2 = Fk[0] - al * ax[k, 0], Fk[1] - al * ax[k, 1], Fk[2] - al * ax[k, 2]
        pn = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if pn > 0.0:
            cdir[k, 0], cdir[k, 1], cdir[k, 2] = p0 / pn, p1 / pn, p2 / pn
        else:
            cdir[k] = basis0[k]
    return state, cact, cdir


@njit(cache=True, nogil=True, error_model="numpy")
def _guess_memo(n, K):
    """The crossover's memory for ``n`` variables and ``K`` cones: ``(state, cact)`` of the last guess
    tried, then of the last one read (none yet: states -1)."""
    return (np.full(n, -1, dtype=np.int8), np.zeros(K, dtype=np.bool_), np.full(n, -1, dtype=np.int8),
            np.zeros(K, dtype=np.bool_))


@njit(cache=True, nogil=True, error_model="numpy")
def _new_guess(state, cact, last_state, last_cact):
    """Whether ``(state, cact)`` differs from ``(last_state, last_cact)`` (the last guess tried, or the
    last one read: then updated to it)."""
    same = True
    for i in range(state.shape[0]):
        if state[i] != last_state[i]:
            same = False
    for k in range(cact.shape[0]):
        if cact[k] != last_cact[k]:
            same = False
    last_state[:] = state
    last_cact[:] = cact
    return not same


@njit(cache=True, nogil=True, error_model="numpy")
def _zbox(zu, zl, iu, il, n):
    z = np.zeros(n)
    for q in range(iu.shape[0]):
        z[iu[q]] += zu[q]
    for q in range(il.shape[0]):
        z[il[q]] -= zl[q]
    return z
