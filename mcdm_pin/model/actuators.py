r"""Actuated joints (hybrid robots, HCDM): joint torques or forces that join the cable forces as unknowns.

With actuators the unknowns are :math:`x = [f;\ \tau_{act}]` and the equation of motion reads

.. math:: L^T f - S\,\tau_{act} = -(M\ddot q + h),

with :math:`S` (nv, n_act) selecting the actuated velocity columns (:func:`actuation_matrix`). An
actuator's torque acts inside its joint, so it does not enter the interaction wrench ``p``: the joint's
joint-space wrench :math:`S_a^T p_a` equals the actuator's torque.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..exceptions import ModelError


@dataclass(frozen=True)
class Actuator:
    """A motor on a physical joint: one torque/force per degree of freedom of the joint.

    Attributes:
        joint: the physical joint's name.
        idx_v: (k,) the velocity columns it drives.
        tau_min, tau_max: (k,) bounds, N m or N (may be negative; ``-inf``/``inf``: unbounded, CASPR's
            default for a joint motor: the weight in the objective alone then keeps the torque finite).
        weight: weight of ``|tau|^2`` in the objectives that weigh the unknowns (case 1).
        names: a name per component (``JOINT`` or ``JOINT[i]``).
    """

    joint: str
    idx_v: np.ndarray
    tau_min: np.ndarray
    tau_max: np.ndarray
    weight: float = 1.0
    label: str = ""  # the actuator's own name (a reserve names its coordinate); default: the joint's

    def __post_init__(self):
        lo, hi = np.asarray(self.tau_min, dtype=float), np.asarray(self.tau_max, dtype=float)
        k = len(self.idx_v)
        if lo.shape != (k,) or hi.shape != (k,):
            raise ModelError(f"actuator of joint {self.joint!r}: expected {k} lower and {k} upper bounds")
        if not (np.all(lo < hi) and np.all(lo < math.inf) and np.all(hi > -math.inf)):
            raise ModelError(f"actuator of joint {self.joint!r}: expected bounds with min < max (min may be -inf, "
                             f"max inf: unbounded), got min={lo.tolist()}, max={hi.tolist()}")
        if not (math.isfinite(self.weight) and self.weight >= 0):
            raise ModelError(f"actuator of joint {self.joint!r}: weight must be finite and >= 0, got {self.weight!r}")
        if self.weight == 0 and not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise ModelError(f"actuator of joint {self.joint!r}: an unbounded actuator needs a weight > 0 (with "
                             f"weight 0 nothing keeps its torque finite and case 1 has no unique answer)")
        object.__setattr__(self, "tau_min", lo)
        object.__setattr__(self, "tau_max", hi)
        object.__setattr__(self, "idx_v", np.asarray(self.idx_v, dtype=int))

    @property
    def names(self) -> tuple[str, ...]:
        k, base = len(self.idx_v), self.label or self.joint
        return (base,) if k == 1 else tuple(f"{base}[{i}]" for i in range(k))

    @classmethod
    def on_coordinate(cls, joints, i: int, tau_min: float, tau_max: float, weight: float = 1.0,
                      label: str = "") -> "Actuator":
        """An actuator of the one coordinate ``i`` (index in ``v``), on the physical joint among
        ``joints`` that holds it (an MJCF motor, a reserve)."""
        owner = next((j for j in joints if int(i) in j.idx_v), None)
        if owner is None:
            raise ModelError(f"actuator {label!r}: coordinate {i} belongs to no physical joint")
        return cls(owner.name, np.array([int(i)]), np.array([float(tau_min)]), np.array([float(tau_max)]),
                   float(weight), label=label)

    @classmethod
    def on(cls, joint, tau_min, tau_max, weight: float = 1.0) -> "Actuator":
        """An actuator on a :class:`~mcdm_pin.model.joints.PhysicalJoint`."""
        return cls(joint.name, joint.idx_v, np.atleast_1d(np.asarray(tau_min, dtype=float)),
                   np.atleast_1d(np.asarray(tau_max, dtype=float)), float(weight))


def actuator_names(robot) -> list[str]:
    """One name per actuator component (``JOINT`` or ``JOINT[i]``), in the order of ``tau_act``; empty
    for a robot without actuators."""
    return [n for a in getattr(robot, "actuators", ()) for n in a.names]


def actuation_matrix(nv: int, actuators) -> np.ndarray:
    """(nv, n_act) ``S``: column k is 1 at the velocity entry actuator component k drives."""
    cols = [int(i) for a in actuators for i in a.idx_v]
    S = np.zeros((nv, len(cols)))
    S[cols, np.arange(len(cols))] = 1.0
    return S
