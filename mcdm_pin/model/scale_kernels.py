r"""The scaled copy of one instant's problem in one compiled pass (:func:`mcdm_pin.scaling.apply_scaling`:
the products of the module docstring there, one loop per array instead of a dozen numpy calls), the
factors and the copy in one call (:func:`scale_instant`), and the answer mapped back
(:func:`unscale_answer`).

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit`; until then the same code runs as Python. The factors are
powers of two (but ``sqrt(obj)``), and each product is taken in the order numpy's expressions took
it, so the scaled problem is the same to the bit either way.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from .kernel_structs import ScaledInstant, ScaledQP, Unscaled
from .kernels import scale_factors


@njit(cache=True, nogil=True)
def scale_qp(c, A, b, lb, ub, P, P_diag, P_factor, G0, g0, norm_weight, d, r, obj, cone):
    """The problem's arrays scaled: ``c d / obj``, ``A`` with ``r`` (rows) and ``d`` (columns), ``r b``,
    ``lb / d``, ``ub / d``, ``d P d / obj``, ``d P_diag d / obj``, ``P_factor d / sqrt(obj)``, the cones'
    ``G`` with ``d`` and ``g`` with their factor ``cone``, and the least-norm weights ``w d^2``
    (``norm_weight`` empty: ones). ``P``, ``P_diag``, ``P_factor`` may be empty (absent): they stay so.
    Returns :class:`~mcdm_pin.model.kernel_structs.ScaledQP`."""
    m, n = A.shape
    sc = np.empty(n)
    slb = np.empty(n)
    sub = np.empty(n)
    nw = np.empty(n)
    for j in range(n):
        sc[j] = d[j] * c[j] / obj
        slb[j] = lb[j] / d[j]
        sub[j] = ub[j] / d[j]
        nw[j] = d[j] * d[j] if norm_weight.shape[0] == 0 else norm_weight[j] * d[j] * d[j]
    sA = np.empty((m, n))
    sb = np.empty(m)
    for i in range(m):
        sb[i] = r[i] * b[i]
        for j in range(n):
            sA[i, j] = A[i, j] * d[j] * r[i]
    sP = np.empty(P.shape)
    if P.shape[0]:
        dj = d / obj
        for i in range(n):
            for j in range(n):
                sP[i, j] = P[i, j] * d[i] * dj[j]
    sPd = np.empty(P_diag.shape[0])
    for j in range(P_diag.shape[0]):
        sPd[j] = d[j] * P_diag[j] * d[j] / obj
    sF = np.empty(P_factor.shape)
    root = math.sqrt(obj)
    for i in range(P_factor.shape[0]):
        for j in range(n):
            sF[i, j] = P_factor[i, j] * d[j] / root
    K = G0.shape[0]
    G = np.empty((K, 3, n))
    g = np.empty((K, 3))
    for k in range(K):
        for e in range(3):
            g[k, e] = cone[k] * g0[k, e]
            for j in range(n):
                G[k, e, j] = G0[k, e, j] * d[j] * cone[k]
    return ScaledQP(sc, sA, sb, slb, sub, sP, sPd, sF, G, g, nw)


@njit(cache=True, nogil=True)
def scale_instant(A, b, lb, ub, c, P, P_diag, P_factor, structured, G, g, f_scale, norm_weight, force, limit):
    """:func:`mcdm_pin.scaling.scale_problem` in one call: the factors
    (:func:`~mcdm_pin.model.kernels.scale_factors`, with its one-pass test for the well-scaled
    instant where it applies: the caller may have made it already, or skip it along a trajectory
    that is being scaled) and, where they scale, the scaled arrays (:func:`scale_qp`). ``P`` (n, n)
    the dense Hessian or (0, 0); ``P_diag`` (n,) or empty; ``P_factor`` (rows, n) (no rows: none);
    ``structured``: ``P = diag(P_diag) + P_factor^T P_factor``. Returns
    :class:`~mcdm_pin.model.kernel_structs.ScaledInstant`."""
    n = A.shape[1]
    if structured:
        scaled, d, r, obj, cone = scale_factors(A, b, lb, ub, c, P, P_diag, P_factor, True, G, g, f_scale, force,
                                                limit)
    else:  # (the factors read no structure then)
        scaled, d, r, obj, cone = scale_factors(A, b, lb, ub, c, P, np.zeros(n), np.zeros((0, n)), False, G, g,
                                                f_scale, force, limit)
    if not scaled:
        e = np.empty(0)
        e2 = np.empty((0, 0))
        return ScaledInstant(False, d, r, obj, cone, ScaledQP(e, e2, e, e, e, e2, e, e2, np.empty((0, 3, 0)),
                                                               np.empty((0, 3)), e))
    return ScaledInstant(True, d, r, obj, cone,
                         scale_qp(c, A, b, lb, ub, P, P_diag, P_factor, G, g, norm_weight, d, r, obj, cone))


@njit(cache=True, nogil=True)
def unscale_answer(d, r, obj, cone, x_s, y_s, z_s, zc_s, P, P_diag, P_factor, c, r0):
    """An answer of the scaled problem mapped back (:meth:`mcdm_pin.scaling.Scaling.unscale`): ``x =
    d x_s``, its objective ``1/2 x^T P x + c^T x + r0`` on the original problem (``P`` (n, n), or
    (0, 0) with ``P = diag(P_diag) + P_factor^T P_factor``; NaN where ``x`` is not finite), ``y =
    obj r y_s``, ``z = obj z_s / d``, the cones' ``obj cone_k zc_s``. A multiplier array may be
    empty (none): it stays so. Returns :class:`~mcdm_pin.model.kernel_structs.Unscaled`."""
    n = x_s.shape[0]
    x = np.empty(n)
    finite = True
    for j in range(n):
        x[j] = d[j] * x_s[j]
        finite = finite and np.isfinite(x[j])
    objective = np.nan
    if finite:
        quad = 0.0
        if P.shape[0]:
            for i in range(n):
                row = 0.0
                for j in range(n):
                    row += P[i, j] * x[j]
                quad += x[i] * row
        else:
            for i in range(P_factor.shape[0]):
                row = 0.0
                for j in range(n):
                    row += P_factor[i, j] * x[j]
                quad += row * row
            for j in range(n):
                quad += P_diag[j] * x[j] * x[j]
        lin = 0.0
        for j in range(n):
            lin += c[j] * x[j]
        objective = 0.5 * quad + lin + r0
    y = np.empty(y_s.shape[0])
    for i in range(y_s.shape[0]):
        y[i] = obj * r[i] * y_s[i]
    z = np.empty(z_s.shape[0])
    for j in range(z_s.shape[0]):
        z[j] = obj * z_s[j] / d[j]
    zc = np.empty(zc_s.shape)
    for k in range(zc_s.shape[0]):
        for e in range(zc_s.shape[1]):
            zc[k, e] = obj * cone[k] * zc_s[k, e]
    return Unscaled(x, objective, y, z, zc)


def warm_calls():
    """This module's kernel with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    o = np.ones
    return [(scale_qp, (z(2), z((1, 2)), z(1), z(2), z(2), z((0, 0)), z(2), z((1, 2)), z((1, 3, 2)), z((1, 3)),
                        z(0), o(2), o(1), 1.0, o(1))),
            (scale_instant, (z((1, 2)), z(1), z(2), z(2), z(2), z((0, 0)), z(2), z((1, 2)), True, z((1, 3, 2)),
                             z((1, 3)), z(0), z(0), False, 1e3)),
            (unscale_answer, (o(2), o(1), 1.0, o(1), z(2), z(1), z(2), z((1, 3)), z((0, 0)), z(2), z((1, 2)), z(2),
                              0.0))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.scale_kernels", warm_calls)


_register()
