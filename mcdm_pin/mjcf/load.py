"""A loader: a MuJoCo MJCF file -> the parts of a :class:`~mcdm_pin.robot.Robot`, through MuJoCo's own
compiler (``Robot.load("model.xml")`` and ``Robot.from_mujoco(mj)`` build the robot from them).

MuJoCo (the ``mjcf`` extra) compiles the file: defaults, includes, frames, inertias from geoms are
resolved exactly as MuJoCo resolves them. The Pinocchio model is built from the compiled arrays
(:mod:`mcdm_pin.mjcf.model`), the cables, muscles and couplings from its tendons, actuators and
equalities (:mod:`mcdm_pin.mjcf.tendons`). Nothing is simulated. The robot speaks MuJoCo's names:
coordinates are its joints, cables its muscles (or tendons), physical joints its bodies.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..exceptions import ModelError, StateError
from ..model.actuators import Actuator
from ..model.cables import CableSet
from ..model.couplings import Couplings
from ..model.joints import physical_joints
from ..source_lines import line_of
from .model import build_model
from .tendons import read_couplings, read_tendons

MJCF_SUFFIXES = (".xml", ".mjcf")


def compile_mjcf(path):
    """``mujoco.MjModel`` of the MJCF file ``path`` (ModelError naming the file and MuJoCo's reason)."""
    try:
        import mujoco
    except ImportError:
        raise ModelError(f"{path}: reading MJCF needs MuJoCo: pip install 'mcdm-pin[mjcf]'") from None
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: MJCF file not found")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except ValueError as exc:
        raise ModelError(f"{path}: MuJoCo cannot compile it: {str(exc).strip()}") from None


def is_mjcf(path) -> bool:
    """Whether ``path`` looks like an MJCF file (an ``.xml``/``.mjcf`` whose root is ``<mujoco``)."""
    p = Path(path)
    if p.suffix.lower() not in MJCF_SUFFIXES or not p.is_file():
        return False
    with open(p, "rb") as fh:
        head = fh.read(4096).decode("utf-8", "replace")
    return re.search(r"<mujoco[\s>]", head) is not None


class RobotParts(NamedTuple):
    """What :func:`mjcf_parts` reads, as :class:`~mcdm_pin.robot.Robot` takes it (``Robot(**parts._asdict())``:
    :meth:`~mcdm_pin.robot.Robot.from_mujoco` does that)."""

    model: object
    cables: object
    joints: tuple
    actuators: tuple
    name: str
    couplings: object
    coordinate_names: tuple
    source: object
    notes: tuple


def mjcf_parts(mj, source: str, name: str = "robot", actuator_weights: dict | None = None) -> RobotParts:
    """The robot of a compiled ``mujoco.MjModel``, in parts (``source``: a path or label for messages;
    ``actuator_weights``: ``{joint motor's actuator name: w}`` of ``w |tau|^2``, default 1 each)."""
    try:
        mjm = build_model(mj, source)
        tendons = read_tendons(mj, mjm, source)
        if not tendons.cables:
            raise ModelError(f"{source}: no actuator drives a spatial tendon, so the model has no cable")
        cables = CableSet(mjm.model, tendons.cables, muscles=tendons.muscles, muscle_cables=tendons.muscle_cables)
        coupled = read_couplings(mj, mjm, source)
    except ModelError as exc:
        msg = str(exc)
        msg = msg if msg.startswith(source) else f"{source}: {msg}"
        raise ModelError(msg + _line_of(source, msg)) from None
    names = mjm.coordinate_names
    q_index = np.full(mjm.model.nv, -1, dtype=int)
    for j, kind in enumerate(mjm.jnt_type):
        if kind in (2, 3):  # slide, hinge: q is the coordinate
            q_index[mjm.jnt_idx_v[j]] = mjm.jnt_idx_q[j]
    couplings = Couplings(q_index, coupled, names) if coupled else None
    joints = physical_joints(mjm.model)
    motors = _joint_motors(mjm, joints, tendons.joint_motors, source, actuator_weights)
    return RobotParts(mjm.model, cables, joints, motors, name, couplings, names, MjcfSource(mjm, couplings),
                      tendons.notes)


def _joint_motors(mjm, joints, motors, source: str, weights: dict | None) -> tuple:
    """Plain motors on hinge and slide joints as actuators of the physical joint (MuJoCo body) holding
    the joint, named after the MuJoCo actuator, each weighted ``weights[name]`` (default 1) in ``w
    |tau|^2`` (an unbounded one, without a control or force range, is kept finite by its weight).
    Weights for other names raise :class:`ModelError`."""
    weights = dict(weights or {})
    out = tuple(Actuator.on_coordinate(joints, int(mjm.jnt_idx_v[jnt]), lo, hi, float(weights.pop(name, 1.0)),
                                       label=name)
                for name, jnt, lo, hi in motors)
    if weights:
        known = ", ".join(repr(m[0]) for m in motors) or "none"
        raise ModelError(f"{source}: actuator_weights names {sorted(weights)}, which are not motors on hinge or "
                         f"slide joints of this model (those: {known})")
    return out


def _line_of(source: str, message: str) -> str:
    """`` (line N)`` of the element a message names (``kind 'name'``) in the MJCF file ``source``, when
    the file holds it (an element from an included file or a model built in code has no line here)."""
    m = re.search(r"\b(body|joint|site|geom|tendon|actuator|equality|spatial|muscle|connect|weld) '([^']+)'",
                  message[len(source):])
    if m is None:
        return ""
    return line_of(source, re.compile(r'name\s*=\s*"' + re.escape(m.group(2)) + '"'))


class MjcfSource:
    """What a robot loaded from MJCF keeps of its source: the Pinocchio-MuJoCo maps (``maps``, an
    :class:`~mcdm_pin.mjcf.model.MjcfModel`) and the couplings, to read MuJoCo's joint values."""

    kind = "mjcf"

    def __init__(self, maps, couplings):
        self.maps, self.couplings = maps, couplings
        has = bool(np.any(maps.jnt_stiffness) or np.any(maps.dof_damping))
        # (the terms evaluator calls it with a checked state)
        self.passive = maps.joint_passive_checked if has else None

    def configuration(self, values: dict) -> np.ndarray:
        """Pinocchio's ``q`` from ``{MuJoCo joint name: qpos value(s)}``: joints not given keep
        ``qpos0`` (MuJoCo's reference), except coupled ones, which are filled from their couplings when
        not given and checked when given."""
        maps = self.maps
        qpos = np.array(maps.qpos0, dtype=float)
        given_v = set()
        index = {n: j for j, n in enumerate(maps.joint_names)}
        for key, value in values.items():
            if key not in index:
                shown = ", ".join(repr(n) for n in maps.joint_names[:12])
                raise StateError(f"{maps.source}: unknown joint {key!r}; expected MuJoCo joint names, e.g. {shown}")
            j = index[key]
            a, k = int(maps.jnt_qposadr[j]), {0: 7, 1: 4}.get(int(maps.jnt_type[j]), 1)
            v = np.atleast_1d(np.asarray(value, dtype=float))
            if v.shape != (k,) or not np.all(np.isfinite(v)):
                raise StateError(f"{maps.source}: joint {key!r}: expected {k} finite number(s), got {value!r}")
            qpos[a:a + k] = v
            given_v.add(int(maps.jnt_idx_v[j]))
        q = maps.to_pin_q(qpos)
        if self.couplings is not None:
            q = self.couplings.complete(q, given_v)
        return q
