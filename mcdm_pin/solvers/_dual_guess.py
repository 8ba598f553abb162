r"""An active-set guess from the dual of a separable QP (:func:`dual_guess`), for the warm active set
(:class:`.active_set.WarmActiveSet`) where its own guess fails, and for a cold instant
(:class:`.active_set.DualActiveSet`, from zero multipliers).

For ``min 1/2 x^T D x + c^T x`` subject to ``A x = b`` and ``l <= x <= u`` with ``D`` diagonal and
positive (case 1's ``f^T f``, the muscles' activations), the minimiser of the Lagrangian
``L(x, y) = 1/2 x^T D x + c^T x + y^T (A x - b)`` over the box is explicit,
``x(y) = clip(-(A^T y + c) / D, l, u)``, and the dual function ``g(y) = L(x(y), y)`` is concave,
piecewise quadratic and once differentiable, with ``grad g = A x(y) - b``. Newton's method on it
(Qi and Sun's semismooth Newton method: the generalised Hessian is ``-A_F D_F^{-1} A_F^T`` over the
variables ``F`` strictly inside their bounds) with an exact line search (the dual along a ray is
piecewise quadratic: :func:`_exact_step`) climbs to the optimum's multipliers from any start; which
bound each variable meets at ``x(y)`` is then the optimum's active set, which the active-set solver
solves exactly and verifies.

Block principal pivoting from the last instant's active set can wander: on the neck's ``roll``
(case 1) three warm starts of 101 exchange cables for the pivot limit (50) or reach a singular
system, and the instant goes on to the interior-point method. From the last instant's multipliers
the dual method reaches those instants' active sets in a few Newton steps, each a Cholesky
factorisation of an ``m x m`` matrix (``m`` the equations), and the active-set solver verifies them
with one KKT solve (docs/speed.md, "The warm start's dual guess").

Where the free variables' columns do not span the equations (a degenerate optimum, or a guess on
the way to one), ``A_F D_F^{-1} A_F^T`` is singular; a multiple ``reg`` of ``A D^{-1} A^T`` (and a
floor of ``1e-14`` of its mean diagonal, for equations that are themselves dependent) keeps the
Newton matrix positive definite, and the line search makes every step an ascent. (A multiple of
the free part's own mean diagonal instead left more of 200 random problems short of the stopping
test within 60 steps, 6 against 3 from zero multipliers.) Where the free set changes at every step
near a vertex the method may need tens of steps; its guess is then often right all the same.
Between steps a few variables enter or leave ``F``: the Newton matrix is updated by their outer
products (:func:`_newton_matrix`). An infeasible problem has an unbounded dual: the method stops at
its step limit and the guess it returns fails its verification, as any wrong guess does.
No sum here is reassociated (``dot_in_order``; the Cholesky factor and solve are inlined and take
this module's flags, which have no ``fastmath``), so the compiled and the uncompiled guesses, and
their step counts, are the same to the bit.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit
from ._ipm_linalg import dot_in_order, inf_norm
from ._kkt_linalg import chol_apply, chol_lower


@njit(cache=True, nogil=True)
def _primal(AT, c, d, lb, ub, y, x):
    """``x = clip(-(A^T y + c) / d, lb, ub)`` in place (``AT``: ``A^T``, C-ordered): the minimiser of
    the Lagrangian over the box at ``y``."""
    n, m = AT.shape
    for j in range(n):
        s = c[j]
        for i in range(m):
            s += AT[j, i] * y[i]
        v = -s / d[j]
        v = lb[j] if v < lb[j] else (ub[j] if v > ub[j] else v)
        x[j] = v


@njit(cache=True, nogil=True)
def _outer_lower(M, v, w):
    """``M += w v v^T``, lower triangle."""
    m = v.shape[0]
    for i in range(m):
        a = w * v[i]
        for k in range(i + 1):
            M[i, k] += a * v[k]


@njit(cache=True, nogil=True)
def dual_guess(d, c, A, b, lb, ub, y0, max_steps, reg, tol):
    """The active set of ``x(y)`` after at most ``max_steps`` Newton steps on the dual from ``y0``
    (the module docstring; ``d > 0``). Stops when ``|A x(y) - b|`` is within ``tol`` of the problem's
    size: ``x(y)`` minimises the Lagrangian over the box, so it is then the optimum, and the set read
    off it the optimum's active set. (A variable whose bound holds with a zero multiplier may read
    free at one step and bound at the next: the exact line search often stops on such a kink, where
    a test that waits for the set to repeat cycles.) Returns ``(state, steps, converged)``:
    ``state`` int8 per variable (0 free, 1 at its lower bound, 2 at its upper bound, as
    the active-set solver takes it), the Newton steps made, and whether the stopping test held."""
    m, n = A.shape
    y = y0.copy()
    x = np.empty(n)
    state = np.zeros(n, dtype=np.int8)
    AT = np.ascontiguousarray(A.T)
    Bt, S, floor = _metric(AT, d)
    size = inf_norm(b)
    amax = 0.0
    for j in range(n):
        for i in range(m):
            amax = max(amax, abs(AT[j, i]))
    _primal(AT, c, d, lb, ub, y, x)
    r = np.empty(m)
    M = np.empty((m, m))
    free_sum = np.zeros((m, m))  # the lower triangle of A_F D_F^-1 A_F^T over ``inside``
    inside = np.zeros(n, dtype=np.bool_)
    work = (np.empty(n), np.empty(n), np.empty(2 * n), np.empty(2 * n))
    steps = 0
    while True:
        xmax = _read_state(x, lb, ub, state)
        rmax = _residual(AT, x, b, r)  # grad g
        if rmax <= tol * max(size, amax * xmax, 1e-300):
            return state, steps, True
        if steps >= max_steps:
            return state, steps, False
        _newton_matrix(M, free_sum, inside, S, Bt, state, reg, floor)
        ok, _ = chol_lower(M, m, 0.0)
        if not ok:
            return state, steps, False
        _exact_step(A, c, d, lb, ub, y, x, chol_apply(M, r), r, work)
        steps += 1


@njit(cache=True, nogil=True)
def _metric(AT, d):
    """``(Bt, S, floor)``: the rows ``Bt = A^T D^-1/2``, the lower triangle of ``S = A D^-1 A^T`` (the
    regularising term's matrix) as the sum of their outer products, and the floor ``1e-14`` of its
    mean diagonal."""
    n, m = AT.shape
    Bt = np.empty((n, m))
    for j in range(n):
        w = 1.0 / np.sqrt(d[j])
        for i in range(m):
            Bt[j, i] = AT[j, i] * w
    S = np.zeros((m, m))
    for j in range(n):
        _outer_lower(S, Bt[j], 1.0)
    trace = 0.0
    for i in range(m):
        trace += S[i, i]
    return Bt, S, 1e-14 * trace / max(m, 1) + 1e-300


@njit(cache=True, nogil=True)
def _newton_matrix(M, free_sum, inside, S, Bt, state, reg, floor):
    """The lower triangle of ``A_F D_F^-1 A_F^T + reg S + floor I`` in ``M`` (``F``: the free
    variables of ``state``). ``free_sum`` holds the first term over the variables ``inside`` (the last
    step's free ones): it is brought up to date by the outer products of the variables that entered
    or left ``F`` (a few per step), or summed again where more changed than stayed free."""
    m, n = M.shape[0], state.shape[0]
    changed, free = 0, 0
    for j in range(n):
        free += state[j] == 0
        changed += (state[j] == 0) != inside[j]
    if changed > free:
        free_sum[:, :] = 0.0
        for j in range(n):
            inside[j] = state[j] == 0
            if inside[j]:
                _outer_lower(free_sum, Bt[j], 1.0)
    else:
        for j in range(n):
            if (state[j] == 0) != inside[j]:
                inside[j] = state[j] == 0
                _outer_lower(free_sum, Bt[j], 1.0 if inside[j] else -1.0)
    for i in range(m):
        for k in range(i + 1):
            M[i, k] = free_sum[i, k] + reg * S[i, k]
        M[i, i] += floor


@njit(cache=True, nogil=True)
def _exact_step(A, c, d, lb, ub, y, x, step, grad, work):
    """``y`` moved in place to the maximiser of the concave dual along ``step`` (an ascent direction:
    ``grad . step > 0``), and ``x = x(y)``. Along the ray each ``x_j(t)`` is linear between the two
    values of ``t`` at which it meets its bounds, so the dual's slope ``step . (A x(t) - b)`` is
    piecewise linear and falls with ``t``: walked through those breakpoints in order, it is zero at
    the step taken, in one pass, where backtracking from the whole Newton step takes many tries from
    zero multipliers (docs/speed.md, "The cold instant's dual guess"). Where the slope stays positive
    with nothing free
    (an unbounded dual: an infeasible problem), or where rounding leaves ``step`` no ascent, the whole
    Newton step. ``x`` comes from ``A^T y + c`` moved along ``A^T step``, not from a product with the
    new ``y``. ``work``: scratch arrays (n,), (n,), (2n,), (2n,)."""
    s, q, ev_t, ev_w = work
    m, n = A.shape
    # s = A^T y + c and q = A^T step, row by row of A: each entry summed in the order of the rows,
    # the loop over the entries contiguous
    for j in range(n):
        s[j] = c[j]
        q[j] = 0.0
    for i in range(m):
        yi, si = y[i], step[i]
        for j in range(n):
            s[j] += A[i, j] * yi
            q[j] += A[i, j] * si
    sig = 0.0  # the slope's rate of change on the current stretch: -sum q_j^2 / d_j over the free j
    ne = 0
    for j in range(n):
        sj, qj = s[j], q[j]
        if qj == 0.0:
            continue
        u0, a, w = -sj / d[j], -qj / d[j], qj * qj / d[j]
        t1, t2 = ((lb[j] - u0) / a, (ub[j] - u0) / a) if a > 0.0 else ((ub[j] - u0) / a, (lb[j] - u0) / a)
        if not t2 > 0.0:  # (at or past its bound all along the ray)
            continue
        if t1 <= 0.0:
            sig -= w
        else:
            ev_t[ne], ev_w[ne] = t1, -w
            ne += 1
        if t2 < np.inf:
            ev_t[ne], ev_w[ne] = t2, w
            ne += 1
    slope = dot_in_order(grad, step)
    t, taken, found = 0.0, 1.0, slope <= 0.0
    # the breakpoints in order of t, up to the slope's zero: the earliest of those left by a scan for
    # the first 16 of them (the zero usually comes within a few of tens), the rest sorted once
    left, at, order = ne, -1, np.empty(0, dtype=np.int64)
    while not found and left > 0:
        if at < 0 and ne - left == 16:
            order, at = np.argsort(ev_t[:left]), 0
        if at >= 0:
            k = order[at]
            at += 1
        else:
            k = 0
            for e in range(1, left):
                if ev_t[e] < ev_t[k]:
                    k = e
        nxt = slope + sig * (ev_t[k] - t)
        if nxt <= 0.0 and sig < 0.0:
            taken, found = t - slope / sig, True
        else:
            slope, t = nxt, ev_t[k]
            sig += ev_w[k]
            left -= 1
            if at < 0:  # (scanned: the last one left takes its place)
                ev_t[k], ev_w[k] = ev_t[left], ev_w[left]
    if not found and sig < 0.0:
        taken = t - slope / sig
    for i in range(m):
        y[i] += taken * step[i]
    for j in range(n):
        v = -(s[j] + taken * q[j]) / d[j]
        x[j] = lb[j] if v < lb[j] else (ub[j] if v > ub[j] else v)


@njit(cache=True, nogil=True)
def _read_state(x, lb, ub, state):
    """Each variable's bound at ``x`` into ``state`` (1 lower, 2 upper, 0 free); returns ``max |x|``."""
    xmax = 0.0
    for j in range(x.shape[0]):
        xmax = max(xmax, abs(x[j]))
        state[j] = 1 if x[j] <= lb[j] else (2 if x[j] >= ub[j] else 0)
    return xmax


@njit(cache=True, nogil=True)
def _residual(AT, x, b, r):
    """``r = A x - b`` in place (``AT``: ``A^T``, C-ordered; each entry summed in the order of the
    variables, the loop over the entries contiguous); returns ``max |r|``."""
    n, m = AT.shape
    for i in range(m):
        r[i] = -b[i]
    for j in range(n):
        xj = x[j]
        for i in range(m):
            r[i] += AT[j, i] * xj
    rmax = 0.0
    for i in range(m):
        rmax = max(rmax, abs(r[i]))
    return rmax
