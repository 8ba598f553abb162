r"""A hybrid robot's instant problem over ``[f; tau_act]`` in one compiled pass
(:meth:`mcdm_pin.problem._Actuation.extend`): the cables' problem padded with the actuators'
columns, bounds and weights, one loop per array instead of a dozen numpy allocations and copies.

Every entry is copied or set, never computed, so the padded problem is the same to the bit as the
numpy expressions it replaces (``-S`` is negated entry by entry as numpy negates it). Compiled by
``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``), registered with
:mod:`mcdm_pin.jit`; until then the same code runs as Python.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import njit

Actuated = namedtuple("Actuated", ["A", "G", "P", "P_diag", "P_factor", "c", "lb", "ub", "norm_weight"])
Actuated.__doc__ = """What :func:`actuated_arrays` returns: the padded problem's equations ``A``
(rows, n), cones' maps ``G`` (K, 3, n), dense Hessian ``P`` ((n, n), or (0, 0) when not asked for),
structure ``P_diag`` (n,) and ``P_factor`` (rows, n) (empty when not structured), ``c``, bounds
``lb``, ``ub`` and least-norm weights (n,; empty when the problem has none)."""

KERNEL_STRUCTURES = (Actuated,)
"""The structure above (the marker :func:`mcdm_pin.jit.kernel_sources` looks for)."""


@njit(cache=True, nogil=True)
def actuated_arrays(A0, S, eom_rows, G0, P0, dense, P_diag0, P_factor0, structured, c0, lb0, ub0, lo, hi, weight,
                    norm_weight0):
    """The problem of ``m`` cable forces (``A0`` (rows, m), ``G0`` (K, 3, m), ``P0`` (m, m) or (0, 0),
    ``P_diag0`` (m,), ``P_factor0`` (frows, m), ``c0``, ``lb0``, ``ub0``, ``norm_weight0`` (m,) or
    empty) over ``n = m + k`` variables: the first ``eom_rows`` rows of ``A`` gain ``-S`` (eom_rows,
    k), every other row and every cone a zero block; ``P`` (when ``dense``) the block diagonal of
    ``P0`` and ``diag(weight)``; ``P_diag`` (when ``structured``) ``[P_diag0; weight]`` and
    ``P_factor`` a zero block; ``c`` zeros, the bounds ``lo``, ``hi`` and the least-norm weights ones
    for the actuators. Returns :class:`Actuated`."""
    rows, m = A0.shape
    k = lo.shape[0]
    n = m + k
    A = np.zeros((rows, n))
    for i in range(rows):
        for j in range(m):
            A[i, j] = A0[i, j]
    for i in range(eom_rows):
        for j in range(k):
            A[i, m + j] = -S[i, j]
    K = G0.shape[0]
    G = np.zeros((K, 3, n))
    for c in range(K):
        for i in range(3):
            for j in range(m):
                G[c, i, j] = G0[c, i, j]
    P = np.zeros((n, n) if dense else (0, 0))
    if dense:
        for i in range(m):
            for j in range(m):
                P[i, j] = P0[i, j]
        for j in range(k):
            P[m + j, m + j] = weight[j]
    P_diag = np.empty(n if structured else 0)
    P_factor = np.zeros((P_factor0.shape[0] if structured else 0, n))
    if structured:
        for j in range(m):
            P_diag[j] = P_diag0[j]
        for j in range(k):
            P_diag[m + j] = weight[j]
        for i in range(P_factor0.shape[0]):
            for j in range(m):
                P_factor[i, j] = P_factor0[i, j]
    c = np.zeros(n)
    lb = np.empty(n)
    ub = np.empty(n)
    for j in range(m):
        c[j] = c0[j]
        lb[j] = lb0[j]
        ub[j] = ub0[j]
    for j in range(k):
        lb[m + j] = lo[j]
        ub[m + j] = hi[j]
    nw = np.ones(n if norm_weight0.shape[0] else 0)
    for j in range(norm_weight0.shape[0]):
        nw[j] = norm_weight0[j]
    return Actuated(A, G, P, P_diag, P_factor, c, lb, ub, nw)


def warm_calls():
    """This module's kernel with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    return [(actuated_arrays, (z((1, 2)), z((1, 1)), 1, z((1, 3, 2)), z((0, 0)), False, z(2), z((1, 2)), True,
                               z(2), z(2), z(2), z(1), z(1), z(1), z(0)))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.actuated_kernels", warm_calls)


_register()
