r"""The scaled copy of one instant's problem in one compiled pass (:func:`mcdm_pin.scaling.apply_scaling`:
the products of the module docstring there, one loop per array instead of a dozen numpy calls).

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit`; until then the same code runs as Python. The factors are
powers of two (but ``sqrt(obj)``), and each product is taken in the order numpy's expressions took
it, so the scaled problem is the same to the bit either way.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import njit
from .kernel_structs import ScaledQP


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


def warm_calls():
    """This module's kernel with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    o = np.ones
    return [(scale_qp, (z(2), z((1, 2)), z(1), z(2), z(2), z((0, 0)), z(2), z((1, 2)), z((1, 3, 2)), z((1, 3)),
                        z(0), o(2), o(1), 1.0, o(1)))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.scale_kernels", warm_calls)


_register()
