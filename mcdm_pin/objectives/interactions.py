r"""Case 2: :math:`J(f) = \sum_a \alpha_a |F_a|^2 + \beta_a |M_a|^2` with
:math:`p_a = [F_a; M_a] = u_a + R_a^T f` (positive semidefinite in :math:`f`).

With :math:`K = \sqrt{w}\, R^T` (the rows of non-zero weight) and :math:`k = \sqrt{w}\, u`:
:math:`J = |K f + k|^2`, so ``P = 2 K^T K`` (factor :math:`\sqrt2 K`), ``c = 2 K^T k``, ``r = |k|^2``.
"""

from __future__ import annotations

import numpy as np

from .. import jit
from ..exceptions import ProblemError
from .base import Objective, Quadratic


class MinInteractions(Objective):
    """Minimise the weighted squared interaction forces and moments.

    Args:
        alpha: ``{joint: weight}`` of |F|^2 (N^-2); joints left out use the sidecar's value.
        beta: ``{joint: weight}`` of |M|^2 (N^-2 m^-2); likewise.
    """

    symmetric = True  # P = K^T K is formed symmetric (see quadratic)

    def __init__(self, alpha: dict | None = None, beta: dict | None = None, _w: np.ndarray | None = None):
        self.alpha = dict(alpha or {})
        self.beta = dict(beta or {})
        self.bound = _w is not None
        self._w = _w
        if _w is not None:
            w = _w.reshape(-1)
            self._keep = np.flatnonzero(w != 0.0).astype(np.int64)
            self._sqrt_w = np.sqrt(w[self._keep])

    def bind(self, robot) -> "MinInteractions":
        names = robot.joint_names
        for label, d in (("alpha", self.alpha), ("beta", self.beta)):
            for k, v in d.items():
                if k not in names:
                    raise ProblemError(f"MinInteractions: {label} for unknown joint {k!r}; expected one "
                                       f"of {', '.join(names)}")
                if not np.isfinite(v) or v < 0:
                    raise ProblemError(f"MinInteractions: {label}[{k!r}] must be finite and >= 0, got {v!r}")
        a = np.array([self.alpha.get(j.name, j.alpha) for j in robot.joints], dtype=float)
        b = np.array([self.beta.get(j.name, j.beta) for j in robot.joints], dtype=float)
        w = np.concatenate([np.repeat(a[:, None], 3, 1), np.repeat(b[:, None], 3, 1)], axis=1)
        return MinInteractions(self.alpha, self.beta, _w=w)

    def weights(self, robot) -> np.ndarray:
        """(J, 6) weights of the squared wrench components."""
        return self.bind(robot)._w

    def quadratic(self, terms, context) -> Quadratic:
        if not self.bound:
            return self._bound_for(context).quadratic(terms, context)
        if jit.ready():  # one compiled pass, the same formulas (numpy below: the reference)
            c_ = np.ascontiguousarray  # (no copies: the terms' arrays are C-ordered floats)
            P, c, r, F = jit.kernels("model.kernels").interaction_quadratic(c_(terms.RT, dtype=float), c_(terms.u, dtype=float),
                                               self._keep, self._sqrt_w)
            return Quadratic(P, c, r, np.zeros(P.shape[0]), F)
        keep, sw = self._keep, self._sqrt_w
        K = sw[:, None] * terms.RT.reshape(self._w.size, -1)[keep]  # sqrt(w) R^T, (k, m)
        k = sw * terms.u.reshape(-1)[keep]
        F = np.sqrt(2.0) * K
        P = F.T @ F  # exactly symmetric (a Gram matrix)
        c = 2.0 * (k @ K)
        return Quadratic(P, c, float(k @ k), np.zeros(P.shape[0]), F)

    def spec(self) -> dict:
        return {"type": "MinInteractions", "alpha": {k: float(v) for k, v in self.alpha.items()},
                "beta": {k: float(v) for k, v in self.beta.items()}}

    @classmethod
    def from_spec(cls, spec: dict) -> "MinInteractions":
        return cls(spec.get("alpha") or None, spec.get("beta") or None)

    def __repr__(self) -> str:
        return f"MinInteractions(alpha={self.alpha or 'sidecar'}, beta={self.beta or 'sidecar'})"
