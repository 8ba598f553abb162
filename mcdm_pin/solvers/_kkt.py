r"""Compiled kernels of the active-set solver (:mod:`.active_set`): block principal pivoting over
active sets (:func:`active_set_run`) until a verified KKT point, from a guess of the active set.

Each active set is solved with its bounds and cones as equations (:func:`._kkt_eq.eq_solve`, whose
small dense systems are :mod:`._kkt_linalg`'s) and checked against the KKT conditions of the full
problem (:func:`._kkt_verify.verify`), which also say what to exchange next.

The arithmetic is small (a KKT system of ~50 unknowns on the neck); written with numpy its cost was
the per-call overhead of ~100 array operations per try, so the whole pivoting loop runs compiled.
The state of a cable is an int8 code: 0 free, 1 at its lower bound, 2 at its upper bound.
"""

from __future__ import annotations

import numpy as np
from ..jit import njit

from ._kkt_eq import DROP, NO_CONVERGENCE, OK, SINGULAR, VANISHED, eq_solve
from ._kkt_linalg import lu_apply_t
from ._kkt_rank import equation_rows, restore_rank
from ._kkt_verify import KKT_EOM, KKT_OPTIMAL, KKT_PIVOT, KKT_STATIONARY, KKT_SURFACE, verify
from ._structs import ActiveSetRun

# active_set_run codes (besides OPTIMAL = 0 and the eq_solve / verify failures, shifted)
FOUND, CYCLE, PIVOT_LIMIT = 0, 10, 11
REASONS = {SINGULAR: "singular KKT system", NO_CONVERGENCE: "Newton steps on the cone surfaces did not converge",
           VANISHED: "a cone's force vanished", 20 + KKT_EOM: "equation of motion not met",
           20 + KKT_STATIONARY: "not stationary",
           20 + KKT_SURFACE: "a held cone's force off its surface",
           CYCLE: "the active set cycles", PIVOT_LIMIT: "no verified point within the pivot limit"}


@njit(cache=True, nogil=True)
def next_guess(state, grad, keep_rel):
    """The next instant's guess of the bounds from a verified answer's: a variable whose multiplier
    (``grad``, > 0 at a lower bound) is below ``keep_rel`` of the largest is guessed free."""
    gmx = 0.0
    for i in range(grad.shape[0]):
        gmx = max(gmx, abs(grad[i]))
    thr = keep_rel * max(gmx, 1e-300)
    nxt = state.copy()
    for i in range(state.shape[0]):
        if (state[i] == 1 and not grad[i] > thr) or (state[i] == 2 and not grad[i] < -thr):
            nxt[i] = 0
    return nxt


@njit(cache=True, nogil=True)
def tikhonov(H, g, ub, reg_rel):
    """The Tikhonov terms ``reg`` (n,) of :func:`._kkt_eq.eq_solve`: ``reg_rel`` times each variable's own
    curvature ``H_ii``, at least ``1e-8`` of the objective's scale ``s = max(max H_ii, max |g_i| /
    (1 + max |u_i|))``; ``reg_rel s`` for a variable the objective does not see (``H_ii = 0``, a
    zero row of a positive semidefinite ``H``).

    Relative to each variable's own curvature, the stationarity residual ``reg_i f_i`` stays
    ~``reg_rel`` of that variable's gradient ``H_ii f_i`` whatever the spread of the diagonal: with
    one term ``reg_rel s`` for all (MyoSuite's arm, scaled: the muscles' ``2 w / g^2`` from 4e-7 to
    381 next to the reserves' 200), the strong muscles' residual ``reg_rel s f_i`` (``s f_i`` 1e4-7e4
    times the gradient's scale) fails the check of stationarity (1e-8 of that scale) at the optimum's
    active set, and the interior-point method's crossover is refused (a fifth of the arm's instants
    with the glenohumeral cone then ran on to a numerical breakdown).
    """
    n = H.shape[0]
    hmax = 0.0  # H's largest entry: for a positive semidefinite H, its largest diagonal entry
    gmax = 0.0
    umax = 0.0
    for i in range(n):
        hmax = max(hmax, H[i, i])
        gmax = max(gmax, abs(g[i]))
        if np.isfinite(ub[i]):
            umax = max(umax, abs(ub[i]))
    scale = max(hmax, gmax / (1.0 + umax))
    reg = np.empty(n)
    for i in range(n):
        reg[i] = reg_rel * (max(H[i, i], 1e-8 * scale) if H[i, i] > 0.0 else scale)
    return reg


@njit(cache=True, nogil=True)
def active_set_run(qp, cones, state0, cact0, cdir0, limits, x0, mus0):
    """Block principal pivoting on ``qp`` (a :class:`._structs.QP`) with ``cones``
    (:class:`._structs.Cones`) from the guess ``(state0, cact0, cdir0)`` and its point ``x0``, ``mus0``
    (or empty; later sets start from the set before: :func:`._kkt_eq.eq_solve`) until a verified KKT
    point (:func:`.active_set.try_active_set`), within ``limits`` (:class:`._structs.Limits`; the
    Tikhonov terms relative to each variable's curvature: :func:`tikhonov`).

    Every violated condition is exchanged at once (a block pivot) while the number of violations
    falls (Judice and Pires allow a few steps without progress; here none: on the neck that wandered
    off and cycled); then, or when a block pivot leaves a singular system (too many cables fixed for
    the equation of motion), only the worst violation changes (Judice and Pires' safeguard).

    Returns an :class:`._structs.ActiveSetRun`: ``code`` :data:`FOUND` or a key of :data:`REASONS`; at
    :data:`FOUND`, the multipliers (``mus`` the cones', ``grad`` the bounds', > 0 at a lower bound,
    ``y`` the equations'), the optimum's active set ``(state, cact, dirs)`` and the next instant's
    guess ``next_state`` (:func:`next_guess`); ``sets`` the active sets tried, ``solves`` the KKT
    systems solved (one per active set without cones, one per Newton step with them).
    """
    n, neq, nc, max_pivots = qp.H.shape[0], qp.A.shape[0], cones.G.shape[0], limits.max_pivots
    reg = tikhonov(qp.H, qp.c, qp.ub, limits.reg_rel)
    state = _held_at_finite(state0, qp.lb, qp.ub)
    cact, cdir = cact0.copy(), cdir0.copy()
    hist_s, hist_c = np.zeros((max_pivots, n), dtype=np.int8), np.zeros((max_pivots, nc), dtype=np.bool_)
    f, y, mus, grad = np.zeros(n), np.zeros(neq), np.zeros(nc), np.zeros(n)
    # the last verified-but-not-optimal point, to step back to when a block pivot fails
    have_prev, last_was_block, blocks_ok = False, False, True
    prev_state, prev_cact, prev_grad, prev_dirs, prev_cone_dir, prev_in, prev_out = _memory(state, cact, cdir)
    prev_kind, prev_idx = np.int64(-1), np.int64(-1)
    best_ninf, solves, none = n + nc + 1, 0, np.zeros(0)
    px, pm = x0, mus0  # where each set's Newton steps start: the guess's point, then the last set's
    for it in range(max_pivots):
        if _tried_before(hist_s, hist_c, it, state, cact):
            return ActiveSetRun(CYCLE, f, mus, grad, state, cact, cdir, state, y, it, solves)
        code, f, y, mus, dirs, ns, LU, perm, lu_ok = eq_solve(qp, cones, state, cact, cdir, limits, reg, px, pm)
        solves += ns
        if code == DROP:  # a cone pulls the force inwards: it is not active
            _drop_pulling(cact, mus)
            px, pm = f, mus
            continue
        if code == SINGULAR and have_prev and last_was_block:
            # the block pivot fixed too much: step back and change only the worst violation
            state, cact = _single_pivot(prev_state, prev_cact, prev_grad, prev_kind, prev_idx,
                                        prev_in, prev_out, neq, nc, n)
            cdir = _next_dirs(prev_in, prev_cone_dir, prev_dirs, nc)
            # from now on one change at a time (finite for strictly convex QPs)
            last_was_block = blocks_ok = False
            px, pm = none, none
            continue
        if code != OK and code != NO_CONVERGENCE:
            return ActiveSetRun(code, f, mus, grad, state, cact, cdir, state, y, it + 1, solves)
        # Newton steps that did not settle still say which cables and cones to exchange; the point
        # itself is accepted only if it passes the full KKT check like any other
        (vcode, to_lower, to_upper, release, cone_in, cone_dir, cone_out, grad, worst_kind,
         worst_idx) = verify(qp, cones, state, f, y, cact, mus, limits)
        if vcode == KKT_OPTIMAL:
            return ActiveSetRun(FOUND, f, mus, grad, state, cact, dirs, next_guess(state, grad, limits.keep_rel), y,
                                it + 1, solves)
        if vcode != KKT_PIVOT:
            return ActiveSetRun(20 + vcode, f, mus, grad, state, cact, cdir, state, y, it + 1, solves)
        have_prev = True
        _remember(prev_state, prev_cact, prev_grad, prev_dirs, prev_cone_dir, prev_in, prev_out, state, cact, grad,
                  dirs, cone_dir, cone_in, cone_out)
        prev_kind, prev_idx = worst_kind, worst_idx
        ninf = _violations(release, to_lower, to_upper, cone_in, cone_out)
        # a block pivot only while the number of violations keeps falling
        block = blocks_ok and ninf < best_ninf
        best_ninf = min(best_ninf, ninf)
        state, cact, cdir, last_was_block = _pivot(block, qp, cones, state, cact, dirs, grad,
                                                   (release, to_lower, to_upper, cone_in, cone_out, cone_dir),
                                                   worst_kind, worst_idx, LU, perm, lu_ok)
        px, pm = f, mus
    return ActiveSetRun(PIVOT_LIMIT, f, mus, grad, state, cact, cdir, state, y, max_pivots, solves)


@njit(cache=True, nogil=True)
def _memory(state, cact, cdir):
    """Room for the last verified-but-not-optimal active set (:func:`_remember`): ``(state, cact,
    grad, dirs, cone_dir, cone_in, cone_out)``."""
    n = state.shape[0]
    nc = cact.shape[0]
    return (state.copy(), cact.copy(), np.zeros(n), cdir.copy(), cdir.copy(), np.zeros(nc, dtype=np.bool_),
            np.zeros(nc, dtype=np.bool_))


@njit(cache=True, nogil=True)
def _remember(prev_state, prev_cact, prev_grad, prev_dirs, prev_cone_dir, prev_in, prev_out, state, cact, grad,
              dirs, cone_dir, cone_in, cone_out):
    """Copy a verified-but-not-optimal active set and its exchanges into :func:`_memory`'s arrays."""
    prev_state[:] = state
    prev_cact[:] = cact
    prev_grad[:] = grad
    prev_dirs[:] = dirs
    prev_cone_dir[:] = cone_dir
    prev_in[:] = cone_in
    prev_out[:] = cone_out


@njit(cache=True, nogil=True)
def _drop_pulling(cact, mus):
    """Let go (in ``cact``) of the held cones whose multiplier is negative: they pull the force
    inwards, so they are not active."""
    for k in range(cact.shape[0]):
        if cact[k] and mus[k] < 0.0:
            cact[k] = False


@njit(cache=True, nogil=True, inline="always")
def _pivot(block, qp, cones, state, cact, dirs, grad, changes, worst_kind, worst_idx, LU, perm, lu_ok):
    """The next active set: every violation exchanged at once when ``block`` and it leaves enough
    cables free (:func:`_block_pivot`), else only the worst (:func:`_one_change`); ``changes``:
    :func:`._kkt_verify.verify`'s ``(release, to_lower, to_upper, cone_in, cone_out, cone_dir)``;
    either way with the rank of the equations and the held cones' surfaces kept
    (:func:`._kkt_rank.restore_rank`; not after a vertex's ratio-test swap, which keeps it: its pivot
    element is not zero). ``(state, cact, cdir, was_block)``, ``cdir`` the held cones' surface
    directions (a cone taken: its ``cone_dir``)."""
    release, to_lower, to_upper, cone_in, cone_out, cone_dir = changes
    cdir = _next_dirs(cone_in, cone_dir, dirs, cact.shape[0])
    fits, new_state, new_cact = _block_pivot(state, cact, release, to_lower, to_upper, cone_in, cone_out,
                                             qp.A.shape[0])
    was_block, swapped = block and fits, False
    if not was_block:
        new_state, new_cact, swapped = _one_change(qp, cones, cact, dirs, state, grad, worst_kind, worst_idx,
                                                   cone_in, cone_out, LU, perm, lu_ok)
    if not swapped:
        restore_rank(qp, cones, state, new_state, grad, cact, new_cact, cdir)
    return new_state, new_cact, cdir, was_block


@njit(cache=True, nogil=True)
def _held_at_finite(state0, lb, ub):
    """``state0`` with the variables it holds at an infinite bound freed (a variable can only be held
    at a finite bound: the least-norm stage frees some bounds) and the fixed ones (``lb == ub``: the
    least-norm stage pins variables so) held."""
    state = state0.copy()
    for i in range(state.shape[0]):
        if lb[i] == ub[i] and np.isfinite(lb[i]):
            state[i] = 1
        elif (state[i] == 1 and not np.isfinite(lb[i])) or (state[i] == 2 and not np.isfinite(ub[i])):
            state[i] = 0
    return state


@njit(cache=True, nogil=True)
def _tried_before(hist_s, hist_c, it, state, cact):
    """Record the active set ``(state, cact)`` as the ``it``-th tried, and whether it is one of the
    ``it`` tried before it (the pivoting cycles)."""
    hist_s[it] = state  # (row ``it`` is not compared below)
    hist_c[it] = cact
    for h in range(it):
        same = True
        for i in range(state.shape[0]):
            if hist_s[h, i] != state[i]:
                same = False
                break
        if same:
            for k in range(cact.shape[0]):
                if hist_c[h, k] != cact[k]:
                    same = False
                    break
        if same:
            return True
    return False


@njit(cache=True, nogil=True)
def _violations(release, to_lower, to_upper, cone_in, cone_out):
    """How many conditions :func:`._kkt_verify.verify` found violated."""
    ninf = 0
    for i in range(release.shape[0]):
        ninf += release[i] + to_lower[i] + to_upper[i]
    for k in range(cone_in.shape[0]):
        ninf += cone_in[k] + cone_out[k]
    return ninf


@njit(cache=True, nogil=True)
def _block_pivot(state, cact, release, to_lower, to_upper, cone_in, cone_out, neq):
    """Every violation exchanged at once (a block pivot): ``(fits, state, cact)`` after it, ``fits``
    false when too few cables would stay free for the equations and the held cones."""
    n = state.shape[0]
    nc = cact.shape[0]
    new_state = state.copy()
    n_in = 0
    n_out = 0
    n_act = 0
    for k in range(nc):
        n_in += cone_in[k]
        n_out += cone_out[k]
        n_act += cact[k]
    for i in range(n):
        if release[i]:
            new_state[i] = 0
        if to_lower[i]:
            new_state[i] = 1
        if to_upper[i]:
            new_state[i] = 2
    new_cact = cact.copy()
    for k in range(nc):
        if cone_out[k]:
            new_cact[k] = False
        if cone_in[k]:
            new_cact[k] = True
    return n - np.count_nonzero(new_state) >= neq + n_act - n_out + n_in, new_state, new_cact


@njit(cache=True, nogil=True, inline="always")
def _one_change(qp, cones, cact, dirs, state, grad, worst_kind, worst_idx, cone_in, cone_out, LU, perm, lu_ok):
    """Only the worst violation changes: ``(state, cact, swapped)`` after it. At a vertex (as many free
    cables as equations and held cones) a cable reaching a bound swaps with the fixed cable the ratio
    test picks (:func:`_ratio_test`; ``swapped``); otherwise, or when none is eligible,
    :func:`_single_pivot`."""
    n = state.shape[0]
    neq = qp.A.shape[0]
    nc = cones.G.shape[0]
    n_act = 0
    for k in range(nc):
        n_act += cact[k]
    enter = -1
    if (worst_kind == 1 or worst_kind == 2) and n - np.count_nonzero(state) == neq + n_act:
        # at a vertex (as many free cables as equations): a dual simplex step, the fixed
        # cable to free chosen by the ratio test (keeps the other multipliers' signs)
        enter = _ratio_test(qp, cones, cact, dirs, state, grad, worst_kind, worst_idx, n_act, LU, perm, lu_ok)
    if enter >= 0:
        new_state = state.copy()
        new_state[worst_idx] = worst_kind
        new_state[enter] = 0
        return new_state, cact, True
    new_state, new_cact = _single_pivot(state, cact, grad, worst_kind, worst_idx, cone_in, cone_out, neq, nc, n)
    return new_state, new_cact, False


@njit(cache=True, nogil=True, inline="always")
def _ratio_test(qp, cones, cact, dirs, state, grad, kind, r, n_act, LU, perm, lu_ok):
    """The fixed cable whose release lets the leaving free cable ``r`` reach its bound (``kind`` 1:
    it is below its lower bound, 2: above its upper bound) at the least dual cost: min over eligible
    j of multiplier_j / |dx_r/df_j|, with ``x_F = B^-1 (rhs - col_j f_j)`` and ``B`` the square
    matrix of the equations and the ``n_act`` held cones' surface rows (:func:`._kkt_rank.equation_rows`)
    on the free cables. -1 if none is
    eligible or ``B`` is singular. ``(LU, perm)``: ``B``'s factors when ``lu_ok`` (the vertex solve
    of this active set factored the same matrix, :func:`vertex_solve_lu`), else ``B`` is solved
    afresh."""
    n = state.shape[0]
    rows = equation_rows(qp.A, qp.b, cones, cact, dirs, n_act)[0]
    m = rows.shape[0]
    free = np.flatnonzero(state == 0)
    if free.shape[0] != m:
        return -1
    pos = -1
    for q in range(m):
        if free[q] == r:
            pos = q
    if pos < 0:
        return -1
    e = np.zeros(m)
    e[pos] = 1.0
    if lu_ok and LU.shape[0] == m:
        u = lu_apply_t(LU, perm, e)  # row pos of B^-1
    else:
        B = np.empty((m, m))
        for q in range(m):
            for i in range(m):
                B[i, q] = rows[i, free[q]]
        try:
            u = np.linalg.solve(B.T, e)  # row pos of B^-1
        except Exception:  # noqa: BLE001 (singular basis)
            return -1
    need_up = kind == 1  # x_r must rise to its lower bound
    best, enter = np.inf, -1
    for j in range(n):
        if state[j] == 0:
            continue
        d = 0.0  # dx_r / df_j = -(B^-1 col_j)_pos
        for i in range(m):
            d -= u[i] * rows[i, j]
        # f_j may only move away from its bound: up from a lower one, down from an upper one
        rate = d if state[j] == 1 else -d
        if (rate > 1e-12) if need_up else (rate < -1e-12):
            lam = grad[j] if state[j] == 1 else -grad[j]
            ratio = max(lam, 0.0) / abs(rate)
            if ratio < best:
                best, enter = ratio, j
    return enter


@njit(cache=True, nogil=True)
def _next_dirs(cone_in, cone_dir, dirs, nc):
    out = dirs.copy()
    for k in range(nc):
        if cone_in[k]:
            out[k] = cone_dir[k]
    return out


@njit(cache=True, nogil=True)
def _single_pivot(state, cact, grad, worst_kind, worst_idx, cone_in, cone_out, neq, nc, n):
    """Change only the worst violation (a bound: fix it, and no cone change; a multiplier of the
    wrong sign: free it, with the cone changes); then, if too few cables are free for the equations,
    free the least binding fixed ones (a simplex-like swap)."""
    new_state = state.copy()
    new_cact = cact.copy()
    bounds_move = worst_kind == 1 or worst_kind == 2
    if bounds_move:
        new_state[worst_idx] = worst_kind
    elif worst_kind == 0:
        new_state[worst_idx] = 0
    n_act = 0
    for k in range(nc):
        if not bounds_move:
            if cone_out[k]:
                new_cact[k] = False
            if cone_in[k]:
                new_cact[k] = True
        n_act += new_cact[k]
    need = neq + n_act
    n_fixed = 0
    for i in range(n):
        if new_state[i] != 0 and i != worst_idx:
            n_fixed += 1
    fixed = np.empty(n_fixed, dtype=np.int64)
    lam = np.empty(n_fixed)
    t = 0
    for i in range(n):
        if new_state[i] != 0 and i != worst_idx:
            fixed[t] = i
            lam[t] = grad[i] if new_state[i] == 1 else -grad[i]
            t += 1
    order = np.argsort(lam, kind="mergesort")
    for t in range(n_fixed):
        if n - np.count_nonzero(new_state) >= need:
            break
        new_state[fixed[order[t]]] = 0
    return new_state, new_cact
