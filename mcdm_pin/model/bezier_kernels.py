r"""OpenSim's quintic Bézier curves (``SmoothSegmentedFunction``, :mod:`mcdm_pin.model.muscles_osim`)
evaluated in one compiled call: every muscle's curve at its own abscissa.

A curve is ``k`` quintic Bézier segments with control points ``px``, ``py`` (k, 6) on
``[x0, x1]``, and lines of slopes ``dydx0``, ``dydx1`` through ``(x0, y0)``, ``(x1, y1)`` beyond. At
an abscissa inside, the segment is the first whose last control abscissa is not below it; its
parameter ``u`` solves ``x(u) = x`` by Newton's method (``x(u)`` is monotone on a segment), started
from the segment's table ``x(u)`` at ``u`` on a uniform grid, interpolated linearly, and stopped
when ``|x(u) - x| <= 4 eps max(1, |x|)`` (60 steps at most); the value is ``y(u)``.

Registered with :mod:`mcdm_pin.jit` (compiled by ``mcdm-pin compile``, the same Python function until
then).
"""

from __future__ import annotations

import numpy as np

from ..jit import extending, njit

register_jitable = extending.register_jitable

EPS = 2.220446049250313e-16  # np.finfo(float).eps
NEWTON_STEPS = 60
# columns of the ends table: the curve's interval and its lines beyond
E_X0, E_X1, E_Y0, E_Y1, E_DYDX0, E_DYDX1 = range(6)
N_ENDS = 6
B5 = (1.0, 5.0, 10.0, 10.0, 5.0, 1.0)
B4 = (1.0, 4.0, 6.0, 4.0, 1.0)


@njit(cache=True, nogil=True)
def bezier_values(px, py, ends, grid, x):
    """(n,) curve ``i`` (control points ``px[i]``, ``py[i]`` (k, 6), ``ends[i]`` (6,), the start
    table ``grid[i]`` (k, G) of ``x(u)``) at ``x[i]`` (module docstring)."""
    n, k, G = px.shape[0], px.shape[1], grid.shape[2]
    out = np.empty(n)
    for i in range(n):
        xi = x[i]
        e = ends[i]
        if xi < e[E_X0]:
            out[i] = e[E_Y0] + e[E_DYDX0] * (xi - e[E_X0])
            continue
        if xi > e[E_X1]:
            out[i] = e[E_Y1] + e[E_DYDX1] * (xi - e[E_X1])
            continue
        seg = 0
        while seg < k - 1 and xi > px[i, seg, 5]:
            seg += 1
        XG = grid[i, seg]
        j = 0
        while j < G and XG[j] < xi:
            j += 1
        j = min(max(j, 1), G - 1)
        width = XG[j] - XG[j - 1]
        t = (xi - XG[j - 1]) / width if width > 0 else 0.0
        u = min(max((j - 1 + t) / (G - 1), 0.0), 1.0)
        P = px[i, seg]
        tol = 4 * EPS * max(1.0, abs(xi))
        for _ in range(NEWTON_STEPS):
            f, d = _value_and_slope(u, P)
            f -= xi
            if abs(f) <= tol:
                break
            u = min(max(u - (f / d if d != 0 else 0.0), 0.0), 1.0)
        out[i] = _value_and_slope(u, py[i, seg])[0]
    return out


@register_jitable
def _value_and_slope(u, P):
    """The quintic Bézier of control points ``P`` (6,) and its slope in ``u``."""
    s = 1.0 - u
    up = (1.0, u, u * u, u * u * u, u * u * u * u, u * u * u * u * u)
    sp = (1.0, s, s * s, s * s * s, s * s * s * s, s * s * s * s * s)
    value = 0.0
    for m in range(6):
        value += B5[m] * sp[5 - m] * up[m] * P[m]
    slope = 0.0
    for m in range(5):
        slope += B4[m] * sp[4 - m] * up[m] * (P[m + 1] - P[m])
    return value, 5.0 * slope


def warm_calls():
    """This module's kernel with example arguments of the types
    :class:`~mcdm_pin.model.muscles_osim.OpenSimMuscles` passes (registered with :mod:`mcdm_pin.jit`)."""
    P = np.linspace(0.0, 1.0, 6).reshape(1, 1, 6)
    ends = np.array([[0.0, 1.0, 0.0, 1.0, 1.0, 1.0]])
    grid = np.linspace(0.0, 1.0, 5).reshape(1, 1, 5)
    return [(bezier_values, (P, P.copy(), ends, grid, np.array([0.5])))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.bezier_kernels", warm_calls)


_register()
