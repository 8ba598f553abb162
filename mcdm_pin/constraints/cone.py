r"""The stability cone of a unilateral spherical joint (case 3):

.. math:: \sqrt{F_x^2 + F_y^2} \le \tan(\rho^*)\, F_z,

with :math:`F` the interaction force in the socket (parent-side) frame by default (``frame='child'``:
in the child link's frame) and :math:`z` the joint's socket axis. It is a second-order cone in
:math:`F`, and :math:`F` is affine in the cable forces, so the constraint is convex.
"""

from __future__ import annotations

import numpy as np

from .. import jit
from ..exceptions import ProblemError
from ..vocabulary import CONE_FRAMES, CONE_TYPES
from ..qp import cone_constants
from ..qp import ConeData, perpendicular_basis
from .base import Constraint

FRAMES = CONE_FRAMES


class InteractionCone(Constraint):
    """Keep joint ``joint``'s interaction force within ``angle_deg`` of its socket axis.

    Args:
        joint: a spherical joint's name.
        angle_deg: the half-angle rho*, degrees, in (0, 90); default: the sidecar's ``cone_deg``.
        frame: ``socket`` (default, the source paper's convention) or ``child``.
    """

    def __init__(self, joint: str, angle_deg: float | None = None, frame: str = "socket",
                 _index: int | None = None, _basis: np.ndarray | None = None):
        if frame not in FRAMES:
            raise ProblemError(f"InteractionCone: frame must be one of {FRAMES}, got {frame!r}")
        self.joint, self.angle_deg, self.frame = joint, angle_deg, frame
        self.bound = _index is not None
        self.index, self.basis = _index, _basis

    def bind(self, robot) -> "InteractionCone":
        joint = robot.joint(self.joint)
        if joint.type not in CONE_TYPES:
            raise ProblemError(f"InteractionCone: joint {self.joint!r} is {joint.type}; cones apply to "
                               f"spherical (and composite) joints")
        angle = self.angle_deg
        if angle is None:
            if joint.cone_deg is None:
                raise ProblemError(f"InteractionCone: joint {self.joint!r} has no cone_deg in the sidecar; "
                                   f"give an angle")
            angle = joint.cone_deg
        if not (0.0 < float(angle) < 90.0):
            raise ProblemError(f"InteractionCone: angle for {self.joint!r} must be in (0, 90) deg, "
                               f"got {angle!r}")
        return InteractionCone(self.joint, float(angle), self.frame, _index=robot.joint_names.index(self.joint),
                               _basis=perpendicular_basis(joint.socket_axis))

    def cones(self, terms, context) -> list[ConeData]:
        if not self.bound:
            return self.bind(context.robot).cones(terms, context)
        a = self.index
        G, g = terms.RT[a, :3], terms.u[a, :3]
        if self.frame == "socket":
            Rs = terms.R_socket[a]
            G, g = Rs @ G, Rs @ g
        return [ConeData(joint=self.joint, G=G, g=g, axis=terms.socket_axes[a],
                         angle_deg=float(self.angle_deg), basis=self.basis)]

    def spec(self) -> dict:
        return {"type": "InteractionCone", "joint": self.joint,
                "angle_deg": None if self.angle_deg is None else float(self.angle_deg), "frame": self.frame}

    @classmethod
    def from_spec(cls, spec: dict) -> "InteractionCone":
        return cls(spec["joint"], spec.get("angle_deg"), spec.get("frame", "socket"))

    def __repr__(self) -> str:
        return f"InteractionCone({self.joint!r}, {self.angle_deg}, frame={self.frame!r})"


class ConeBatch:
    """All bound :class:`InteractionCone` constraints of a problem evaluated at once: one batched
    product for every cone's ``G, g`` instead of one small product per cone (the per-instant hot
    path; one compiled pass, :func:`mcdm_pin.model.kernels.cone_batch`, when the kernels are
    compiled)."""

    def __init__(self, cones: list[InteractionCone]):
        self.cones = cones
        self.index = np.array([c.index for c in cones], dtype=np.int64)
        self.socket = np.array([c.frame == "socket" for c in cones], dtype=np.bool_)
        self.all_socket = bool(self.socket.all())
        self.tan = np.array([np.tan(np.radians(float(c.angle_deg))) for c in cones])
        self.basis0 = np.array([c.basis[0] for c in cones]).reshape(len(cones), 3)
        self.consts = cone_constants(cones)  # QPData.cone_consts: the same at every instant
        self._made = [(c.joint, float(c.angle_deg), c.basis) for c in cones]

    def __call__(self, terms) -> tuple[list[ConeData], tuple]:
        if jit.ready():
            c_ = np.ascontiguousarray  # (no copy: the terms' arrays are C-ordered floats)
            G, g, axes = jit.kernels("model.kernels").cone_batch(c_(terms.RT, dtype=float), c_(terms.u, dtype=float),
                                    c_(terms.R_socket, dtype=float), c_(terms.socket_axes, dtype=float),
                                    self.index, self.socket)
        else:
            G, g, axes = self.arrays(terms)
        data = [ConeData(joint, G[k], g[k], axes[k], angle, basis)
                for k, (joint, angle, basis) in enumerate(self._made)]
        return data, (G, g, axes, self.tan, self.basis0)

    def arrays(self, terms) -> tuple:
        """``(G, g, axes)`` of every cone, in numpy (the reference of the compiled pass)."""
        idx = self.index
        G, g = terms.RT[idx, :3], terms.u[idx, :3]
        if self.all_socket:
            Rs = terms.R_socket[idx]
            G, g = Rs @ G, np.einsum("kab,kb->ka", Rs, g)
        elif self.socket.any():
            s = self.socket
            Rs = terms.R_socket[idx[s]]
            G, g = G.copy(), g.copy()
            G[s], g[s] = Rs @ G[s], np.einsum("kab,kb->ka", Rs, g[s])
        return G, g, terms.socket_axes[idx]
