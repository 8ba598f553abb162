r"""The compiled couplings of coordinates (:mod:`mcdm_pin.model.couplings`): the basis ``N = dq/dz``,
the terms projected onto the independent coordinates, and the check that a state follows the
couplings, each one pass over the couplings in their order (a source before what depends on it).

Compiled by ``mcdm-pin compile`` with the other kernels and cached on disk (``cache=True``),
registered with :mod:`mcdm_pin.jit`; until then the same code runs as Python
(``jit.kernels("model.coupling_kernels").coupling_basis``). No ``fastmath``: compiled and
uncompiled answers are the same to the bit.
"""

from __future__ import annotations

import numpy as np

from ..jit import extending, njit
from .kernel_structs import CouplingTable

register_jitable = extending.register_jitable


@register_jitable
def polynomial(a0, a1, a2, a3, a4, x):
    """``(p(x), p'(x), p''(x))`` of ``p(x) = a0 + a1 x + a2 x^2 + a3 x^3 + a4 x^4`` (Horner): the one
    evaluation of a polynomial coupling, in Python (:meth:`mcdm_pin.model.couplings.Coupling.value`)
    and in the kernels below."""
    return (a0 + x * (a1 + x * (a2 + x * (a3 + x * a4))),
            a1 + x * (2 * a2 + x * (3 * a3 + x * 4 * a4)),
            2 * a2 + x * (6 * a3 + x * 12 * a4))


@register_jitable
def _coupling(q, src_q, coef, fvals, k):
    """Coupling ``k``'s ``(x, p, p', p'')``: ``x`` its source's ``q`` entry (``src_q[k]`` -1: a fixed
    coordinate, at 0); its function's values ``fvals[k]`` where finite (evaluated by the caller), else
    its polynomial ``coef[k]``."""
    x = q[src_q[k]] if src_q[k] >= 0 else 0.0
    if np.isfinite(fvals[k, 0]):
        return x, fvals[k, 0], fvals[k, 1], fvals[k, 2]
    p, dp, ddp = polynomial(coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3], coef[k, 4], x)
    return x, p, dp, ddp


@njit(cache=True, nogil=True)
def coupling_basis(q, table, fvals, independent, nv):
    """:meth:`mcdm_pin.model.couplings.Couplings.basis`: ``N`` (nv, n), one pass over the couplings in
    order (``table``: :class:`~mcdm_pin.model.kernel_structs.CouplingTable`): each dependent row's entry
    is its coupling's slope ``p'(x)`` times its source row's, in the column of its chain's root
    (none where the chain starts at a fixed coordinate: a zero row); the independent rows' ones in
    their own columns."""
    table = CouplingTable(*table)  # (a plain tuple at the boundary: solvers._structs)
    n = independent.shape[0]
    value = np.ones(nv)
    N = np.zeros((nv, n))
    for a in range(n):
        N[independent[a], a] = 1.0
    for k in range(table.dep_v.shape[0]):
        if table.col[k] >= 0:
            dp = _coupling(q, table.src_q, table.coef, fvals, k)[2]
            value[table.dep_v[k]] = dp * value[table.src_v[k]]
            N[table.dep_v[k], table.col[k]] = value[table.dep_v[k]]
    return N


@njit(cache=True, nogil=True)
def coupled_terms(q, table, fvals, independent, L, tau):
    """:func:`coupling_basis`'s ``N`` with ``L N`` and ``N^T tau`` (``L`` (m, nv), ``tau`` (nv,)): ``N``
    has one entry at most per row, so each product is a sum over the rows of ``L^T`` (``tau``) that
    land in a column, in the order of the couplings, instead of a dense product."""
    nv = tau.shape[0]
    N = coupling_basis(q, table, fvals, independent, nv)  # (the plain tuple, as Python passes it)
    table = CouplingTable(*table)  # (a plain tuple at the boundary: solvers._structs)
    m, n = L.shape[0], independent.shape[0]
    LN = np.empty((m, n))
    Nt = np.empty(n)
    for a in range(n):
        r = independent[a]
        Nt[a] = tau[r]
        for i in range(m):
            LN[i, a] = L[i, r]
    for k in range(table.dep_v.shape[0]):
        r, a = table.dep_v[k], table.col[k]
        if a < 0:
            continue
        w = N[r, a]
        Nt[a] += w * tau[r]
        for i in range(m):
            LN[i, a] += w * L[i, r]
    return N, LN, Nt


@njit(cache=True, nogil=True)
def coupling_violation(q, v, a, table, fvals, tol):
    """:meth:`mcdm_pin.model.couplings.Couplings.check`: the first violation of the couplings by the
    given ``q``, ``v``, ``a`` (``v``, ``a`` empty: not checked), each dependent against its coupling
    at the given values of its source (a fixed coordinate's at 0). Returns ``(k, what, value)`` for
    the first coupling (in their order: a source before what depends on it, so the cause before its
    echoes) whose dependent is more than ``tol (1 + |value|)`` from the value it gives (NaN counts as
    beyond): 0/1/2 for ``q``/``v``/``a``, and that value; ``(-1, -1, 0.0)`` when every coupling holds."""
    table = CouplingTable(*table)  # (a plain tuple at the boundary: solvers._structs)
    has_v, has_a = v.shape[0] > 0, a.shape[0] > 0
    src_v = table.src_v
    for k in range(table.dep_q.shape[0]):
        _, p, dp, ddp = _coupling(q, table.src_q, table.coef, fvals, k)
        for j in range(3):
            if j == 0:
                given, value = q[table.dep_q[k]], p
            elif j == 1 and has_v:
                xd = v[src_v[k]] if src_v[k] >= 0 else 0.0
                given, value = v[table.dep_v[k]], dp * xd
            elif j == 2 and has_v and has_a:
                xd = v[src_v[k]] if src_v[k] >= 0 else 0.0
                xdd = a[src_v[k]] if src_v[k] >= 0 else 0.0
                given, value = a[table.dep_v[k]], ddp * xd * xd + dp * xdd
            else:
                continue
            if not abs(given - value) <= tol * (1.0 + abs(value)):
                return k, j, value
    return -1, -1, 0.0


def warm_calls():
    """This module's kernels with example arguments of the types the library passes (registered with
    :mod:`mcdm_pin.jit`)."""
    z = np.zeros
    i64 = np.int64
    table = CouplingTable(z(1, dtype=i64), z(1, dtype=i64), z(1, dtype=i64), z(1, dtype=i64), z(1, dtype=i64),
                          z((1, 5)))
    fvals = np.full((1, 3), np.nan)
    return [(coupling_basis, (z(2), tuple(table), fvals, z(1, dtype=i64), 2)),
            (coupled_terms, (z(2), tuple(table), fvals, z(1, dtype=i64), z((1, 2)), z(2))),
            (coupling_violation, (z(2), z(2), z(2), tuple(table), fvals, 1e-9))]


def _register() -> None:
    from .. import jit

    jit.register("mcdm_pin.model.coupling_kernels", warm_calls)


_register()
