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
from .coupling_kernels import polynomial
from .kernel_structs import CouplingTable

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
        return polynomial(*self.coef, x)


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
        self._table, self._functions = _table(self)
        self._table_plain = tuple(self._table)  # (as the per-instant kernels take it: solvers._structs)
        self._no_functions = np.full((len(self.items), 3), np.nan)  # (the kernels take it writable)
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
        q = np.asarray(q, dtype=float)
        vv = _EMPTY if v is None else np.asarray(v, dtype=float)
        aa = _EMPTY if v is None or a is None else np.asarray(a, dtype=float)
        k, what, value = jit.kernels("model.coupling_kernels").coupling_violation(
            q, vv, aa, self._table_plain, self._function_values(q), float(tol))
        if k >= 0:
            c = self.items[k]
            name = ("q", "v", "a")[what]
            given = (q, vv, aa)[what][self._table.dep_q[k] if what == 0 else c.dependent]
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
        q = np.asarray(q, dtype=float)
        return jit.kernels("model.coupling_kernels").coupling_basis(q, self._table_plain, self._function_values(q),
                                                                    self._independent64, int(self.nv))

    def project(self, q, L, tau):
        """``(N, L N, N^T tau)`` at ``q`` (:meth:`basis`; ``L`` (m, nv), ``tau`` (nv,)): the terms'
        projection onto the independent coordinates in one compiled pass
        (:func:`mcdm_pin.model.coupling_kernels.coupled_terms`: ``N`` has one entry at most per row)."""
        q = np.asarray(q, dtype=float)
        return jit.kernels("model.coupling_kernels").coupled_terms(
            q, self._table_plain, self._function_values(q), self._independent64, np.ascontiguousarray(L, dtype=float),
            np.ascontiguousarray(tau, dtype=float))

    def _function_values(self, q) -> np.ndarray:
        """(k, 3) ``(p, p', p'')`` of the couplings given by a function (OpenSim's), evaluated here at
        their source's value in ``q`` (a fixed coordinate's at 0); NaN rows for the polynomials, which
        the kernels evaluate."""
        if not self._functions:
            return self._no_functions
        fvals = np.full((len(self.items), 3), np.nan)
        src_q = self._table.src_q
        for k, f in self._functions:
            fvals[k] = f(q[src_q[k]] if src_q[k] >= 0 else 0.0)
        return fvals


def _table(cs: Couplings):
    """``(CouplingTable, functions)``: the couplings in their order as the kernels read them
    (:class:`~mcdm_pin.model.kernel_structs.CouplingTable`) and the ``(k, value)`` of those given by a
    function (``value(x) = (p, p', p'')``)."""
    i64 = np.int64
    col = {int(i): a for a, i in enumerate(cs.independent)}
    cols = []
    for c in cs.items:  # the column of each chain's root; none below a fixed coordinate
        col[c.dependent] = col.get(c.independent) if c.independent >= 0 else None
        cols.append(-1 if col[c.dependent] is None else col[c.dependent])
    ind = np.array([c.independent for c in cs.items], dtype=i64)
    coef = np.array([[0.0] * 5 if c.function is not None else [float(t) for t in c.coef] for c in cs.items],
                    dtype=float).reshape(len(cs.items), 5)
    table = CouplingTable(cs.q_index[cs.dependent].astype(i64),
                          np.where(ind >= 0, cs.q_index[np.maximum(ind, 0)], -1).astype(i64),
                          cs.dependent.astype(i64), ind, np.array(cols, dtype=i64), coef)
    return table, tuple((k, c.value) for k, c in enumerate(cs.items) if c.function is not None)


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
