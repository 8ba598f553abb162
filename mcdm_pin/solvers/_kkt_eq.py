r"""The equality-constrained solve of one active set (:func:`eq_solve`, for :mod:`._kkt`'s pivoting
loop): the cables of the set fixed at their bounds, the held cones on their surfaces (Newton steps
on the surfaces' curvature), the equations of motion as equations.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._kkt_linalg import determined_solve, kkt_solve, matvec, schur_solve, vertex_solve_lu

# eq_solve codes
OK, SINGULAR, NO_CONVERGENCE, DROP, VANISHED = 0, 1, 2, 3, 5


@njit(cache=True, nogil=True, inline="always")
def cone_force(G, gc, ax, k, x):
    """Cone ``k``'s force ``F = g_k + G_k x`` at ``x``, its component along the axis and the part
    perpendicular to it: ``(F0, F1, F2, along, p0, p1, p2)``."""
    F0, F1, F2 = gc[k, 0], gc[k, 1], gc[k, 2]
    for i in range(x.shape[0]):
        xi = x[i]
        F0 += G[k, 0, i] * xi
        F1 += G[k, 1, i] * xi
        F2 += G[k, 2, i] * xi
    al = ax[k, 0] * F0 + ax[k, 1] * F1 + ax[k, 2] * F2
    return F0, F1, F2, al, F0 - al * ax[k, 0], F1 - al * ax[k, 1], F2 - al * ax[k, 2]


@njit(cache=True, nogil=True)
def _on_surfaces(f, G, gc, ax, tn, act, tol):
    """Every cone of ``act`` has ``| |F_perp| - tan a.F | <= tol |F|`` at ``f``."""
    for s in range(act.shape[0]):
        k = act[s]
        F = gc[k] + G[k] @ f
        al = ax[k, 0] * F[0] + ax[k, 1] * F[1] + ax[k, 2] * F[2]
        p0, p1, p2 = F[0] - al * ax[k, 0], F[1] - al * ax[k, 1], F[2] - al * ax[k, 2]
        perp = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
        if not abs(perp - tn[k] * al) <= tol * np.sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]):
            return False
    return True


@njit(cache=True, nogil=True, inline="always")
def eq_solve(qp, cones, state, cact, cdir, limits, reg, x0, mus0):
    """Minimise ``1/2 f^T H f + c^T f`` (``qp``, a :class:`._structs.QP`) with ``A f = b``, the
    cables of ``state`` fixed at their bounds and the cones of ``cact`` (of ``cones``, a
    :class:`._structs.Cones`) held on their surface (at most ``limits.max_newton`` Newton steps down
    to ``limits.step_tol``, with the cones' curvature weighted by their multipliers).

    ``x0``, ``mus0``: a point near the answer and its cones' multipliers, or empty (:func:`_warm_start`);
    without one the first step linearises each held cone along ``cdir``.

    ``reg`` (n,) > 0 is added to the free cables' diagonal (a Tikhonov term ``1/2 sum reg_i f_i^2``):
    with a positive semidefinite objective whose optimum is a flat ridge (case 2 with ``beta = 0``)
    the system is otherwise singular and its solution arbitrary along the ridge; with it, the point
    of the ridge nearest the origin in that weighted norm. The KKT check of the original problem
    decides whether the point is accepted (its residual ``reg_i f_i``: ~1e-12 of the gradient's
    scale, :func:`._kkt.tikhonov`; refined where a cable has no curvature, :func:`_refine`).

    Returns ``(code, f, y, mus, dirs, solves, LU, perm, lu_ok)``: ``mus`` (nc,) the active cones'
    multipliers (0 elsewhere), ``dirs`` (nc, 3) their surface directions at ``f``, ``solves`` the
    linear KKT systems solved (1 without active cones; one per Newton step with them); at a vertex,
    ``(LU, perm)`` the factors of the last solve's rows on the free cables (:func:`._kkt_linalg.vertex_solve_lu`;
    ``lu_ok`` false otherwise).
    """
    H, g, A, b, lb, ub = qp.H, qp.c, qp.A, qp.b, qp.lb, qp.ub
    G, gc, ax, tn = cones.G, cones.gc, cones.ax, cones.tn
    max_newton, step_tol = limits.max_newton, limits.step_tol
    neq, nc = A.shape[0], G.shape[0]
    f, free = _fixed_point(state, lb, ub)
    act = _held(cact)
    nf, na = free.shape[0], act.shape[0]
    mus = np.zeros(nc)
    dirs = cdir.copy()
    # fewer free cables than equations is fine when the equations are dependent (e.g. the 2-link
    # arm at q = 0): the KKT system is then solved in the least-squares sense (and verified)
    square = nf >= neq + na
    N = nf + neq + na
    # fixed part of the gradient and of the equations (f is zero on the free cables here)
    Hf = matvec(H, f)
    Af = matvec(A, f)
    f_cur = f.copy()
    x_prev = np.zeros(nf)
    have_cur = have_prev = _warm_start(x0, mus0, free, act, f_cur, mus, x_prev)
    last_step = -1.0  # the last Newton step's size (none yet)
    y = np.zeros(neq)
    iters = max_newton if na > 0 else 1
    flat = _flat(H, free)
    converged = False
    solves = 0
    LU = np.empty((0, 0))
    perm = np.empty(0, dtype=np.int64)
    lu_ok = False
    for _ in range(iters):
        K = np.zeros((N, N))
        rhs = np.empty(N)
        _linear_rows(H, g, A, b, reg, free, Hf, Af, K, rhs)
        if not _cone_rows(G, gc, ax, tn, state, f, f_cur, have_cur, free, neq, act, mus, dirs, K, rhs):
            return VANISHED, f, y, mus, dirs, solves, LU, perm, False
        sol, LU, perm, lu_ok = _solve_refined(K, rhs, nf, neq, na, square, reg, free, flat)
        solves += 1
        if not _finite(sol):
            return SINGULAR, f, y, mus, dirs, solves, LU, perm, False
        y = _take(sol, free, neq, act, f, mus)
        if na == 0:
            converged = True
            break
        # (from the second solve: the first one's multipliers, at a point of another instant, mislead)
        if solves > 1 and _pulling(mus, act):
            return DROP, f, y, mus, dirs, solves, LU, perm, lu_ok
        if have_prev:
            done, last_step = _settled(sol, x_prev, f, G, gc, ax, tn, act, step_tol, last_step, limits.settle_tol)
            if done:
                converged = True
                break
        for p in range(nf):
            x_prev[p] = sol[p]
        have_prev = True
        f_cur[:] = f
        have_cur = True
    if not converged:
        return NO_CONVERGENCE, f, y, mus, dirs, solves, LU, perm, lu_ok
    return OK, f, y, mus, dirs, solves, LU, perm, lu_ok


@njit(cache=True, nogil=True)
def _warm_start(x0, mus0, free, act, f_cur, mus, x_prev):
    """A guess's point ``x0`` (n,) and its cones' multipliers ``mus0`` (nc,) (the previous instant's
    answer) as the Newton steps' start, in place: the point where the first step takes the surfaces'
    curvature and directions (``f_cur``), as the later steps take them at the point before, the held
    cones' multipliers (``mus``) and the free cables' values the first step is measured from
    (``x_prev``, :func:`_settled`). Whether there is one: held cones (``act``) and arrays of the
    problem's sizes (empty ones: none)."""
    if act.shape[0] == 0 or x0.shape[0] != f_cur.shape[0] or mus0.shape[0] != mus.shape[0]:
        return False
    f_cur[:] = x0
    for s in range(act.shape[0]):
        mus[act[s]] = mus0[act[s]]
    for p in range(free.shape[0]):
        x_prev[p] = x0[free[p]]
    return True


@njit(cache=True, nogil=True)
def _take(sol, free, neq, act, f, mus):
    """A KKT solve's ``sol`` (free cables, equations, held cones) into ``f`` and ``mus``, in place;
    returns the equations' multipliers."""
    nf = free.shape[0]
    for p in range(nf):
        f[free[p]] = sol[p]
    for s in range(act.shape[0]):
        mus[act[s]] = sol[nf + neq + s]
    return sol[nf:nf + neq].copy()


@njit(cache=True, nogil=True)
def _pulling(mus, act):
    """Whether a held cone (``act``) has a negative multiplier: it pulls the force inwards."""
    for s in range(act.shape[0]):
        if mus[act[s]] < 0.0:
            return True
    return False


@njit(cache=True, nogil=True)
def _fixed_point(state, lb, ub):
    """The cables that ``state`` fixes at their bounds (zero on the free ones) and the free cables'
    indices: ``(f, free)``."""
    n = state.shape[0]
    f = np.zeros(n)
    nf = 0
    for i in range(n):
        if state[i] == 1:
            f[i] = lb[i]
        elif state[i] == 2:
            f[i] = ub[i]
        else:
            nf += 1
    free = np.empty(nf, dtype=np.int64)
    t = 0
    for i in range(n):
        if state[i] == 0:
            free[t] = i
            t += 1
    return f, free


@njit(cache=True, nogil=True)
def _held(cact):
    """The indices of the cones held on their surface (``cact`` true)."""
    na = 0
    for k in range(cact.shape[0]):
        if cact[k]:
            na += 1
    act = np.empty(na, dtype=np.int64)
    t = 0
    for k in range(cact.shape[0]):
        if cact[k]:
            act[t] = k
            t += 1
    return act


@njit(cache=True, nogil=True)
def _linear_rows(H, g, A, b, reg, free, Hf, Af, K, rhs):
    """The rows of the free cables and of the equations in the KKT system ``K`` (zeros on entry) and
    its right-hand side: ``[[H_FF + diag(reg_F), A_F^T], [A_F, 0]]`` and ``[-(g + H f_fixed)_F, b -
    A f_fixed]`` (``Hf``, ``Af``: the fixed cables' products)."""
    nf = free.shape[0]
    neq = A.shape[0]
    for p in range(nf):
        i = free[p]
        for q in range(nf):
            K[p, q] = H[i, free[q]]
        K[p, p] += reg[i]
        for r in range(neq):
            K[p, nf + r] = A[r, i]
            K[nf + r, p] = A[r, i]
        rhs[p] = -(g[i] + Hf[i])
    for r in range(neq):
        rhs[nf + r] = b[r] - Af[r]


@njit(cache=True, nogil=True)
def _cone_rows(G, gc, ax, tn, state, f, f_cur, have_cur, free, neq, act, mus, dirs, K, rhs):
    """The held cones' rows of the KKT system: each cone's surface linearised along its direction
    ``dirs[k]``. From the second Newton step on (``have_cur``) each direction is renewed from the
    cone's force at ``f_cur`` (in ``dirs``) and the surface's curvature, weighted by the cone's
    multiplier, is added to the free cables' block. False when a held cone's force lies on its axis
    (no surface direction: :data:`VANISHED`)."""
    n = f.shape[0]
    nf = free.shape[0]
    na = act.shape[0]
    for s in range(na):
        k = act[s]
        d0, d1, d2 = dirs[k, 0], dirs[k, 1], dirs[k, 2]
        if have_cur:
            F = gc[k] + G[k] @ f_cur
            al = ax[k, 0] * F[0] + ax[k, 1] * F[1] + ax[k, 2] * F[2]
            p0, p1, p2 = F[0] - al * ax[k, 0], F[1] - al * ax[k, 1], F[2] - al * ax[k, 2]
            nrm = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2)
            if nrm <= 1e-300:
                return False
            d0, d1, d2 = p0 / nrm, p1 / nrm, p2 / nrm
            dirs[k, 0], dirs[k, 1], dirs[k, 2] = d0, d1, d2
            mu = mus[k]
            if mu > 0.0:
                # curvature mu G^T (I - a a^T - d d^T) G / |F_perp| = mu/|F_perp| v v^T with
                # v = G^T e, e = a x d (the projector is rank one: e e^T)
                e0 = ax[k, 1] * d2 - ax[k, 2] * d1
                e1 = ax[k, 2] * d0 - ax[k, 0] * d2
                e2 = ax[k, 0] * d1 - ax[k, 1] * d0
                v = e0 * G[k, 0] + e1 * G[k, 1] + e2 * G[k, 2]
                sc = mu / nrm
                # centred at f_cur: + 1/2 (f - f_cur)^T D (f - f_cur); on the free cables the
                # gradient gains D (f_fixed - f_cur) restricted to free rows
                vdf = 0.0
                for i in range(n):
                    if state[i] != 0:
                        vdf += v[i] * (f[i] - f_cur[i])
                    else:
                        vdf -= v[i] * f_cur[i]
                for p in range(nf):
                    vp = sc * v[free[p]]
                    for q in range(nf):
                        K[p, q] += vp * v[free[q]]
                    rhs[p] -= vp * vdf
        w0 = d0 - tn[k] * ax[k, 0]
        w1 = d1 - tn[k] * ax[k, 1]
        w2 = d2 - tn[k] * ax[k, 2]
        row = w0 * G[k, 0] + w1 * G[k, 1] + w2 * G[k, 2]
        rr = -(w0 * gc[k, 0] + w1 * gc[k, 1] + w2 * gc[k, 2])
        for i in range(n):
            if state[i] != 0:
                rr -= row[i] * f[i]
        for p in range(nf):
            K[p, nf + neq + s] = row[free[p]]
            K[nf + neq + s, p] = row[free[p]]
        rhs[nf + neq + s] = rr
    return True


@njit(cache=True, nogil=True, inline="always")
def _solve_rows(K, rhs, nf, neq, na, square):
    """The KKT system's solution ``(sol, LU, perm, lu_ok)``: at a vertex (as many free cables as
    equations and held cones) through the rows alone (:func:`._kkt_linalg.vertex_solve_lu`, whose
    factors come back), else, when square, through the rows' Schur complement where the free
    cables' block is diagonal (:func:`._kkt_linalg.schur_solve`) and by LU where it is not, and by
    :func:`._kkt_linalg.determined_solve` when not square (then ``lu_ok`` is false; where that finds
    the free cables' columns dependent, by the Schur complement if their block is diagonal)."""
    if nf == neq + na:
        return vertex_solve_lu(K, rhs, nf, square)
    if square:
        sol, ok = schur_solve(K, rhs, nf)
        if ok:
            return sol, np.empty((0, 0)), np.empty(0, dtype=np.int64), False
    sol = kkt_solve(K, rhs, nf, square) if square else determined_solve(K, rhs, nf)
    if not square and not _finite(sol):
        # free cables whose columns are themselves dependent (two along one line: the neck's pitch)
        # leave the equations short of determining them; where the free block is diagonal the
        # rows' Schur complement still solves the system, a dependent row's multiplier zero
        alt, ok = schur_solve(K, rhs, nf)
        if ok:
            sol = alt
    return sol, np.empty((0, 0)), np.empty(0, dtype=np.int64), False


@njit(cache=True, nogil=True)
def _solve_refined(K, rhs, nf, neq, na, square, reg, free, flat):
    """:func:`_solve_rows`, then, where a free cable has no curvature (``flat``), :func:`_refine`."""
    K0 = K.copy() if flat else K
    sol, LU, perm, lu_ok = _solve_rows(K, rhs, nf, neq, na, square)
    if flat and _finite(sol):
        _refine(K0, sol, reg, free, nf, neq, na, square)
    return sol, LU, perm, lu_ok


@njit(cache=True, nogil=True)
def _flat(H, free):
    """Whether a free cable has no curvature (``H_ii = 0``): the objective does not see it, so its
    Tikhonov term is not negligible beside its gradient (:func:`_refine`)."""
    for p in range(free.shape[0]):
        if H[free[p], free[p]] == 0.0:
            return True
    return False


@njit(cache=True, nogil=True)
def _finite(x):
    for i in range(x.shape[0]):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(cache=True, nogil=True)
def _refine(K, sol, reg, free, nf, neq, na, square):
    """One step of iterative refinement of ``sol`` toward the KKT system without the Tikhonov terms
    (``K`` holds them: ``K sol = rhs``, so the system without them leaves the residual ``reg_F
    sol_F``): ``sol += K^-1 [reg_F sol_F; 0]``, in place. A free cable the objective does not see
    (``H_ii = 0``: the shoulder's unweighted reserve actuators) has the term ``reg_rel`` times the
    objective's scale, and its residual ``reg_i f_i`` then stood above the check of stationarity
    although the equations determine the cable; the step removes it to ``reg^2``. Along a flat
    ridge of optima (the system without the terms is singular), the solved point is the one nearest
    the origin in the ``reg`` norm, where this residual is orthogonal to the ridge, so the step
    leaves it there."""
    r = np.zeros(K.shape[0])
    for p in range(nf):
        r[p] = reg[free[p]] * sol[p]
    dz = _solve_rows(K, r, nf, neq, na, square)[0]
    for i in range(sol.shape[0]):
        sol[i] += dz[i]


@njit(cache=True, nogil=True)
def _settled(sol, x_prev, f, G, gc, ax, tn, act, step_tol, last_step, settle_tol):
    """Whether the Newton steps on the cone surfaces have settled, and this step's size
    ``(settled, step)``; the KKT check that follows decides in every case. Settled:

    - the free cables' step from ``x_prev`` to ``sol`` (relative) is below ``step_tol``;
    - or the steps converge quadratically (this one below the last one, ``last_step``) and the next
      one, predicted as this one squared times their rate (this step over the last one squared, at
      least one), is below ``step_tol``: the solve it would take moves the point by less than that
      (on MyoSuite's arm the steps run 2e-3, 2e-6, 1e-12, and the third solve is saved). A rate
      below one is not trusted: on the human arm a step of 2.3e-5 follows one of 2.7e-2 (a rate of
      0.03) and the next one is larger than that rate predicts, enough for its least-norm answer to
      fail the check of stationarity (``tests/test_warm_fast.py``'s instants). The prediction is
      trusted only with every held cone on its surface to ``settle_tol`` of ``|F|``
      (``Settings.active_set_settle``, a hundredth of the active-set check's ``surface_tol``): the
      step is relative to every free cable, the surface to the cone's own force, which may be a small
      part of them (a large chain's tip), and a point the check accepts on the surface to
      ``surface_tol`` would be another chain's point only to that;
    - or, on an ill-conditioned system whose rounding floor is above ``step_tol``, the step is below
      1e-8 with every held cone on its surface to 1e-11 of ``|F|``."""
    dx = 0.0
    xx = 0.0
    for p in range(x_prev.shape[0]):
        dx += (sol[p] - x_prev[p]) ** 2
        xx += sol[p] ** 2
    step = np.sqrt(dx) / (1.0 + np.sqrt(xx))
    if step <= step_tol:
        return True, step
    if 0.0 < last_step and step <= last_step and step * step * max(1.0, step / last_step ** 2) <= step_tol \
            and _on_surfaces(f, G, gc, ax, tn, act, settle_tol):
        return True, step
    return step <= 1e-8 and _on_surfaces(f, G, gc, ax, tn, act, 1e-11), step
