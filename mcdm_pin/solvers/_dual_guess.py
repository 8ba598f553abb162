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
    AT = np.ascontiguousarray(A.T)
    Bt, S, floor = _metric(AT, d)
    size = inf_norm(b)
    amax = 0.0
    for j in range(n):
        for i in range(m):
            amax = max(amax, abs(AT[j, i]))
    val = _primal(AT, c, d, lb, ub, y, x) - dot_in_order(b, y)
    r = np.empty(m)
    M = np.empty((m, m))
    work = (np.empty(m), np.empty(n))
    steps = 0
    while True:
        xmax = _read_state(x, lb, ub, state)
        rmax = _residual(A, x, b, r)  # grad g
        same = True
        for j in range(n):
            same = same and state[j] == last[j]
        if same and rmax <= tol * max(size, amax * xmax, 1e-300):
            return state, steps, True
        if steps >= max_steps:
            return state, steps, False
        last[:] = state
        _newton_matrix(M, S, Bt, state, reg, floor)
        ok, _ = chol_lower(M, m, 0.0)
        if not ok:
            return state, steps, False
        val = _line_search(AT, c, d, lb, ub, b, y, x, chol_apply(M, r), r, val, work)
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
def _newton_matrix(M, S, Bt, state, reg, floor):
    """The lower triangle of ``A_F D_F^-1 A_F^T + reg S + floor I`` in ``M`` (``F``: the free
    variables of ``state``)."""
    m = M.shape[0]
    for i in range(m):
        for k in range(i + 1):
            M[i, k] = reg * S[i, k]
        M[i, i] += floor
    for j in range(state.shape[0]):
        if state[j] == 0:
            _outer_lower(M, Bt[j], 1.0)


@njit(cache=True, nogil=True)
def _line_search(AT, c, d, lb, ub, b, y, x, step, grad, val, work):
    """Armijo's backtracking along ``step`` on the concave dual (``step`` is an ascent direction:
    ``grad . step > 0``): ``y`` and ``x`` moved in place to the first of the steps ``1, 1/2, ...``
    that gains ``1e-4`` of its slope (or the last, below ``1e-10``); returns the dual's new value.
    ``work``: scratch arrays (m,) and (n,)."""
    y_try, x_try = work
    slope = dot_in_order(grad, step)
    t = 1.0
    while True:
        for i in range(y.shape[0]):
            y_try[i] = y[i] + t * step[i]
        v = _primal(AT, c, d, lb, ub, y_try, x_try) - dot_in_order(b, y_try)
        if v >= val + 1e-4 * t * slope or t < 1e-10:
            break
        t *= 0.5
    y[:] = y_try
    x[:] = x_try
    return v


@njit(cache=True, nogil=True)
def _read_state(x, lb, ub, state):
    """Each variable's bound at ``x`` into ``state`` (1 lower, 2 upper, 0 free); returns ``max |x|``."""
    xmax = 0.0
    for j in range(x.shape[0]):
        xmax = max(xmax, abs(x[j]))
        state[j] = 1 if x[j] <= lb[j] else (2 if x[j] >= ub[j] else 0)
    return xmax


@njit(cache=True, nogil=True)
def _residual(A, x, b, r):
    """``r = A x - b`` in place; returns ``max |r|``."""
    rmax = 0.0
    for i in range(A.shape[0]):
        s = -b[i]
        for j in range(A.shape[1]):
            s += A[i, j] * x[j]
        r[i] = s
        rmax = max(rmax, abs(s))
    return rmax
