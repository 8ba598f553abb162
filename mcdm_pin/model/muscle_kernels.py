r"""The compiled muscle curves: MuJoCo's force-length, force-velocity and passive curves and a
muscle's tension range at given tendon lengths and speeds, one muscle at a time.

:mod:`mcdm_pin.model.muscles` gives the model (its module docstring has the formulas, after
MuJoCo's ``mju_muscleGainLength``, ``mju_muscleGain`` and ``mju_muscleBias``); this module is its
one implementation of the curves: :func:`fl_one`, :func:`fv_one`, :func:`fp_one` on scalars
(``register_jitable``: compiled inline into the kernels, plain Python before), and the kernels
:func:`tension_range` (a muscle set's passive force, gain and tension bounds) and :func:`curves`
(the three curves at given normalised values) that loop over them. Each expression is written in
the order the formulas give, with no ``fastmath``, so compiled and uncompiled answers are the same
to the bit.

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit`; until then the same code runs as Python
(``jit.kernels("model.muscle_kernels").tension_range``).

The muscles' constants travel as one table ``k`` (:data:`N_ROWS`, m), a row per constant (the
names below; :func:`mcdm_pin.model.muscles.MuscleParams.kernel_table` fills it), so that a call
passes few arguments (numba's dispatch costs about a microsecond per argument).
"""

from __future__ import annotations

import numpy as np
from ..jit import extending, njit

register_jitable = extending.register_jitable

# rows of the constants table (each (m,)): the normalisation (range[0], bias_range[0],
# lengthrange[0], max(eps, L_opt), max(eps, L_opt^p), max(eps, L_opt vmax), gear), F_L's
# (lmin, lmax, (lmin + 1)/2, (1 + lmax)/2 and its four pieces' denominators), F_V's (fvmax - 1,
# max(eps, fvmax - 1), fvmax), F_P's ((1 + bias_lmax)/2, max(eps, that - 1), fpmax/2, fpmax), the
# scales g F0^p and g F0, and the activation range
(R0, BIAS_R0, LR0, LOPT, BIAS_LOPT, VDEN, GEAR, LMIN, LMAX, FL_A, FL_B, FL_D1, FL_D2, FL_D3, FL_D4, FV_Y, FV_D,
 FVMAX, FP_B, FP_W, FP_HALF, FPMAX, PASSIVE_SCALE, GAIN_SCALE, ACT_MIN, ACT_MAX) = range(26)
N_ROWS = 26


@register_jitable
def fl_one(l, k, i):
    """``F_L(l)`` of muscle ``i`` (table ``k``): 0 outside ``[lmin, lmax]``, else the first of its
    four quadratic pieces whose upper end ``l`` does not pass."""
    if not (k[LMIN, i] <= l <= k[LMAX, i]):
        return 0.0
    if l <= k[FL_A, i]:
        x = (l - k[LMIN, i]) / k[FL_D1, i]
        return 0.5 * x * x
    if l <= 1:
        x = (1 - l) / k[FL_D2, i]
        return 1 - 0.5 * x * x
    if l <= k[FL_B, i]:
        x = (l - 1) / k[FL_D3, i]
        return 1 - 0.5 * x * x
    x = (k[LMAX, i] - l) / k[FL_D4, i]
    return 0.5 * x * x


@register_jitable
def fv_one(v, k, i):
    """``F_V(v)`` of muscle ``i``: 0 at ``v <= -1``, ``(v + 1)^2`` up to 0, ``fvmax - (y - v)^2 / y``
    up to ``y = fvmax - 1``, ``fvmax`` beyond."""
    if v <= -1:
        return 0.0
    if v <= 0:
        return (v + 1) * (v + 1)
    y = k[FV_Y, i]
    if v <= y:
        return k[FVMAX, i] - (y - v) * (y - v) / k[FV_D, i]
    return k[FVMAX, i]


@register_jitable
def fp_one(l, k, i):
    """``F_P(l)`` of muscle ``i`` at the passive normalised length ``l``: 0 up to 1, quadratic up to
    ``(1 + bias_lmax)/2``, linear beyond."""
    if l <= 1:
        return 0.0
    if l <= k[FP_B, i]:
        x = (l - 1) / k[FP_W, i]
        return k[FP_HALF, i] * x * x
    x = (l - k[FP_B, i]) / k[FP_W, i]
    return k[FPMAX, i] * (0.5 + x)


@njit(cache=True, nogil=True)
def tension_range(ell, ell_dot, k):
    """The tension range of m muscles at ``T`` states: ``ell``, ``ell_dot`` (T, m) tendon lengths (m)
    and speeds (m/s), ``k`` (:data:`N_ROWS`, m) the constants. Returns (4, T, m): the passive force
    ``g F0^p F_P(l^p)``, the gain ``g F0 F_L(l) F_V(v)``, and the bounds ``passive + gain a_min``,
    ``passive + gain a_max`` (N), with ``l = r0 + (g ell - Lr0) / L_opt``, ``v = g ell_dot /
    (L_opt vmax)`` and ``l^p = r0^p + (g ell - Lr0) / L_opt^p``."""
    T, m = ell.shape
    out = np.empty((4, T, m))
    for s in range(T):
        for i in range(m):
            g_ell = k[GEAR, i] * ell[s, i]
            l = k[R0, i] + (g_ell - k[LR0, i]) / k[LOPT, i]
            v = k[GEAR, i] * ell_dot[s, i] / k[VDEN, i]
            lp = k[BIAS_R0, i] + (g_ell - k[LR0, i]) / k[BIAS_LOPT, i]
            passive = k[PASSIVE_SCALE, i] * fp_one(lp, k, i)
            gain = k[GAIN_SCALE, i] * fl_one(l, k, i) * fv_one(v, k, i)
            out[0, s, i] = passive
            out[1, s, i] = gain
            out[2, s, i] = passive + gain * k[ACT_MIN, i]
            out[3, s, i] = passive + gain * k[ACT_MAX, i]
    return out


@njit(cache=True, nogil=True)
def curves(x, which, k):
    """One curve of m muscles at ``x`` (T, m): ``which`` 0 ``F_L`` (``x`` normalised lengths), 1
    ``F_V`` (normalised velocities), 2 ``F_P`` (passive normalised lengths). Returns (T, m)."""
    T, m = x.shape
    out = np.empty((T, m))
    for s in range(T):
        for i in range(m):
            if which == 0:
                out[s, i] = fl_one(x[s, i], k, i)
            elif which == 1:
                out[s, i] = fv_one(x[s, i], k, i)
            else:
                out[s, i] = fp_one(x[s, i], k, i)
    return out


def warm_calls():
    """This module's kernels with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    k = np.ones((N_ROWS, 1))
    k.setflags(write=False)  # the library's table is read-only (MuscleParams.kernel_table): one type
    x = np.ones((1, 1))
    return [(tension_range, (x, x, k)), (curves, (x, 0, k))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.muscle_kernels", warm_calls)


_register()
