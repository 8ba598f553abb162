r"""Compiled fast paths of per-instant steps that were ~40 small numpy calls each (on the warm
path of a trajectory, where one instant's solve is a fraction of a millisecond, their Python
overhead cost as much as the solve). The scaling decision has its own compiled pass
(:func:`mcdm_pin.model.kernels.needs_scaling`).

- :func:`answer_unique`: the uniqueness test of an answer (:func:`._unique.unique_test`, compiled
  :func:`mcdm_pin.solvers.least_norm.is_unique`, which calls it through this module).
- :func:`active_set_answer`: the active-set kernel (:func:`._kkt.active_set_run`) and, at a verified
  point, its answer's duals and objective (:func:`mcdm_pin.solvers.active_set.active_solution`, the
  numpy reference), in one call.

Two more fuse the runner's per-instant numpy steps after the solve into one pass each, with the
same formulas: :func:`answer_check` (equation-of-motion residual, bounds, cones: the runner's check
of every answer on the original problem) and :func:`instant_outputs` (interaction wrenches, socket
forces and angles); :func:`answer_check_outputs` calls both at once (the runner's usual path).
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._ipm_linalg import dot
from ._ipm import CROSSOVER, INFEASIBLE_CERT, ipm_solve
from ._kkt import FOUND, active_set_run, next_guess
from ._kkt_eq import cone_force
from ._structs import QP, Answer, Cones, KKTMeasures, Limits, Tensions
from ._unique import face_setup, unique_test


@njit(cache=True, nogil=True)
def answer_check(L, tau, extra, x, lb, ub, G, g, ax, angle_deg):
    """The runner's check of an answer on the original problem, in one pass
    (:func:`mcdm_pin.inverse_dynamics._check`): ``(eom, broken, viol, k)`` with ``eom`` the relative
    equation-of-motion residual (:meth:`mcdm_pin.model.terms.Terms.eom_residual`: ``|tau + L^T f +
    extra|_inf`` over ``max(|tau|_inf, max_v sum_c |L_cv f_c|, |extra|_inf)``, ``f`` the first
    ``L.shape[0]`` entries of ``x``), ``broken`` the largest bound violation (0 inside), ``viol``
    the largest cone violation in degrees (:func:`mcdm_pin.solvers.base.cone_violation_deg`) and
    ``k`` its cone (-1: none)."""
    m, nv = L.shape
    n = x.shape[0]
    scale = 1e-300
    extra_scale = 0.0
    for v in range(extra.shape[0]):
        extra_scale = max(extra_scale, abs(extra[v]))
    rmax = 0.0
    tmax = 0.0
    smax = 0.0
    # row by row of L (each column's sums in the same order as a loop down the column: the same
    # bits, without L's stride)
    res = tau.copy()
    mag = np.zeros(nv)
    for c in range(m):
        Lc = L[c]
        xc = x[c]
        ac = abs(xc)
        for v in range(nv):
            res[v] += Lc[v] * xc
            mag[v] += abs(Lc[v]) * ac
    for v in range(nv):
        r = res[v]
        s = mag[v]
        if extra.shape[0]:
            r += extra[v]
        if not abs(r) <= rmax:
            rmax = abs(r)
            if r != r:
                return np.nan, np.nan, np.nan, -1
        tmax = max(tmax, abs(tau[v]))
        smax = max(smax, s)
    scale = max(tmax, smax, extra_scale, 1e-300)
    eom = rmax / scale
    broken = 0.0
    for i in range(n):
        if x[i] != x[i]:
            return eom, np.nan, np.nan, -1
        if not lb[i] - x[i] <= broken:
            broken = lb[i] - x[i]
        if not x[i] - ub[i] <= broken:
            broken = x[i] - ub[i]
    viol = 0.0
    worst = -1
    for k in range(G.shape[0]):
        _, _, _, al, p0, p1, p2 = cone_force(G, g, ax, k, x)
        ang = np.degrees(np.arctan2(np.sqrt(p0 * p0 + p1 * p1 + p2 * p2), al)) - angle_deg[k]
        if not ang <= viol:
            viol = ang
            worst = k
    return eom, broken, viol, worst


@njit(cache=True, nogil=True)
def instant_outputs(u, RT, R_socket, axes, f):
    """Per physical joint: the interaction wrench ``u + R^T f`` (J, 6, child frame), its force in the
    socket frame (J, 3) and that force's angle from the socket axis, degrees (J,)
    (:meth:`mcdm_pin.model.terms.Terms.wrenches`, :func:`mcdm_pin.model.terms.interaction_angles`)."""
    J = u.shape[0]
    m = f.shape[0]
    W = np.empty((J, 6))
    Fs = np.empty((J, 3))
    ang = np.empty(J)
    for j in range(J):
        for a in range(6):
            acc = 0.0
            for c in range(m):
                acc += RT[j, a, c] * f[c]
            W[j, a] = u[j, a] + acc
        for a in range(3):
            Fs[j, a] = R_socket[j, a, 0] * W[j, 0] + R_socket[j, a, 1] * W[j, 1] + R_socket[j, a, 2] * W[j, 2]
        al = Fs[j, 0] * axes[j, 0] + Fs[j, 1] * axes[j, 1] + Fs[j, 2] * axes[j, 2]
        p0, p1, p2 = Fs[j, 0] - al * axes[j, 0], Fs[j, 1] - al * axes[j, 1], Fs[j, 2] - al * axes[j, 2]
        ang[j] = np.degrees(np.arctan2(np.sqrt(p0 * p0 + p1 * p1 + p2 * p2), al))
    return W, Fs, ang


@njit(cache=True, nogil=True)
def active_set_answer(qp, cones, state0, cact0, dirs0, limits, x0, mus0):
    """:func:`._kkt.active_set_run` on ``qp`` (a :class:`._structs.QP`) with ``cones``
    (:class:`._structs.Cones`) within ``limits`` (:class:`._structs.Limits`) from the guess
    ``(state0, cact0, dirs0)`` (``dirs0``: the held cones' surface directions; the others start from
    ``cones.basis0``; ``x0``, ``mus0``: the guess's point and its cones' multipliers, or empty),
    then, at a verified point, what :func:`mcdm_pin.solvers.active_set.active_solution` makes of it:
    the bounds' multipliers ``z`` (base convention), the cone duals ``z_cone``
    (:func:`mcdm_pin.solvers.active_set.cone_duals`), the objective ``1/2 f^T H f + c^T f + r`` and
    the cones held with a positive multiplier.

    And whether the optimum is provably unique (:func:`answer_unique`), so that the least-norm stage
    need not ask again.

    Returns an :class:`._structs.Answer` (``iterations``: the KKT systems solved); only ``code`` and
    ``iterations`` mean anything unless ``code`` is :data:`._kkt.FOUND`."""
    qp, cones, limits = QP(*qp), Cones(*cones), Limits(*limits)  # (plain tuples at the boundary: ._structs)
    nc = cones.G.shape[0]
    cdir = cones.basis0.copy()
    for k in range(nc):
        if cact0[k]:
            for a in range(3):
                cdir[k, a] = dirs0[k, a]
    run = active_set_run(qp, cones, state0, cact0, cdir, limits, x0, mus0)
    if run.code != FOUND:
        n = run.f.shape[0]
        return Answer(run.code, run.f, run.y, np.zeros(n), np.zeros((nc, 3)), np.nan, run.solves,
                      np.zeros(nc, dtype=np.bool_), run.mus, run.dirs, run.next_state, 0)
    z, zc, obj, held = answer_duals(qp, cones, run.f, run.grad, run.state, run.cact, run.mus, run.dirs)
    unique = answer_unique(run.f, z, zc, qp, cones, limits)
    return Answer(run.code, run.f, run.y, z, zc, obj, run.solves, held, run.mus, run.dirs, run.next_state, unique)


@njit(cache=True, nogil=True)
def answer_unique(x, z, zc, qp, cones, limits):
    """:func:`mcdm_pin.solvers.least_norm.is_unique` of an answer ``x`` of ``qp`` with its duals ``z``,
    ``zc``: 1 when ``qp.strict`` (its first test: a strictly convex objective), else
    :func:`unique_test` (``limits``: its thresholds ``near``, ``unique_rel``, ``penalty``)."""
    if qp.strict:
        return 1
    return unique_test(x, z, zc, qp, cones, limits)


@njit(cache=True, nogil=True)
def answer_duals(qp, cones, f, grad, state, cact, mus, dirs):
    """A verified active-set point's (``f`` on ``qp`` and ``cones``, at the active set ``state``,
    ``cact`` with the bounds' multipliers ``grad`` (> 0 at a lower bound), the cones' ``mus`` and
    surface directions ``dirs``) duals and objective (what :func:`mcdm_pin.solvers.active_set.active_solution`
    computes in numpy): the bounds' multipliers ``z`` (base convention), the cone duals ``z_cone``
    (:func:`mcdm_pin.solvers.active_set.cone_duals`, from the half-angles' cosines ``cosr`` and the
    planes ``basis`` normal to the axes), the objective ``1/2 f^T H f + c^T f + r`` and the cones
    held with a positive multiplier. Returns ``(z, z_cone, objective, held)``.

    A held cone's dual points along its force's own direction across the axis at ``f``
    (:func:`held_direction`), the direction :func:`._kkt_verify.verify` judged stationarity with."""
    H, g, r = qp.H, qp.c, qp.r
    cosr, basis = cones.cosr, cones.basis
    n = f.shape[0]
    nc = mus.shape[0]
    z = np.zeros(n)
    zc = np.zeros((nc, 3))
    held = np.zeros(nc, dtype=np.bool_)
    for i in range(n):
        if state[i] != 0:
            z[i] = -grad[i]
    for k in range(nc):
        mu = mus[k] if cact[k] else 0.0
        held[k] = cact[k] and mus[k] > 0.0
        if mu != 0.0:
            d0, d1, d2 = held_direction(cones.G, cones.gc, cones.ax, k, f, dirs)
            zc[k, 0] = mu / cosr[k]
            for e in range(2):
                zc[k, 1 + e] = -zc[k, 0] * (basis[k, e, 0] * d0 + basis[k, e, 1] * d1 + basis[k, e, 2] * d2)
    quad = 0.0
    lin = 0.0
    for i in range(n):
        quad += dot(H[i], f) * f[i]  # (H symmetric: row i is column i)
        lin += g[i] * f[i]
    return z, zc, 0.5 * quad + lin + r, held


@njit(cache=True, nogil=True)
def held_direction(G, gc, ax, k, f, dirs):
    """The unit direction of held cone ``k``'s force across its axis at ``f``; ``dirs[k]`` (the
    surface direction the active set carried) where that part is of rounding size (at most 1e-12 of
    the force, as :func:`._unique._held_cone_rows` judges a cone held at its apex). The active-set
    solver stops Newton's method on the surface once the force is on it to ``surface_tol``, where
    ``dirs`` may still lag the force's own direction; with a large multiplier, duals aimed along
    ``dirs`` fail the chain's check of stationarity at a point the active-set check verified
    (docs/speed.md, "The equations' rank through a pivot")."""
    F0, F1, F2, _, p0, p1, p2 = cone_force(G, gc, ax, k, f)
    perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
    if perp > 1e-12 * np.sqrt(F0 * F0 + F1 * F1 + F2 * F2):
        return p0 / perp, p1 / perp, p2 / perp
    return dirs[k, 0], dirs[k, 1], dirs[k, 2]


@njit(cache=True, nogil=True)
def cone_rows(G, g, ax, cosr, basis):
    """:meth:`mcdm_pin.problem.QPData.cone_rows` from the stacked cones: per cone ``T = W G``,
    ``t = W g`` with ``W = [sin(rho) axis; cos(rho) basis]``."""
    K, _, n = G.shape
    T = np.zeros((K, 3, n))
    t = np.zeros((K, 3))
    for k in range(K):
        c = cosr[k]
        W = np.empty((3, 3))
        for a in range(3):
            W[0, a] = np.sqrt(max(1.0 - c * c, 0.0)) * ax[k, a]
            W[1, a] = c * basis[k, 0, a]
            W[2, a] = c * basis[k, 1, a]
        for e in range(3):
            for a in range(3):
                w = W[e, a]
                if w != 0.0:
                    t[k, e] += w * g[k, a]
                    for j in range(n):
                        T[k, e, j] += w * G[k, a, j]
    return T, t


@njit(cache=True, nogil=True, error_model="numpy")
def ipm_answer(qp, cones, limits):
    """:func:`._ipm.ipm_solve` on ``qp`` (a :class:`._structs.QP`) with ``cones``
    (:class:`._structs.Cones`; the cone rows made here: :func:`cone_rows`) within ``limits``
    (:class:`._structs.Limits`) and, after a crossover, the answer's duals and objective
    (:func:`answer_duals`) and the next instant's guess of the bounds (multipliers below
    ``limits.keep_rel`` of the largest free their variable), in one call.

    Variables with ``lb == ub`` (a muscle whose force range has collapsed to its passive force) are
    substituted out first (:func:`without_fixed`): a box without interior leaves an interior-point
    method no room (its two slacks must vanish together; on MyoSuite's arm, case 3, such a muscle
    made 54 of 101 cold instants end in a numerical breakdown or at a crossover that failed). The
    reduced problem is solved and its answer extended (:func:`with_fixed`).

    Returns an :class:`._structs.Answer`: after a crossover as :func:`active_set_answer`'s;
    otherwise ``z, z_cone`` the method's own (or the certificate), the rest empty and ``unique`` 0."""
    qp, cones, limits = QP(*qp), Cones(*cones), Limits(*limits)  # (plain tuples at the boundary: ._structs)
    T, t = cone_rows(cones.G, cones.gc, cones.ax, cones.cosr, cones.basis)
    fixed, free = fixed_split(qp.lb, qp.ub)
    reduce = fixed.shape[0] > 0 and free.shape[0] > 0
    if reduce:
        qpr, Tr, tr, cr = without_fixed(qp, T, t, cones, fixed, free)
    else:
        qpr, Tr, tr, cr = qp, T, t, cones
    run = ipm_solve(qpr, Tr, tr, cr, limits)
    x, z, zc, state = run.x, run.z, run.z_cone, run.state
    obj, held, nxt, unique = np.nan, np.zeros(0, dtype=np.bool_), state, 0
    if run.code == CROSSOVER:
        grad = -z
        nxt = next_guess(state, grad, limits.keep_rel)
        z, zc, obj, held = answer_duals(qpr, cr, x, grad, state, run.cact, run.mus, run.dirs)
        unique = answer_unique(x, z, zc, qpr, cr, limits)
    if reduce:
        x, z, objf, nxt = with_fixed(run.code, x, run.y, z, zc, nxt, qp, T, fixed, free, limits.keep_rel)
        obj = objf if run.code == CROSSOVER else obj
    return Answer(run.code, x, run.y, z, zc, obj, run.iterations, held, run.mus, run.dirs, nxt, unique)


@njit(cache=True, nogil=True)
def fixed_split(lb, ub):
    """``(fixed, free)``: the indices of the variables with ``lb == ub`` (finite) and of the others."""
    n = lb.shape[0]
    nfix = 0
    for i in range(n):
        if lb[i] == ub[i] and np.isfinite(lb[i]):
            nfix += 1
    fixed = np.empty(nfix, dtype=np.int64)
    free = np.empty(n - nfix, dtype=np.int64)
    a_, b_ = 0, 0
    for i in range(n):
        if lb[i] == ub[i] and np.isfinite(lb[i]):
            fixed[a_] = i
            a_ += 1
        else:
            free[b_] = i
            b_ += 1
    return fixed, free


@njit(cache=True, nogil=True)
def without_fixed(qp, T, t, cones, fixed, free):
    r"""The problem over the ``free`` variables with the ``fixed`` ones at their value ``x_F = lb_F``:
    with ``x = (x_R, x_F)``,

    .. math:: \tfrac12 x_R^T H_{RR} x_R + (c_R + H_{RF} x_F)^T x_R
              + (r + c_F^T x_F + \tfrac12 x_F^T H_{FF} x_F),

    ``A_R x_R = b - A_F x_F``, the cone rows ``T_R x_R + (t + T_F x_F)`` and forces
    ``G_R x_R + (g + G_F x_F)``; ``P = diag(d0) + Fm^T Fm`` keeps its form (``d0_R``, ``Fm_R``).
    Returns ``(qp', T_R, t', cones')``: ``qp'`` the reduced :class:`._structs.QP` (``H_RR, d0_R,
    Fm_R, c', r', A_R, b'`` and the free variables' bounds), ``cones'`` the cones with ``G_R, g'``."""
    H, d0, Fm, c, r, A, b, lb = qp.H, qp.d0, qp.F, qp.c, qp.r, qp.A, qp.b, qp.lb
    G, g = cones.G, cones.gc
    nr, nf = free.shape[0], fixed.shape[0]
    xF = np.empty(nf)
    for a in range(nf):
        xF[a] = lb[fixed[a]]
    Hr = np.empty((nr, nr))
    cr = np.empty(nr)
    for a in range(nr):
        i = free[a]
        acc = c[i]
        for q in range(nf):
            acc += H[i, fixed[q]] * xF[q]
        cr[a] = acc
        for e in range(nr):
            Hr[a, e] = H[i, free[e]]
    rr = r
    for q in range(nf):
        j = fixed[q]
        rr += c[j] * xF[q]
        for p in range(nf):
            rr += 0.5 * xF[q] * H[j, fixed[p]] * xF[p]
    d0r = np.empty(nr)
    Fr = np.empty((Fm.shape[0], nr))
    Ar = np.empty((A.shape[0], nr))
    for a in range(nr):
        d0r[a] = d0[free[a]]
        for k in range(Fm.shape[0]):
            Fr[k, a] = Fm[k, free[a]]
        for k in range(A.shape[0]):
            Ar[k, a] = A[k, free[a]]
    br = b.copy()
    for k in range(A.shape[0]):
        for q in range(nf):
            br[k] -= A[k, fixed[q]] * xF[q]
    K = T.shape[0]
    Tr = np.empty((K, 3, nr))
    Gr = np.empty((K, 3, nr))
    tr = t.copy()
    gr = g.copy()
    for k in range(K):
        for e in range(3):
            for a in range(nr):
                Tr[k, e, a] = T[k, e, free[a]]
                Gr[k, e, a] = G[k, e, free[a]]
            for q in range(nf):
                tr[k, e] += T[k, e, fixed[q]] * xF[q]
                gr[k, e] += G[k, e, fixed[q]] * xF[q]
    qpr = QP(Hr, d0r, Fr, cr, rr, Ar, br, lb[free], qp.ub[free], qp.strict)
    return qpr, Tr, tr, Cones(Gr, gr, cones.ax, cones.tn, cones.basis0, cones.cosr, cones.basis)


@njit(cache=True, nogil=True)
def with_fixed(code, x, y, z, zc, nxt, qp, T, fixed, free, keep_rel):
    """The reduced problem's answer (:func:`without_fixed`; ``code`` its :func:`._ipm.ipm_solve` code)
    on every variable: ``x_F = lb_F``; the fixed variables' bound multipliers from stationarity
    (:mod:`.base`'s convention, ``z_F = -(H x + c + A^T y - sum_k T_k^T z^cone_k)_F``, without
    ``H x + c`` for an infeasibility certificate: a fixed variable is at both bounds, so its
    multiplier may have either sign); after a crossover the objective on the whole
    problem and the next guess, a fixed variable held at the bound its multiplier points to
    (unless that multiplier is below ``keep_rel`` of the largest, :func:`._kkt.next_guess`'s rule).
    Returns ``(x, z, objective, next_state)``."""
    H, c, r, A, lb = qp.H, qp.c, qp.r, qp.A, qp.lb
    n = lb.shape[0]
    nr, nf = free.shape[0], fixed.shape[0]
    xf = np.empty(n)
    zf = np.zeros(n)
    for a in range(nr):
        xf[free[a]] = x[a]
        zf[free[a]] = z[a]
    for q in range(nf):
        xf[fixed[q]] = lb[fixed[q]]
    K = T.shape[0]
    for q in range(nf):
        j = fixed[q]
        s = 0.0 if code == INFEASIBLE_CERT else c[j] + dot(H[j], xf)
        for k in range(A.shape[0]):
            s += A[k, j] * y[k]
        for k in range(K):
            for e in range(3):
                s -= T[k, e, j] * zc[k, e]
        zf[j] = -s
    if code != CROSSOVER:
        return xf, zf, np.nan, nxt
    obj = r
    for i in range(n):
        obj += (0.5 * dot(H[i], xf) + c[i]) * xf[i]
    zmax = 0.0
    for i in range(n):
        zmax = max(zmax, abs(zf[i]))
    nxtf = np.zeros(n, dtype=np.int8)
    for a in range(nr):
        nxtf[free[a]] = nxt[a]
    for q in range(nf):
        j = fixed[q]
        if abs(zf[j]) > keep_rel * zmax:
            nxtf[j] = 2 if zf[j] > 0.0 else 1
    return xf, zf, obj, nxtf


@njit(cache=True, nogil=True)
def answer_check_outputs(L, tau, extra, x, lb, ub, G, g, ax, angle_deg, u, RT, R_socket, axes, tensions):
    """:func:`answer_check`, :func:`instant_outputs` and :func:`activations` (at the first
    ``L.shape[0]`` entries of ``x``, the cable forces; ``tensions``: :class:`._structs.Tensions`) in
    one call: ``(eom, broken, viol, k, W, Fs, angles, activation)``."""
    tensions = Tensions(*tensions)  # (a plain tuple at the boundary: ._structs)
    m = L.shape[0]
    eom, broken, viol, k = answer_check(L, tau, extra, x, lb, ub, G, g, ax, angle_deg)
    W, Fs, ang = instant_outputs(u, RT, R_socket, axes, x[:m])
    return eom, broken, viol, k, W, Fs, ang, activations(tensions, x, m)


@njit(cache=True, nogil=True, error_model="numpy")
def activations(tensions, f, m):
    """The muscles' activations at the tensions ``f`` (:func:`mcdm_pin.model.muscles.activation`'s
    formulas: ``(f - passive) / gain``; where ``gain`` is 0, ``a_min`` when ``f`` is within
    ``bound_abs`` of the passive force, else NaN), NaN on the other cables: (m,); (0,) without
    muscles."""
    idx = tensions.index
    if idx.shape[0] == 0:
        return np.empty(0)
    out = np.full(m, np.nan)
    for i in range(idx.shape[0]):
        c = idx[i]
        d = f[c] - tensions.passive[i]
        gain = tensions.gain[i]
        if gain == 0.0:
            out[c] = tensions.a_min[i] if abs(d) <= tensions.bound_abs else np.nan
        else:
            out[c] = d / gain
    return out


@njit(cache=True, nogil=True, error_model="numpy")
def kkt_measures(qp, cones, angle_deg, x, y, z, zc, duals, floor):
    """:func:`mcdm_pin.solvers.check.kkt_residuals` in one pass (:class:`._structs.KKTMeasures`, its
    numpy reference's formulas): ``qp`` with ``H`` the dense Hessian, or ``d0`` (n,) and ``F`` its
    structure ``H = diag(d0) + F^T F``; ``cones`` (with ``cosr`` and ``basis``: their rows
    :func:`cone_rows`, :meth:`mcdm_pin.qp.QPData.cone_rows`'s) and their half-angles ``angle_deg``; the
    point ``x`` and, when ``duals``, its multipliers ``y``, ``z``, ``zc``; ``floor``: the gradient
    scale's least value."""
    qp, cones = QP(*qp), Cones(*cones)  # (plain tuples at the boundary: ._structs)
    eom, bound, cone_deg = _primal_measures(qp, cones, angle_deg, x)
    if not duals:
        return KKTMeasures(eom, bound, cone_deg, np.nan, np.nan)
    T, t = cone_rows(cones.G, cones.gc, cones.ax, cones.cosr, cones.basis)
    n, k, K = x.shape[0], qp.b.shape[0], T.shape[0]
    Px, size = _hessian_product(qp, x)
    g = np.empty(n)
    gscale = floor
    for i in range(n):
        aty = 0.0
        for r in range(k):
            aty += qp.A[r, i] * y[r]
        tl = 0.0
        for c in range(K):
            tl += T[c, 0, i] * zc[c, 0] + T[c, 1, i] * zc[c, 1] + T[c, 2, i] * zc[c, 2]
        g[i] = Px[i] + qp.c[i] + aty + z[i] - tl
        gscale = max(gscale, abs(Px[i]), abs(qp.c[i]), abs(aty), abs(z[i]), size[i], abs(tl))
    stat = 0.0
    for i in range(n):
        stat = _nanmax(stat, abs(g[i]))
    comp, outside, smax = 0.0, 0.0, 0.0
    for c in range(K):
        ls = 0.0
        for a in range(3):
            s = t[c, a]
            for j in range(n):
                s += T[c, a, j] * x[j]
            ls += zc[c, a] * s
            smax = _nanmax(smax, abs(s))
        comp += abs(ls)
        outside += max(np.sqrt(zc[c, 1] * zc[c, 1] + zc[c, 2] * zc[c, 2]) - zc[c, 0], 0.0)
    comp += outside * (1.0 + smax)  # every cone dual in its cone, to rounding
    xscale, bscale = 1e-300, 0.0
    for i in range(n):
        if z[i] > 0:
            comp += z[i] * (qp.ub[i] - x[i])
        elif z[i] < 0:
            comp += -z[i] * (x[i] - qp.lb[i])
        xscale = _nanmax(xscale, abs(x[i]))
        for b in (qp.lb[i], qp.ub[i]):
            if np.isfinite(b):
                bscale = max(bscale, abs(b))
    denominator = gscale * max(xscale, 1e-12 * bscale)  # (0 where every term and variable is 0)
    if not np.isfinite(comp):
        complementarity = np.inf
    elif denominator > 0.0:
        complementarity = abs(comp) / denominator
    else:
        complementarity = 0.0 if comp == 0.0 else np.inf
    return KKTMeasures(eom, bound, cone_deg, stat / gscale, complementarity)


@njit(cache=True, nogil=True, error_model="numpy")
def _primal_measures(qp, cones, angle_deg, x):
    """:func:`kkt_measures`' primal part: ``(eom, bound, cone_deg)``."""
    n, k = x.shape[0], qp.b.shape[0]
    eom = 0.0
    if k:
        rmax, scale = 0.0, 1e-300
        for i in range(k):
            acc, mag = 0.0, 0.0
            for j in range(n):
                acc += qp.A[i, j] * x[j]
                mag += abs(qp.A[i, j]) * abs(x[j])
            rmax = _nanmax(rmax, abs(acc - qp.b[i]))
            scale = _nanmax(scale, max(abs(qp.b[i]), mag))
        eom = rmax / scale
    bound = 0.0
    for i in range(n):
        bound = _nanmax(_nanmax(bound, qp.lb[i] - x[i]), x[i] - qp.ub[i])
    cone_deg = 0.0
    for c in range(cones.G.shape[0]):
        _, _, _, al, p0, p1, p2 = cone_force(cones.G, cones.gc, cones.ax, c, x)
        cone_deg = _nanmax(cone_deg, np.degrees(np.arctan2(np.sqrt(p0 * p0 + p1 * p1 + p2 * p2), al)) - angle_deg[c])
    return eom, bound, cone_deg


@njit(cache=True, nogil=True)
def _hessian_product(qp, x):
    """``(P x, |P| |x|)`` for :func:`kkt_measures` (``qp.d0`` of size n: ``P = diag(d0) + F^T F``,
    and ``|P|`` is read as ``diag(|d0|) + |F|^T |F|``; else the dense ``qp.H``)."""
    n = x.shape[0]
    Px, size = np.zeros(n), np.zeros(n)
    if qp.d0.shape[0] == n:
        for r in range(qp.F.shape[0]):
            fx, fa = 0.0, 0.0
            for j in range(n):
                fx += qp.F[r, j] * x[j]
                fa += abs(qp.F[r, j]) * abs(x[j])
            for i in range(n):
                Px[i] += qp.F[r, i] * fx
                size[i] += abs(qp.F[r, i]) * fa
        for i in range(n):
            Px[i] += qp.d0[i] * x[i]
            size[i] += abs(qp.d0[i]) * abs(x[i])
    else:
        for i in range(n):
            for j in range(n):
                Px[i] += qp.H[i, j] * x[j]
                size[i] += abs(qp.H[i, j]) * abs(x[j])
    return Px, size


@njit(cache=True, nogil=True)
def _nanmax(m, v):
    """``max(m, v)``, NaN once either is (numpy's ``max`` of an array with a NaN)."""
    if m != m or v != v:
        return np.nan
    return v if v > m else m


@njit(cache=True, nogil=True)
def outside_bounds(x, lb, ub):
    """Whether some ``x_i < lb_i`` or ``x_i > ub_i`` (NaN: no)."""
    for i in range(x.shape[0]):
        if x[i] < lb[i] or x[i] > ub[i]:
            return True
    return False


def warm_calls():
    """The kernels with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit` by :mod:`.active_set`)."""
    z = np.zeros
    n = 2
    qp = QP(z((n, n)), z(0), z((0, n)), z(n), 0.0, z((1, n)), z(1), z(n), z(n), False)
    cones = Cones(z((1, 3, n)), z((1, 3)), z((1, 3)), z(1), z((1, 3)), z(1), z((1, 2, 3)))
    limits = Limits(2, 2, 1e-10, 1e-12, 1e-9, 1e-11, 1e-12, 1e-8, 1e-10, 1e-12, 1e-12, 1e-12, 1e-8, 1e-9, 1e3, 60, 1e-10,
                    1e-3, 1, 1e-9, 0.2, 8, 1e-14, 1e-5, 0.99, 1e-14, 1e-6)
    # (the entry points Python calls at every instant take plain tuples: ._structs)
    tq, tc, tl = tuple(qp), tuple(cones), tuple(limits)
    calls = [(active_set_answer, (tq, tc, z(n, dtype=np.int8), z(1, dtype=np.bool_), z((1, 3)), tl, z(n), z(1)))]
    return calls + [(answer_unique, (z(n), z(n), z((1, 3)), qp, cones, limits)),
            (answer_check, (z((n, 1)), z(1), z(0), z(n), z(n), z(n), z((1, 3, n)), z((1, 3)), z((1, 3)), z(1))),
            (answer_check_outputs, (z((n, 1)), z(1), z(0), z(n), z(n), z(n), z((1, 3, n)), z((1, 3)), z((1, 3)), z(1),
                                    z((1, 6)), z((1, 6, n)), z((1, 3, 3)), z((1, 3)),
                                    tuple(Tensions(z(1, dtype=np.int64), z(1), z(1), z(1), 1e-6)))),
            (outside_bounds, (z(n), z(n), z(n))),
            (kkt_measures, (tq, tc, z(1), z(n), z(1), z(n), z((1, 3)), True, 1e-300)),
            (instant_outputs, (z((1, 6)), z((1, 6, n)), z((1, 3, 3)), z((1, 3)), z(n))),
            (face_setup, (z(n), z(n), z((1, 3)), tq, tc, tl, z((1, n)), z(n), z(n)))]
