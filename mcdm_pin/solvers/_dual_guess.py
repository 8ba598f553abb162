r"""An active-set guess from the dual of a separable QP (:func:`dual_guess`), for the warm active set
(:class:`.active_set.WarmActiveSet`) where its own guess fails.

For ``min 1/2 x^T D x + c^T x`` subject to ``A x = b`` and ``l <= x <= u`` with ``D`` diagonal and
positive (case 1's ``f^T f``, the muscles' activations), the minimiser of the Lagrangian
``L(x, y) = 1/2 x^T D x + c^T x + y^T (A x - b)`` over the box is explicit,
``x(y) = clip(-(A^T y + c) / D, l, u)``, and the dual function ``g(y) = L(x(y), y)`` is concave,
piecewise quadratic and once differentiable, with ``grad g = A x(y) - b``. Newton's method on it
(Qi and Sun's semismooth Newton method: the generalised Hessian is ``-A_F D_F^{-1} A_F^T`` over the
variables ``F`` strictly inside their bounds) with an Armijo line search climbs to the optimum's
multipliers from any start; which bound each variable meets at ``x(y)`` is then the optimum's
active set, which the active-set solver solves exactly and verifies.

Block principal pivoting from the last instant's active set can wander: on the neck's ``roll``
(case 1) three warm starts of 101 exchange cables for the pivot limit (50) or reach a singular
system, and the instant goes on to the interior-point method. From the last instant's multipliers
the dual method reaches those instants' active sets in a few Newton steps, each a Cholesky
factorisation of an ``m x m`` matrix (``m`` the equations), and the active-set solver verifies them
with one KKT solve (docs/speed.md, "The warm start's dual guess").

Where the free variables' columns do not span the equations (a degenerate optimum, or a guess on
the way to one), ``A_F D_F^{-1} A_F^T`` is singular; a multiple ``reg`` of ``A D^{-1} A^T`` (and a
floor of ``1e-14`` of its mean diagonal, for equations that are themselves dependent) keeps the
Newton matrix positive definite, and the line search keeps every step an ascent. (A multiple of
the free part's own mean diagonal instead left more of 200 random problems short of the stopping
test within 60 steps, 6 against 3 from zero multipliers.) Where the free set changes at every step
near a vertex the line search cuts the steps short and the method may need tens of steps; its
guess is then often right all the same. An infeasible problem has an unbounded dual: the method
stops at its step limit and the guess it returns fails its verification, as any wrong guess does.
"""

from __future__ import annotations

import numpy as np

from ..jit import njit


@njit(cache=True, nogil=True)
def _primal(AT, c, d, lb, ub, y, x):
    """``x = clip(-(A^T y + c) / d, lb, ub)`` in place (``AT``: ``A^T``, C-ordered); returns ``g(y)``
    (the module docstring's dual function, without its ``-b^T y``)."""
    n, m = AT.shape
    val = 0.0
    for j in range(n):
        s = c[j]
        for i in range(m):
            s += AT[j, i] * y[i]
        v = -s / d[j]
        v = lb[j] if v < lb[j] else (ub[j] if v > ub[j] else v)
        x[j] = v
        val += (0.5 * d[j] * v + s) * v
    return val


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
    (the module docstring; ``d > 0``). Stops when the set read off ``x(y)`` is the one of the step
    before and ``|A x(y) - b|`` is within ``tol`` of the problem's size. Returns ``(state, steps,
    converged)``: ``state`` int8 per variable (0 free, 1 at its lower bound, 2 at its upper bound, as
    the active-set solver takes it), the Newton steps made, and whether the stopping test held."""
    m, n = A.shape
    y = y0.copy()
    x = np.empty(n)
    state = np.zeros(n, dtype=np.int8)
    last = np.full(n, -1, dtype=np.int8)
    # A D^-1 A^T (the regularising term's matrix) as a sum over the variables of the outer products
    # of the rows of Bt = A^T D^-1/2, lower triangle; the Newton matrix sums the free rows alike
    AT = np.ascontiguousarray(A.T)
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
    floor = 1e-14 * trace / max(m, 1) + 1e-300
    size = 0.0
    amax = 0.0
    for i in range(m):
        size = max(size, abs(b[i]))
        for j in range(n):
            amax = max(amax, abs(A[i, j]))
    val = _primal(AT, c, d, lb, ub, y, x)
    for i in range(m):
        val -= b[i] * y[i]
    r = np.empty(m)
    M = np.empty((m, m))
    step = np.empty(m)
    y_try = np.empty(m)
    x_try = np.empty(n)
    converged = False
    steps = 0
    while True:
        xmax = 0.0
        for j in range(n):
            xmax = max(xmax, abs(x[j]))
            state[j] = 1 if x[j] <= lb[j] else (2 if x[j] >= ub[j] else 0)
        rmax = 0.0
        for i in range(m):
            s = -b[i]
            for j in range(n):
                s += A[i, j] * x[j]
            r[i] = s  # grad g
            rmax = max(rmax, abs(s))
        same = True
        for j in range(n):
            if state[j] != last[j]:
                same = False
        if same and rmax <= tol * max(size, amax * xmax, 1e-300):
            converged = True
            break
        if steps >= max_steps:
            break
        last[:] = state
        # the Newton matrix: A_F D_F^-1 A_F^T + reg A D^-1 A^T + floor I, by Cholesky (lower, in M)
        for i in range(m):
            for k in range(i + 1):
                M[i, k] = reg * S[i, k]
            M[i, i] += floor
        for j in range(n):
            if state[j] == 0:
                _outer_lower(M, Bt[j], 1.0)
        ok = True
        for k in range(m):
            s = M[k, k]
            for q in range(k):
                s -= M[k, q] * M[k, q]
            if not s > 0.0:
                ok = False
                break
            M[k, k] = np.sqrt(s)
            for i in range(k + 1, m):
                t = M[i, k]
                for q in range(k):
                    t -= M[i, q] * M[k, q]
                M[i, k] = t / M[k, k]
        if not ok:
            break
        for i in range(m):  # M step = r: forward, then back substitution
            s = r[i]
            for q in range(i):
                s -= M[i, q] * step[q]
            step[i] = s / M[i, i]
        for i in range(m - 1, -1, -1):
            s = step[i]
            for q in range(i + 1, m):
                s -= M[q, i] * step[q]
            step[i] = s / M[i, i]
        slope = 0.0
        for i in range(m):
            slope += r[i] * step[i]
        # Armijo's backtracking on the concave dual: the step is an ascent direction (slope > 0)
        t = 1.0
        while True:
            for i in range(m):
                y_try[i] = y[i] + t * step[i]
            v = _primal(AT, c, d, lb, ub, y_try, x_try)
            for i in range(m):
                v -= b[i] * y_try[i]
            if v >= val + 1e-4 * t * slope or t < 1e-10:
                break
            t *= 0.5
        y[:] = y_try
        x[:] = x_try
        val = v
        steps += 1
    return state, steps, converged
