r"""OpenSim's quintic Bézier curves (``SmoothSegmentedFunction``, :mod:`mcdm_pin.model.muscles_osim`)
evaluated in one compiled call: every muscle's curve at its own abscissa; and, for a set of Millard
muscles, the fiber, the curves and the tension range in one call (:func:`millard_range`).

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


# rows of the muscles' constants table of pennation and millard_range (each (m,)): OpenSimMuscles'
# per-muscle numbers
(K_LS, K_H, K_PEN_MIN, K_FLOOR_ALONG, K_MIN_FIBER, K_PENNATE, K_MAX_PENNATION, K_SIN_MAX, K_SLACK_BELOW, K_LO,
 K_SPEED_SCALE, K_F0, K_DAMPING, K_A_MIN, K_A_MAX) = range(15)
N_MILLARD_ROWS = 15


@register_jitable
def _pennation_one(ell, ell_dot, k, i):
    """Muscle ``i``'s fiber at muscle-tendon length ``ell`` and speed ``ell_dot`` (rigid tendon):
    ``(lf, lf_m, cos_m, dl_m, clamped)``, the fiber length along the pennation model without its
    floor, Millard's fiber length (the pennation model's floor, at least the minimum fiber), its
    pennation's cosine (the angle's limits), its fiber speed (0 when slack or clamped) and Millard's
    clamp (no force). ``k`` the constants table (rows ``K_*``)."""
    along = ell - k[K_LS, i]
    h = k[K_H, i]
    lf = np.sqrt(along * along + h * h)
    pen_min, min_fiber, max_pen = k[K_PEN_MIN, i], k[K_MIN_FIBER, i], k[K_MAX_PENNATION, i]
    lf_m = max(lf if along >= k[K_FLOOR_ALONG, i] else pen_min, min_fiber)
    sin_m = h / lf_m
    pennate = k[K_PENNATE, i] != 0.0
    phi = np.arcsin(min(sin_m, 1.0)) if pennate and lf_m > pen_min else max_pen
    if sin_m >= k[K_SIN_MAX, i]:
        phi = max_pen
    if not pennate:
        phi = 0.0
    cos_m = np.cos(phi)
    dl_m = 0.0 if ell - lf_m * cos_m < k[K_SLACK_BELOW, i] else ell_dot * cos_m
    clamped = (lf_m <= min_fiber and dl_m <= 0) or lf_m < min_fiber
    if clamped:
        dl_m = 0.0
    return lf, lf_m, cos_m, dl_m, clamped


@njit(cache=True, nogil=True)
def pennation(ell, ell_dot, k):
    """(5, m) :func:`_pennation_one` of every muscle: ``lf``, ``lf_m``, ``cos_m``, ``dl_m`` and
    ``clamped`` (1.0 or 0.0), for :meth:`mcdm_pin.model.muscles_osim.OpenSimMuscles.fiber`."""
    m = ell.shape[0]
    out = np.empty((5, m))
    for i in range(m):
        lf, lf_m, cos_m, dl_m, clamped = _pennation_one(ell[i], ell_dot[i], k, i)
        out[0, i], out[1, i], out[2, i], out[3, i] = lf, lf_m, cos_m, dl_m
        out[4, i] = 1.0 if clamped else 0.0
    return out


@njit(cache=True, nogil=True)
def millard_range(ell, ell_dot, k, px, py, ends, grid):
    """:meth:`mcdm_pin.model.muscles_osim.OpenSimMuscles.force_range` of muscles that are all
    Millard's, in one pass: the fiber (:func:`_pennation_one`), the three curves
    (:func:`bezier_values` on the stacked tables, at ``(l, v, l)``) and the tension range. ``ell``,
    ``ell_dot`` (m,) muscle-tendon lengths and speeds, ``k`` (:data:`N_MILLARD_ROWS`, m) the
    constants. Returns (4, m): passive, gain, f_min, f_max."""
    m = ell.shape[0]
    x = np.empty(3 * m)
    cos_a = np.empty(m)
    live = np.empty(m, dtype=np.bool_)
    for i in range(m):
        _, lf_m, cos_m, dl_m, clamped = _pennation_one(ell[i], ell_dot[i], k, i)
        x[i] = lf_m / k[K_LO, i]
        x[m + i] = dl_m / k[K_SPEED_SCALE, i]
        x[2 * m + i] = x[i]
        cos_a[i] = cos_m
        live[i] = not clamped
    curves = bezier_values(px, py, ends, grid, x)
    out = np.empty((4, m))
    for i in range(m):
        out[0, i], out[1, i], out[2, i], out[3, i] = _range_one(
            k, i, curves[i], curves[m + i], curves[2 * m + i], x[m + i], cos_a[i], live[i], True)
    return out


@register_jitable
def _range_one(k, i, fl, fv, fp, v, cos_a, live, saturate):
    """Muscle ``i``'s ``(passive, gain, f_min, f_max)`` from its curves ``fl``, ``fv``, ``fp`` at the
    normalised fiber speed ``v``, its pennation's cosine and whether it is live (not clamped): the
    passive force with the fiber damping, the active gain, and the tensions at ``a_min`` and ``a_max``
    (``k`` the constants table); ``saturate``: at least 0 (OpenSim saturates Millard's rigid fiber
    there)."""
    f0 = k[K_F0, i]
    passive = f0 * (fp + k[K_DAMPING, i] * v) * cos_a if live else 0.0
    gain = f0 * fl * fv * cos_a if live else 0.0
    lo, hi = passive + gain * k[K_A_MIN, i], passive + gain * k[K_A_MAX, i]
    if saturate:
        lo = lo if (np.isnan(lo) or lo > 0.0) else 0.0
        hi = hi if (np.isnan(hi) or hi > 0.0) else 0.0
    return passive, gain, lo, hi


@njit(cache=True, nogil=True)
def tension_range(k, fl, fv, fp, v, cos_a, live, saturate):
    """(4, m): :func:`_range_one` of every muscle (``saturate`` (m,): Millard's), for
    :meth:`mcdm_pin.model.muscles_osim.OpenSimMuscles.force_range` of a set of several kinds."""
    m = fl.shape[0]
    out = np.empty((4, m))
    for i in range(m):
        out[0, i], out[1, i], out[2, i], out[3, i] = _range_one(k, i, fl[i], fv[i], fp[i], v[i], cos_a[i],
                                                                live[i], saturate[i])
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
    P3, ends3, grid3 = np.tile(P, (3, 1, 1)), np.tile(ends, (3, 1)), np.tile(grid, (3, 1, 1))
    return [(bezier_values, (P, P.copy(), ends, grid, np.array([0.5]))),
            (millard_range, (np.ones(1), np.ones(1), np.ones((N_MILLARD_ROWS, 1)), P3, P3.copy(), ends3, grid3)),
            (pennation, (np.ones(1), np.ones(1), np.ones((N_MILLARD_ROWS, 1)))),
            (tension_range, (np.ones((N_MILLARD_ROWS, 1)), np.ones(1), np.ones(1), np.ones(1), np.ones(1), np.ones(1),
                             np.ones(1, dtype=np.bool_), np.ones(1, dtype=np.bool_)))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.bezier_kernels", warm_calls)


_register()
