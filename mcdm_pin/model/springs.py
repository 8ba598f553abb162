r"""Passive springs: cable-like elements whose tension is *known*, a function of their length.

A spring runs along a route exactly as a cable does (:mod:`mcdm_pin.model.cables`: points fixed in
frames, wraps, pulleys), so its length :math:`\ell_s(q)`, its row of
:math:`L_s = \partial \ell_s / \partial q` and its interaction maps :math:`R_s^T` are a cable's. Its tension is not an unknown of the
problem but follows its length, CASPR's ``CableModelPassiveLinearSpring`` (``force = K_cable (length -
l_0)``, with no sign restriction):

.. math:: f_s = k\,(\ell_s - \ell_0) \qquad (\text{N};\ k \text{ in N/m},\ \ell_0 \text{ in m}),

positive when stretched (it pulls its ends together, as a cable in tension), negative when compressed
(it pushes them apart). ``tension_only`` clips it at zero (an elastic cord that goes slack); CASPR's
spring is not clipped.

Being known, the springs move to the right-hand side of the equation of motion and join the
interaction wrenches (:mod:`mcdm_pin.model.terms`):

.. math:: L^T f = -(M\ddot q + h + L_s^T f_s), \qquad p_a = (u_a + R_{s,a}^T f_s) + R_a^T f,

which is CASPR's ``IDSolverBase.GetEoMConstraints`` (``b = M q_ddot + C + G + L_passive' f_passive``)
and ``IDObjectiveMinInteractions`` (``a_x = a + H_passive' f_passive``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError
from .cables import Cable, CableSet


@dataclass(frozen=True)
class Spring:
    """One passive spring: a name, a route (as a :class:`~mcdm_pin.model.cables.Cable`'s), its stiffness
    ``stiffness`` (N/m, >= 0), its rest length ``rest_length`` (m, >= 0) and whether it can only pull."""

    name: str
    route: tuple
    stiffness: float
    rest_length: float
    tension_only: bool = False


class SpringSet:
    """Springs bound to one Pinocchio model.

    Args:
        model: the ``pin.Model`` the route frames belong to.
        springs: :class:`Spring` objects.

    Attributes:
        springs, names; ``stiffness``, ``rest_length`` (s,); ``tension_only`` (s,) booleans.
        geometry: a :class:`~mcdm_pin.model.cables.CableSet` of the same routes (its force bounds are
            placeholders, never read): lengths, ``L_s`` and ``R_s^T`` are computed as a cable's.
    """

    def __init__(self, model: pin.Model, springs: Iterable):
        self.springs = tuple(springs)
        if not self.springs:
            raise ModelError("a spring set needs at least one spring")
        for k, s in enumerate(self.springs):
            if not isinstance(s, Spring):
                raise ModelError(f"spring {k}: expected a Spring, got {type(s).__name__}")
            for what, value in (("stiffness", s.stiffness), ("rest_length", s.rest_length)):
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                        or value < 0:
                    raise ModelError(f"spring {s.name!r}: expected a finite {what} >= 0, got {value!r}")
        try:
            self.geometry = CableSet(model, [Cable(s.name, tuple(s.route), 0.0, 1.0) for s in self.springs])
        except ModelError as exc:
            raise ModelError(str(exc).replace("cable ", "spring ", 1)) from None
        self.names = self.geometry.names
        self.stiffness = np.array([float(s.stiffness) for s in self.springs])
        self.rest_length = np.array([float(s.rest_length) for s in self.springs])
        self.tension_only = np.array([bool(s.tension_only) for s in self.springs])

    @property
    def count(self) -> int:
        return len(self.springs)

    def __len__(self) -> int:
        return len(self.springs)

    def forces(self, lengths) -> np.ndarray:
        """(s,) tensions ``k (l - l0)`` (N) at the lengths ``lengths`` (m), clipped at 0 where
        ``tension_only``."""
        f = self.stiffness * (np.asarray(lengths, dtype=float) - self.rest_length)
        return np.where(self.tension_only, np.maximum(f, 0.0), f)

    def check_model(self, model: pin.Model) -> None:
        self.geometry.check_model(model)

    def __repr__(self) -> str:
        return f"SpringSet({len(self)} springs: {', '.join(self.names[:6])}{', ...' if len(self) > 6 else ''})"
