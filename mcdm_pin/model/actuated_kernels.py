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

ProblemArrays = namedtuple("ProblemArrays", ["A", "G", "P", "P_diag", "P_factor", "c", "lb", "ub", "norm_weight"])
ProblemArrays.__doc__ = """An instant problem's arrays as :func:`actuated_arrays` takes and returns them: its
equations ``A`` (rows, n), cones' maps ``G`` (K, 3, n), dense Hessian ``P`` ((n, n), or (0, 0) when
absent), structure ``P_diag`` (n,) and ``P_factor`` (frows, n) (empty when not structured), ``c``,
bounds ``lb``, ``ub`` and least-norm weights (n,; empty when the problem has none)."""

Actuators = namedtuple("Actuators", ["S", "eom_rows", "lo", "hi", "weight"])
Actuators.__doc__ = """The actuators' part: ``S`` (rows of the equation of motion, k), the number of
equation rows that gain ``-S`` (0 without an equation of motion), the bounds ``lo``, ``hi`` and the
Hessian's diagonal ``weight`` (k,)."""

KERNEL_STRUCTURES = (ProblemArrays, Actuators)
"""The structures above (the marker :func:`mcdm_pin.jit.kernel_sources` looks for)."""


@njit(cache=True, nogil=True)
def actuated_arrays(problem, dense, structured, actuators):
    """The problem of ``m`` cable forces (``problem``: :class:`ProblemArrays`' fields as a plain tuple,
    as the entry points take them: :mod:`mcdm_pin.solvers._structs`) over ``n = m + k`` variables
    (``actuators``: :class:`Actuators`' fields): the first ``eom_rows`` rows of ``A`` gain ``-S``,
    every other row and every cone a zero block; ``P`` (when ``dense``) the block diagonal of the
    problem's ``P`` and ``diag(weight)``; ``P_diag`` (when ``structured``) gains ``weight`` and
    ``P_factor`` a zero block; ``c`` zeros, the bounds ``lo``, ``hi`` and the least-norm weights (when
    given) ones for the actuators. Returns :class:`ProblemArrays`."""
    p = ProblemArrays(*problem)
    act = Actuators(*actuators)
    rows, m = p.A.shape
    S, lo, hi, weight = act.S, act.lo, act.hi, act.weight
    k = lo.shape[0]
    n = m + k
    A = np.zeros((rows, n))
    for i in range(rows):
        for j in range(m):
            A[i, j] = p.A[i, j]
    for i in range(act.eom_rows):
        for j in range(k):
            A[i, m + j] = -S[i, j]
    K = p.G.shape[0]
    G = np.zeros((K, 3, n))
    for c in range(K):
        for i in range(3):
            for j in range(m):
                G[c, i, j] = p.G[c, i, j]
    P = np.zeros((n, n) if dense else (0, 0))
    if dense:
        for i in range(m):
            for j in range(m):
                P[i, j] = p.P[i, j]
        for j in range(k):
            P[m + j, m + j] = weight[j]
    P_diag = np.empty(n if structured else 0)
    P_factor = np.zeros((p.P_factor.shape[0] if structured else 0, n))
    if structured:
        for j in range(m):
            P_diag[j] = p.P_diag[j]
        for j in range(k):
            P_diag[m + j] = weight[j]
        for i in range(p.P_factor.shape[0]):
            for j in range(m):
                P_factor[i, j] = p.P_factor[i, j]
    c = np.zeros(n)
    lb = np.empty(n)
    ub = np.empty(n)
    for j in range(m):
        c[j] = p.c[j]
        lb[j] = p.lb[j]
        ub[j] = p.ub[j]
    for j in range(k):
        lb[m + j] = lo[j]
        ub[m + j] = hi[j]
    nw = np.ones(n if p.norm_weight.shape[0] else 0)
    for j in range(p.norm_weight.shape[0]):
        nw[j] = p.norm_weight[j]
    return ProblemArrays(A, G, P, P_diag, P_factor, c, lb, ub, nw)


def warm_calls():
    """This module's kernel with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    problem = ProblemArrays(z((1, 2)), z((1, 3, 2)), z((0, 0)), z(2), z((1, 2)), z(2), z(2), z(2), z(0))
    return [(actuated_arrays, (tuple(problem), False, True, tuple(Actuators(z((1, 1)), 1, z(1), z(1), z(1)))))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.actuated_kernels", warm_calls)


_register()
