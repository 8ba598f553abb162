r"""The data every back-end reads: one instant's quadratic problem with cones (:class:`QPData`) and
one stability cone (:class:`ConeData`), with the cone constants stacked for compiled code.

.. math::

    \min_x\; \tfrac12\, x^T P x + c^T x + r \quad \text{s.t.}\quad A x = b,\;\; l \le x \le u,\;\;
    \|F_{k,\perp}\| \le \tan\rho^*_k\, a_k^T F_k\;\; (F_k = g_k + G_k x).

The bottom of the solving layers: :mod:`mcdm_pin.problem` assembles a :class:`QPData`, the constraints
make :class:`ConeData`, and :mod:`mcdm_pin.solvers` reads both; this module imports none of them.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .exceptions import ProblemError


@dataclass
class ConeData:
    r"""``|F - (a.F) a| <= tan(angle) (a.F)`` with ``F = g + G x``.

    Attributes:
        joint: the joint's name.
        G: (3, n), g: (3,): the force in the cone's frame as an affine map of x.
        axis: (3,) unit axis in the same frame.
        angle_deg: half-angle, degrees.
        basis: (2, 3) orthonormal vectors spanning the plane normal to ``axis``.
    """

    joint: str
    G: np.ndarray
    g: np.ndarray
    axis: np.ndarray
    angle_deg: float
    basis: np.ndarray

    @property
    def tan(self) -> float:
        return float(np.tan(np.radians(self.angle_deg)))

    def force(self, x) -> np.ndarray:
        return self.g + self.G @ x

    def angle_of(self, x) -> float:
        F = self.force(x)
        along = float(self.axis @ F)
        perp = float(np.linalg.norm(F - along * self.axis))
        return float(np.degrees(np.arctan2(perp, along)))

    def with_angle(self, angle_deg: float) -> "ConeData":
        return ConeData(self.joint, self.G, self.g, self.axis, float(angle_deg), self.basis)


def perpendicular_basis(axis: np.ndarray) -> np.ndarray:
    """Two unit vectors that complete ``axis`` to a right-handed orthonormal frame."""
    a = np.asarray(axis, dtype=float)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(a, e1)
    return np.vstack([e1, e2])


class QPData:
    """One instant's problem, ready for a back-end (see the module docstring).

    Args:
        P: (n, n) symmetric positive semidefinite Hessian, or ``None`` when ``P_diag`` and
            ``P_factor`` give it (then formed on first use).
        c: (n,), r: the linear and constant terms.
        A: (k, n), b: (k,): equalities.
        lb, ub: (n,) bounds (may be infinite, may be negative).
        cones: :class:`ConeData` list.
        P_diag, P_factor: optional structure ``P = diag(P_diag) + P_factor^T P_factor`` (the compiled
            solver factors this far faster than a dense ``P``).
        norm_weight: (n,) weights of the least-norm stage, which picks among equally optimal points
            the one of least ``sum_i norm_weight_i x_i^2`` (``None``: ones, i.e. ``|x|^2``). A scaled
            copy carries the weights that keep that norm the original variables' ``|f|^2``.
        cone_arrays, cone_consts, kernel_arrays: :meth:`cone_arrays`, :meth:`cone_consts` and
            :meth:`kernel_arrays` when the caller has them already (a scaled copy: the scaling
            kernel's arrays), instead of made on first use.
    """

    __slots__ = ("_P", "c", "r", "A", "b", "lb", "ub", "cones", "P_diag", "P_factor", "norm_weight",
                 "_cone_arrays", "_cone_consts", "_kernel_arrays", "_kernel_qp", "_strict")

    def __init__(self, P, c, r, A, b, lb, ub, cones=(), *, P_diag=None, P_factor=None, norm_weight=None,
                 cone_arrays=None, cone_consts=None, kernel_arrays=None):
        self._P = P
        self.c, self.r, self.A, self.b, self.lb, self.ub = c, float(r), A, b, lb, ub
        self.cones = list(cones)
        self.P_diag, self.P_factor = P_diag, P_factor
        self.norm_weight = norm_weight
        self._cone_arrays = cone_arrays
        self._cone_consts = cone_consts
        self._kernel_arrays = kernel_arrays
        self._kernel_qp = None  # (the compiled solvers' view of it: solvers.active_set.kernel_qp)
        self._strict = None  # (strictly_convex, once asked)
        if P is None and (P_diag is None or P_factor is None):
            raise ProblemError("QPData: give P or both P_diag and P_factor")

    @property
    def P(self) -> np.ndarray:
        if self._P is None:
            F = self.P_factor
            if not F.shape[0]:  # a diagonal objective (f^T f, activations'): no product to form
                self._P = np.diag(self.P_diag + 0.0)  # (+ 0.0: a -0.0 entry reads +0.0, as the sum below gives)
                return self._P
            self._P = F.T @ F
            # (the diagonal as a strided view of the flat array: no index arrays, as
            # diag_indices_from makes)
            self._P.flat[:: self._P.shape[0] + 1] += self.P_diag
        return self._P

    @property
    def n(self) -> int:
        return len(self.c)

    @property
    def structured(self) -> bool:
        return self.P_diag is not None and self.P_factor is not None

    def cone_arrays(self) -> tuple:
        """The cones stacked for vectorised and compiled code: ``G`` (k, 3, n), ``g`` (k, 3),
        ``axis`` (k, 3), ``tan`` (k,), ``basis0`` (k, 3) (a unit vector normal to each axis)."""
        if self._cone_arrays is None:
            n, cs = self.n, self.cones
            k = len(cs)
            if not k:  # no cones (cases 1 and 2): the empty arrays of this size, made once
                self._cone_arrays = _no_cones(n)[0]
                return self._cone_arrays
            self._cone_arrays = (
                np.array([c.G for c in cs], dtype=float).reshape(k, 3, n),
                np.array([c.g for c in cs], dtype=float).reshape(k, 3),
                np.array([c.axis for c in cs], dtype=float).reshape(k, 3),
                np.array([c.tan for c in cs], dtype=float).reshape(k),
                np.array([c.basis[0] for c in cs], dtype=float).reshape(k, 3))
        return self._cone_arrays

    def kernel_arrays(self) -> tuple:
        """``(c, A, b, lb, ub, G, g, axis, tan, basis0)`` (the vectors and equations, then
        :meth:`cone_arrays`) as C-ordered float arrays, made once: what the compiled steps of an
        instant read (no copies when they are so already, as an assembled problem's are; ``A`` is
        (k, n) even when empty, ``G`` (K, 3, n))."""
        if self._kernel_arrays is None:
            c_ = np.ascontiguousarray
            n = self.n
            G, g, ax, tn, basis0 = self.cone_arrays()
            K = len(g)
            self._kernel_arrays = (
                c_(self.c, dtype=float), c_(self.A, dtype=float).reshape(len(self.b), n), c_(self.b, dtype=float),
                c_(self.lb, dtype=float), c_(self.ub, dtype=float), c_(G, dtype=float).reshape(K, 3, n),
                c_(g, dtype=float).reshape(K, 3), c_(ax, dtype=float).reshape(K, 3), c_(tn, dtype=float).reshape(K),
                c_(basis0, dtype=float).reshape(K, 3))
        return self._kernel_arrays

    def cone_consts(self) -> tuple:
        """What does not change from instant to instant about the cones, stacked for compiled code:
        their joints' names (a tuple), half-angles in degrees (k,), the cosines of the half-angles
        (k,) and the bases normal to the axes (k, 2, 3)."""
        if self._cone_consts is None:
            self._cone_consts = cone_constants(self.cones) if self.cones else _no_cones(self.n)[1]
        return self._cone_consts

    def cone_rows(self) -> tuple[np.ndarray, np.ndarray]:
        r"""Per cone, ``T (3, n)`` and ``t (3,)`` with ``s = T x + t`` in the second-order cone
        ``|s[1:]| <= s[0]``: ``s = [sin(rho) a.F, cos(rho) e1.F, cos(rho) e2.F]`` (rows of norm <= 1
        for any half-angle, so a cone near 90 degrees is as well scaled as one near 0). Stacked:
        (K, 3, n), (K, 3)."""
        if not self.cones:
            return np.zeros((0, 3, self.n)), np.zeros((0, 3))
        W = np.empty((len(self.cones), 3, 3))
        for k, c in enumerate(self.cones):
            rho = np.radians(c.angle_deg)
            W[k, 0] = np.sin(rho) * c.axis
            W[k, 1:] = np.cos(rho) * c.basis
        G, g = self.cone_arrays()[:2]
        return W @ G, np.einsum("kab,kb->ka", W, g)

    def constant_objective(self) -> bool:
        """Whether the objective is a constant (``P = 0`` and ``c = 0`` exactly, as when every joint's
        weights are zero): every feasible point is then optimal."""
        cnz = np.count_nonzero  # (no reduction's per-call machinery, as any() has, on every instant)
        if cnz(self.c):  # (c first: n entries, where P has n^2; most objectives have a linear part)
            return False
        if self._P is None:
            return not (cnz(self.P_diag) or cnz(self.P_factor))
        return not cnz(self._P)

    def strictly_convex(self) -> bool:
        """Whether ``P = diag(P_diag) + P_factor^T P_factor`` has every ``P_diag`` entry above zero (a NaN
        not): then ``P`` is positive definite and the optimum unique (case 1, the activations'
        objective). ``False`` proves nothing."""
        if self._strict is None:
            d = self.P_diag
            # (the first entry first: the interaction objectives' diagonal is zero; then counted:
            # count_nonzero has no reduction's per-call machinery, as min() has, on every instant)
            self._strict = not (d is None or d.size == 0 or not d[0] > 0.0 or np.count_nonzero(~(d > 0.0)))
        return self._strict

    def objective(self, x) -> float:
        """``1/2 x^T P x + c^T x + r``."""
        x = np.asarray(x, dtype=float)
        if self._P is None:
            Fx = self.P_factor @ x
            return float(0.5 * (Fx @ Fx + self.P_diag @ (x * x)) + self.c @ x + self.r)
        return float(0.5 * x @ self._P @ x + self.c @ x + self.r)

    def gradient(self, x) -> np.ndarray:
        """``P x + c``."""
        if self._P is None:
            return self.P_factor.T @ (self.P_factor @ x) + self.P_diag * x + self.c
        return self._P @ x + self.c

    def replace(self, **changes) -> "QPData":
        """A copy with some fields replaced (arrays are shared, not copied)."""
        fields = dict(P=self._P, c=self.c, r=self.r, A=self.A, b=self.b, lb=self.lb, ub=self.ub,
                      cones=self.cones, P_diag=self.P_diag, P_factor=self.P_factor,
                      norm_weight=self.norm_weight)
        if "cones" not in changes:
            fields["cone_arrays"] = self._cone_arrays
            fields["cone_consts"] = self._cone_consts
        if "P" in changes and "P_diag" not in changes:
            fields["P_diag"] = fields["P_factor"] = None
        fields.update(changes)
        P = fields.pop("P")
        return QPData(P, **fields)

    def without_cones(self) -> "QPData":
        return self.replace(cones=[])

    def with_cones(self, cones) -> "QPData":
        return self.replace(cones=list(cones))


@functools.lru_cache(maxsize=64)
def _no_cones(n: int) -> tuple:
    """``(cone_arrays, cone_consts)`` of a problem of ``n`` variables without cones: empty arrays,
    shared (nothing can be written into them; not flagged read-only, which would be another type to
    the compiled kernels), made once per size instead of at every instant of cases 1 and 2."""
    arrays = (np.zeros((0, 3, n)), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros((0, 3)))
    consts = ((), np.zeros(0), np.zeros(0), np.zeros((0, 2, 3)))
    return arrays, consts


def cone_constants(cones) -> tuple:
    """:meth:`QPData.cone_consts` of a list of cones (:class:`ConeData` or
    bound :class:`~mcdm_pin.constraints.InteractionCone`)."""
    k = len(cones)
    deg = np.array([float(c.angle_deg) for c in cones], dtype=float).reshape(k)
    return (tuple(c.joint for c in cones), deg, np.cos(np.radians(deg)),
            np.array([c.basis for c in cones], dtype=float).reshape(k, 2, 3))

__all__ = ["QPData", "ConeData", "perpendicular_basis", "cone_constants"]
