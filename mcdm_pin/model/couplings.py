r"""Coupled coordinates: a coordinate that is a function of another (MuJoCo's ``equality joint``,
OpenSim's ``CustomJoint`` transform axes and ``CoordinateCouplerConstraint``).

A coupling ties a *dependent* coordinate :math:`y` to an *independent* one :math:`x`, by a polynomial

.. math:: y = a_0 + a_1 x + a_2 x^2 + a_3 x^3 + a_4 x^4,

or by any function of one variable with two derivatives (``Coupling.function``: OpenSim's linear,
multiplier and spline functions, :mod:`mcdm_pin.osim.functions`),

both measured as Pinocchio's configuration entries of one-degree-of-freedom joints (a MuJoCo hinge or
slide ``q = qpos - qpos0``, so MuJoCo's ``y - y_0 = p(x - x_0)`` is this polynomial unchanged); without an
independent coordinate :math:`y = a_0` is fixed. Dependents may depend on dependents (evaluated in
order).

With couplings the configuration is a function :math:`q = \phi(z)` of the independent coordinates
:math:`z` (n of them), and

.. math:: \dot q = N(q)\,\dot z, \qquad \ddot q = N(q)\,\ddot z + \dot N(q, \dot z)\,\dot z,

with :math:`N = \partial\phi/\partial z` (nv, n). The couplings' constraint forces :math:`G^T\lambda`
do no work along :math:`N` (:math:`G N = 0`), so the equation of motion the cables must satisfy is the
projected one, :math:`N^T (M\ddot q + h) = -N^T L^T f`: the cable terms' ``L`` becomes :math:`L N`
(the derivative of the lengths with respect to :math:`z`) and ``tau`` becomes :math:`N^T\tau`
(:mod:`mcdm_pin.model.terms`). A constraint force acts inside the coupled joints, as an actuator's
torque does, so it changes no interaction wrench.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import jit
from ..exceptions import ModelError, StateError

_EMPTY = np.zeros(0)
DEPENDENT_TOL = 1e-9  # a given dependent coordinate must match its polynomial to this (rad or m)


@dataclass(frozen=True)
class Coupling:
    """``q[dependent] = polynomial(q[independent])`` (module docstring).

    Attributes:
        dependent, independent: indices into ``v`` (coordinates of one-DoF joints); ``independent``
            -1 for a fixed coordinate.
        coef: (5,) ``a_0 .. a_4`` (ignored when ``function`` is given).
        name: the source's name of the coupling (MuJoCo's equality name), for messages.
        function: ``None`` (the polynomial), or an object whose ``value(x)`` returns
            ``(f(x), f'(x), f''(x))``.
    """

    dependent: int
    independent: int
    coef: tuple
    name: str = ""
    function: object = None

    def value(self, x: float) -> tuple[float, float, float]:
        """``(p(x), p'(x), p''(x))``."""
        if self.function is not None:
            return tuple(float(t) for t in self.function.value(x))
        a0, a1, a2, a3, a4 = self.coef
        return (a0 + x * (a1 + x * (a2 + x * (a3 + x * a4))),
                a1 + x * (2 * a2 + x * (3 * a3 + x * 4 * a4)),
                2 * a2 + x * (6 * a3 + x * 12 * a4))


class Couplings:
    """The couplings of one model, ordered so that every dependent is computed after what it depends on.

    Args:
        q_index: (nv,) the ``q`` entry of each ``v`` entry of a one-DoF joint whose ``q`` is its
            coordinate (revolute, prismatic), -1 elsewhere.
        couplings: :class:`Coupling` objects.
        names: coordinate names (nv), for messages.
    """

    def __init__(self, q_index, couplings, names):
        self.q_index = np.asarray(q_index, dtype=int)
        self.nv = nv = len(self.q_index)
        self.names = tuple(names)
        items = list(couplings)
        deps = [c.dependent for c in items]
        if len(set(deps)) != len(deps):
            twice = sorted({self.names[d] for d in deps if deps.count(d) > 1})
            raise ModelError(f"coordinate(s) {twice} are coupled twice (two equalities make each dependent)")
        for c in items:
            for i in (c.dependent, c.independent):
                if i >= nv or (i >= 0 and self.q_index[i] < 0) or (i < 0 and i != c.independent):
                    raise ModelError(f"coupling {c.name!r}: coordinate {i} is not the angle or position of a "
                                     f"one-degree-of-freedom joint")
            if c.function is None and (len(c.coef) != 5 or not all(math.isfinite(a) for a in c.coef)):
                raise ModelError(f"coupling {c.name!r}: expected 5 finite polynomial coefficients, got {c.coef!r}")
        self.items = tuple(_ordered(items, self.names))
        self.dependent = np.array([c.dependent for c in self.items], dtype=int)
        dep = set(self.dependent.tolist())
        self.independent = np.array([i for i in range(nv) if i not in dep], dtype=int)
        self.independent_names = tuple(self.names[i] for i in self.independent)
        self._chain = None  # basis()'s index arrays, made on first use
        self._local = None  # check()'s, likewise
        self._independent64 = self.independent.astype(np.int64)

    @property
    def n(self) -> int:
        """Number of independent coordinates."""
        return len(self.independent)

    def __len__(self) -> int:
        return len(self.items)

    def complete(self, q, given) -> np.ndarray:
        """``q`` with the dependent entries whose velocity columns are not in ``given`` (a set of ``v``
        indices a user gave values for) computed from the independent ones, then checked: values given
        for dependents must follow their couplings (:class:`~mcdm_pin.exceptions.StateError`)."""
        dep = [int(d) for d in self.dependent if int(d) not in given]
        filled, _, _ = self.fill(q)
        q = np.array(q, dtype=float)
        q[self.q_index[dep]] = filled[self.q_index[dep]]
        self.check(q)
        return q

    def fill(self, q, v=None, a=None):
        """``(q, v, a)`` with every dependent entry computed from the independent ones (copies; ``v``,
        ``a`` ``None`` stay ``None``)."""
        q = np.array(q, dtype=float)
        v = None if v is None else np.array(v, dtype=float)
        a = None if a is None else np.array(a, dtype=float)
        qi = self.q_index
        for c in self.items:
            if c.independent < 0:
                q[qi[c.dependent]] = c.value(0.0)[0]
                if v is not None:
                    v[c.dependent] = 0.0
                if a is not None:
                    a[c.dependent] = 0.0
                continue
            x = q[qi[c.independent]]
            p, dp, ddp = c.value(x)
            q[qi[c.dependent]] = p
            if v is not None:
                xd = v[c.independent]
                v[c.dependent] = dp * xd
                if a is not None:
                    a[c.dependent] = ddp * xd * xd + dp * a[c.independent]
        return q, v, a

    def check(self, q, v=None, a=None, tol: float = DEPENDENT_TOL) -> None:
        """Raise :class:`StateError` unless the dependent entries of ``(q, v, a)`` follow the couplings:
        each dependent within ``tol (1 + |value|)`` of its coupling evaluated at the given values of
        what it depends on (one compiled pass, :func:`mcdm_pin.model.coupling_kernels.coupling_violation`;
        :meth:`fill` evaluates them along their chains). The error names the first broken coupling
        in order, a source before what depends on it."""
        if self._local is None:
            self._local = _local(self)
        dep_q, src_q, dep_v, src_v, coef, no_functions, functions = self._local
        q = np.asarray(q, dtype=float)
        vv = _EMPTY if v is None else np.asarray(v, dtype=float)
        aa = _EMPTY if v is None or a is None else np.asarray(a, dtype=float)
        fvals = no_functions if not functions else np.full((len(self.items), 3), np.nan)
        for k, f in functions:  # OpenSim's functions: evaluated here, the polynomials in the kernel
            fvals[k] = f(q[src_q[k]] if src_q[k] >= 0 else 0.0)
        k, what, value = jit.kernels("model.coupling_kernels").coupling_violation(
            q, vv, aa, dep_q, src_q, dep_v, src_v, coef, fvals, float(tol))
        if k >= 0:
            c = self.items[k]
            name, given = ("q", "v", "a")[what], (q, vv, aa)[what][dep_q[k] if what == 0 else c.dependent]
            raise StateError(f"{name}: coordinate {self.names[c.dependent]!r} is {given!r} but "
                             f"coupling {c.name!r} makes it {value!r} (give only the "
                             f"independent coordinates, or values that follow the couplings)")

    def basis(self, q) -> np.ndarray:
        """``N`` (nv, n): ``dq/dz`` at ``q`` (module docstring).

        Every row has one entry at most: an independent coordinate's 1 in its own column; a
        dependent's ``p'(x)`` times its independent coordinate's entry, in that one's column (none for
        a fixed coordinate). So the rows are products of scalars along each chain of couplings,
        taken in order: one compiled pass (:func:`mcdm_pin.model.coupling_kernels.coupling_basis`, compiled
        or not: mcdm_pin/jit.py)."""
        src, rows, cols, slope = self._slopes(q)
        return jit.kernels("model.coupling_kernels").coupling_basis(slope, src, rows, cols, self._independent64,
                                                           int(self.nv))

    def project(self, q, L, tau):
        """``(N, L N, N^T tau)`` at ``q`` (:meth:`basis`; ``L`` (m, nv), ``tau`` (nv,)): the terms'
        projection onto the independent coordinates in one compiled pass
        (:func:`mcdm_pin.model.coupling_kernels.coupled_terms`: ``N`` has one entry at most per row)."""
        src, rows, cols, slope = self._slopes(q)
        return jit.kernels("model.coupling_kernels").coupled_terms(slope, src, rows, cols, self._independent64,
                                                          np.ascontiguousarray(L, dtype=float),
                                                          np.ascontiguousarray(tau, dtype=float))

    def _slopes(self, q):
        """``(sources, rows, columns, slopes p'(x))`` of :func:`_chain`'s couplings at ``q``."""
        if self._chain is None:
            self._chain = _chain(self)
        src, src_q, rows, cols, coef, functions = self._chain
        x = np.asarray(q, dtype=float)[src_q]
        # each coupling's slope p'(x): the polynomials' at once, the functions' (OpenSim's) one by one
        slope = coef[:, 1] + x * (2 * coef[:, 2] + x * (3 * coef[:, 3] + x * 4 * coef[:, 4]))
        for k, f in functions:
            slope[k] = f(x[k])[1]
        return src, rows, cols, slope


def _chain(cs: Couplings):
    """:meth:`Couplings.basis`'s index arrays, in the couplings' order, for those with an independent
    coordinate at the root of its chain (not a fixed one): ``(sources, their q entries, rows,
    columns, coefficients, functions)``: the row each dependent multiplies (whose ``q`` entry is also
    the coupling's ``x``), that ``q`` entry's index, each dependent's row, the column of the
    independent coordinate at its chain's root, its polynomial (k, 5; zeros for a function) and the
    ``(k, value)`` of the couplings given by a function (``value(x) = (p, p', p'')``)."""
    col = {int(i): k for k, i in enumerate(cs.independent)}
    rows, cols, src, coef, functions = [], [], [], [], []
    for c in cs.items:
        root = col.get(c.independent) if c.independent >= 0 else None
        if root is None:  # a fixed coordinate, or one coupled to a fixed one: a zero row
            col[c.dependent] = None
            continue
        col[c.dependent] = root
        rows.append(c.dependent)
        cols.append(root)
        src.append(c.independent)
        coef.append([0.0] * 5 if c.function is not None else [float(a) for a in c.coef])
        if c.function is not None:
            functions.append((len(rows) - 1, c.value))
    i64 = np.int64
    src = np.array(src, dtype=i64)
    return (src, cs.q_index[src].astype(i64), np.array(rows, dtype=i64), np.array(cols, dtype=i64),
            np.array(coef, dtype=float).reshape(len(rows), 5), tuple(functions))


def _local(cs: Couplings):
    """:meth:`Couplings.check`'s arrays, in the couplings' order: each dependent's ``q`` entry, its
    source's ``q`` entry (-1 for a fixed coordinate), the dependents' and their sources' ``v`` indices
    (likewise), the polynomials (k, 5; zeros for a function), a (k, 3) NaN array (no function values:
    read only) and the ``(k, value)`` of the couplings given by a function."""
    i64 = np.int64
    ind = np.array([c.independent for c in cs.items], dtype=i64)
    coef = np.array([[0.0] * 5 if c.function is not None else [float(t) for t in c.coef] for c in cs.items],
                    dtype=float).reshape(len(cs.items), 5)
    functions = tuple((k, c.value) for k, c in enumerate(cs.items) if c.function is not None)
    src_q = np.where(ind >= 0, cs.q_index[np.maximum(ind, 0)], -1).astype(i64)
    return (cs.q_index[cs.dependent].astype(i64), src_q, cs.dependent.astype(i64), ind, coef,
            np.full((len(cs.items), 3), np.nan), functions)


def _ordered(items, names):
    """Topological order: a coupling after the one that makes its independent coordinate."""
    by_dep = {c.dependent: c for c in items}
    out, done, busy = [], set(), set()

    def visit(c):
        if c.dependent in done:
            return
        if c.dependent in busy:
            raise ModelError(f"couplings form a cycle through coordinate {names[c.dependent]!r}")
        busy.add(c.dependent)
        if c.independent in by_dep:
            visit(by_dep[c.independent])
        busy.discard(c.dependent)
        done.add(c.dependent)
        out.append(c)

    for c in items:
        visit(c)
    return out
