r"""Problem scaling for badly scaled robots: solve an equilibrated copy of the QP, return unscaled forces.

A robot with grams next to tonnes and millimetres next to metres gives equation-of-motion rows whose
sizes differ by many orders of magnitude (a tonne's gravity torque next to a gram's) and columns of
``L^T`` of very different sizes (millimetre and metre lever arms); ProxQP's first-order iterations
then stall at their iteration limit (measured: ``tests/test_conditioning.py``). With

.. math:: f = D x, \qquad A f = b \;\to\; (R A D)\, x = R b, \qquad
          F_k = g_k + G_k f \;\to\; s_k F_k = s_k g_k + (s_k G_k D)\, x

(:math:`R`, :math:`D` positive diagonal from a few Ruiz equilibration sweeps of ``A``, :math:`s_k > 0`
per cone; cones are invariant under positive scaling of :math:`F_k`), the objective
:math:`x^T (D P D) x + (D c)^T x` divided by its own size, and bounds :math:`l/d \le x \le u/d`, the
scaled problem has the same solution set mapped by :math:`D`. The answer is unscaled (``f = D x``), its
objective re-evaluated on the original problem, and the runner then checks it against the *original*
constraints, so scaling can never hide a violated equation of motion or bound.

Use: ``ScaledSolver(get_solver("proxqp"))`` is a :class:`~mcdm_pin.solvers.Solver` like any other.
"""

from __future__ import annotations

import numpy as np

from .constraints import ConeData
from .problem import QPData
from .solvers.base import Solution, Solver


def equilibrate(A: np.ndarray, sweeps: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """Ruiz equilibration: positive ``r`` (rows) and ``d`` (columns) with ``r_i |A_ij| d_j`` of order
    1 in every row and column (powers of two, so scaling adds no rounding)."""
    n_r, n_c = A.shape
    r, d = np.ones(n_r), np.ones(n_c)
    B = np.abs(A)
    for _ in range(sweeps):
        S = r[:, None] * B * d[None, :]
        row = S.max(axis=1, initial=0.0)
        col = S.max(axis=0, initial=0.0)
        row[row == 0] = 1.0
        col[col == 0] = 1.0
        r /= np.sqrt(row)
        d /= np.sqrt(col)
    return _pow2(r), _pow2(d)


def _pow2(x: np.ndarray) -> np.ndarray:
    return np.exp2(np.round(np.log2(x)))


def scale_problem(qp: QPData, f_scale: np.ndarray | None = None):
    """Return ``(scaled QPData, d, objective_scale)``; ``f = d * x``."""
    if qp.A.shape[0]:
        r, d = equilibrate(qp.A)
    else:
        r, d = np.zeros(0), np.ones(qp.n)
    if f_scale is not None:
        d = d * _pow2(np.asarray(f_scale, dtype=float))
    A = r[:, None] * qp.A * d[None, :]
    b = r * qp.b
    P = d[:, None] * qp.P * d[None, :]
    c = d * qp.c
    obj = max(np.abs(P).max(initial=0.0), np.abs(c).max(initial=0.0), 1e-300)
    obj = float(_pow2(np.array([obj]))[0])
    cones = []
    for cone in qp.cones:
        G = cone.G * d[None, :]
        s = float(_pow2(np.array([1.0 / max(np.abs(G).max(initial=0.0), np.abs(cone.g).max(initial=0.0),
                                             1e-300)]))[0])
        cones.append(ConeData(cone.joint, s * G, s * cone.g, cone.axis, cone.angle_deg, cone.basis))
    scaled = QPData(P=P / obj, c=c / obj, r=qp.r / obj, A=A, b=b, lb=qp.lb / d, ub=qp.ub / d, cones=cones)
    return scaled, d, obj


class ScaledSolver(Solver):
    """Wrap a back-end: solve the equilibrated problem, return the unscaled answer (module docstring).

    Args:
        inner: the back-end (a :class:`~mcdm_pin.solvers.Solver`).
        only_if_worse_than: skip scaling when the EoM matrix's row and column norms already lie within
            this ratio (well-scaled problems keep the inner back-end's warm starts untouched).
    """

    def __init__(self, inner: Solver, only_if_worse_than: float = 1e3):
        self.inner = inner
        self.only_if_worse_than = only_if_worse_than
        self.name = inner.name

    def fresh(self) -> "ScaledSolver":
        return ScaledSolver(self.inner.fresh(), self.only_if_worse_than)

    def reset(self) -> None:
        self.inner.reset()

    def needs_scaling(self, qp: QPData) -> bool:
        if not qp.A.shape[0]:
            return False
        from .model.kernels import spread

        # C order: one compiled specialisation (qp.A is often the transposed view L.T)
        return spread(np.ascontiguousarray(qp.A, dtype=float), np.ascontiguousarray(qp.b, dtype=float)) \
            > self.only_if_worse_than

    def solve(self, qp: QPData) -> Solution:
        if not self.needs_scaling(qp):
            return self.inner.solve(qp)
        scaled, d, _ = scale_problem(qp)
        sol = self.inner.solve(scaled)
        f = d * sol.f
        objective = qp.objective(f) if np.all(np.isfinite(f)) else float("nan")
        return Solution(f, sol.status, objective, sol.iterations, sol.rounds, sol.message)

    def __getattr__(self, name):  # expose the inner back-end's settings and helpers
        if name == "inner":
            raise AttributeError(name)
        return getattr(self.inner, name)
