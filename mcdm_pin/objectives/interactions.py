r"""Case 2: :math:`J(f) = \sum_a \alpha_a |F_a|^2 + \beta_a |M_a|^2` with
:math:`p_a = [F_a; M_a] = u_a + R_a^T f` (positive semidefinite in :math:`f`)."""

from __future__ import annotations

import numpy as np

from ..exceptions import ProblemError
from .base import Objective, Quadratic


class MinInteractions(Objective):
    """Minimise the weighted squared interaction forces and moments.

    Args:
        alpha: ``{joint: weight}`` of |F|^2 (N^-2); joints left out use the sidecar's value.
        beta: ``{joint: weight}`` of |M|^2 (N^-2 m^-2); likewise.
    """

    symmetric = True  # P = R^T W R is formed symmetric (see quadratic)

    def __init__(self, alpha: dict | None = None, beta: dict | None = None):
        self.alpha = dict(alpha or {})
        self.beta = dict(beta or {})
        self._w = None

    def validate(self, robot) -> None:
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
        self._w = np.concatenate([np.repeat(a[:, None], 3, 1), np.repeat(b[:, None], 3, 1)], axis=1)
        w = self._w.reshape(-1)
        self._keep = np.flatnonzero(w != 0.0)
        self._sqrt_w = np.sqrt(w[self._keep])

    def weights(self, robot) -> np.ndarray:
        """(J, 6) weights of the squared wrench components."""
        self.validate(robot)
        return self._w

    def quadratic(self, terms, context) -> Quadratic:
        if self._w is None:
            self.validate(context.robot)
        keep, sw = self._keep, self._sqrt_w
        SR = sw[:, None] * terms.RT.reshape(len(self._w.reshape(-1)), -1)[keep]  # sqrt(w) R, (k, m)
        su = sw * terms.u.reshape(-1)[keep]
        P = SR.T @ SR  # exactly symmetric (a Gram matrix: BLAS syrk-like product of SR with itself)
        c = 2.0 * (su @ SR)
        r = float(su @ su)
        return Quadratic(P, c, r)

    def __repr__(self) -> str:
        return f"MinInteractions(alpha={self.alpha or 'sidecar'}, beta={self.beta or 'sidecar'})"
