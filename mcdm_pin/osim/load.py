"""A loader: an OpenSim ``.osim`` file -> the parts of a :class:`~mcdm_pin.robot.Robot`
(``Robot.load("model.osim")`` builds the robot from them).

The file is read as XML (:mod:`.document`), without OpenSim: users need no OpenSim install, the
reader states in one place what it takes and refuses, and the model layer computes everything at
solve time. OpenSim (the pip wheel) is only the tests' reference. The skeleton (bodies, joints,
couplings, loops) is built here (:mod:`.model`); the muscles and their paths come from
:func:`_cables`. The robot speaks OpenSim's names: its coordinates are OpenSim's coordinates (plus
``JOINT/AXIS`` entries that follow functions), its physical joints OpenSim's moving joints, its
link frames OpenSim's bodies.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..exceptions import ModelError, StateError
from ..mjcf.load import RobotParts
from ..model.cables import CableSet
from ..model.couplings import Couplings
from ..model.joints import physical_joints
from ..source_lines import line_of
from . import speeds
from .actuators import read_coordinate_actuators
from .constraints import PointLoops
from .document import read_osim
from .model import OsimModel, build


def is_osim(path) -> bool:
    """Whether ``path`` is an ``.osim`` file."""
    return Path(path).suffix.lower() == ".osim"


def _cables(root, file, model):
    """``(CableSet or None, notes)``: the muscles of the ``.osim`` as cables (:mod:`.paths`), ``None``
    when it has none. ``root`` is the parsed ``<Model>`` element (``xml.etree``), ``file`` the path,
    ``model`` the :class:`~mcdm_pin.osim.model.OsimModel` (its frames are named after the bodies)."""
    from .paths import read_paths

    coordinates = {n: (int(model.q_index[v]), int(v)) for n, v in zip(model.coordinates, model.coordinate_v)}
    cables, muscles, notes = read_paths(root, file, model.model, coordinates)
    # the CoordinateActuators are read here (mcdm_pin.osim.actuators), not left aside
    notes = [n for n in notes if not (n.startswith("CoordinateActuator ") and "not a path force" in n)]
    if not cables:
        return None, notes
    if muscles is None:
        return CableSet(model.model, cables), notes
    return CableSet(model.model, cables, muscles=muscles, muscle_cables=muscles.names), notes


def osim_skeleton(path):
    """``(OsimModel, Couplings or None, OsimSource, Document)`` of the ``.osim`` file ``path``: the
    skeleton alone, without muscles."""
    source = str(path)
    try:
        doc = read_osim(path)
        om = build(doc)
        couplings = Couplings(om.q_index, om.couplings, om.velocity_names) if om.couplings else None
    except ModelError as exc:
        msg = str(exc)
        msg = msg if msg.startswith(source) else f"{source}: {msg}"
        raise ModelError(msg + _line_of(source, msg)) from None
    return om, couplings, OsimSource(om, couplings), doc


def osim_parts(path, name: str | None = None, actuator_weights: dict | None = None) -> RobotParts:
    r"""The robot of the ``.osim`` file ``path``, in parts (``Robot(**parts._asdict())``): its muscles
    as cables, its ``CoordinateActuator``\ s as actuators (:mod:`.actuators`; ``actuator_weights``
    ``{name: w}`` of their ``w c^2``)."""
    source = str(path)
    om, couplings, src, doc = osim_skeleton(path)
    joints = physical_joints(om.model)
    try:
        cables, path_notes = _cables(doc.root, source, om)
        actuators, act_notes = read_coordinate_actuators(doc.root, om, joints, actuator_weights)
    except ModelError as exc:
        msg = str(exc)
        msg = msg if msg.startswith(source) else f"{source}: {msg}"
        raise ModelError(msg + _line_of(source, msg)) from None
    if cables is None:
        raise ModelError(f"{source}: no muscle (no force with a GeometryPath), so the model has no cable")
    notes = tuple(doc.notes) + om.notes + tuple(f"PointConstraint {n!r}: a closed loop (mcdm_pin.osim.constraints)"
                                     for n, _, _ in om.loops) + tuple(path_notes) + tuple(act_notes)
    return RobotParts(om.model, cables, joints, actuators, name or Path(path).stem, couplings,
                      om.velocity_names, src, notes)


def _line_of(source: str, message: str) -> str:
    """`` (line N)`` of the element a message names (``Tag 'name'``) in ``source``."""
    m = re.search(r"\b([A-Z]\w*) '([^']+)'", message[len(source):])
    if m is None:
        return ""
    return line_of(source, re.compile(r"<" + re.escape(m.group(1)) + r'\s+name\s*=\s*"' + re.escape(m.group(2)) + '"'))


class OsimSource:
    """What a robot loaded from ``.osim`` keeps of its source: the maps between OpenSim's coordinates
    and speeds and Pinocchio's ``q``, ``v`` (``maps``, an :class:`~mcdm_pin.osim.model.OsimModel`),
    the couplings and the closed loops (``loops``, a :class:`~mcdm_pin.osim.constraints.PointLoops`
    or ``None``)."""

    kind = "osim"
    passive = None

    def __init__(self, maps: OsimModel, couplings):
        self.maps, self.couplings = maps, couplings
        self.loops = PointLoops(maps.model, maps.loops, couplings) if maps.loops else None

    def configuration(self, values: dict) -> np.ndarray:
        """Pinocchio's ``q`` from ``{OpenSim coordinate: value}`` (rad, m): coordinates not given keep
        their ``default_value``; entries that follow couplings are computed (and checked when given)."""
        maps = self.maps
        index = {n: k for k, n in enumerate(maps.coordinates)}
        x = np.array(maps.defaults, dtype=float)
        given = set()
        for key, value in values.items():
            if key not in index:
                shown = ", ".join(repr(n) for n in maps.coordinates[:12])
                raise StateError(f"{maps.source}: unknown coordinate {key!r}; expected OpenSim coordinate names, "
                                 f"e.g. {shown}")
            v = np.asarray(value, dtype=float)
            if v.shape != () or not np.isfinite(v):
                raise StateError(f"{maps.source}: coordinate {key!r}: expected one finite number, got {value!r}")
            x[index[key]] = float(v)
            given.add(int(maps.coordinate_v[index[key]]))
        q = np.zeros(maps.model.nq)
        q[maps.q_index[maps.coordinate_v]] = x
        if self.couplings is not None:
            q = self.couplings.complete(q, given)
        return q

    def coordinate_values(self, q) -> dict:
        """``{OpenSim coordinate: value}`` of Pinocchio's ``q``."""
        q = np.asarray(q, dtype=float)
        return {n: float(q[self.maps.q_index[v]]) for n, v in zip(self.maps.coordinates, self.maps.coordinate_v)}

    def velocity(self, q, speeds_by_name: dict, rates: dict | None = None):
        """Pinocchio's ``v`` (and ``a`` if ``rates`` is given: ``(v, a)``) from OpenSim's speeds and
        their rates ``{coordinate: value}`` (coordinates not given: 0; entries that follow couplings
        computed by the chain rule) at ``q`` (:mod:`mcdm_pin.osim.speeds`)."""
        u = self._vector(speeds_by_name, "speed")
        udot = None if rates is None else self._vector(rates, "acceleration")
        q = np.asarray(q, dtype=float)
        out = speeds.from_speeds(self.maps.angular, q, u, udot)
        v, a = (out, None) if udot is None else out
        if self.couplings is not None:
            _, v, a = self.couplings.fill(q, v, a)
        return v if a is None else (v, a)

    def speeds(self, q, v) -> dict:
        """``{OpenSim coordinate: speed}`` of Pinocchio's ``v`` at ``q``."""
        u = speeds.to_speeds(self.maps.angular, np.asarray(q, dtype=float), np.asarray(v, dtype=float))
        return {n: float(u[i]) for n, i in zip(self.maps.coordinates, self.maps.coordinate_v)}

    def _vector(self, values: dict, what: str) -> np.ndarray:
        index = {n: int(v) for n, v in zip(self.maps.coordinates, self.maps.coordinate_v)}
        out = np.zeros(self.maps.model.nv)
        for key, value in values.items():
            if key not in index:
                raise StateError(f"{self.maps.source}: unknown coordinate {key!r} in the {what}s")
            out[index[key]] = float(value)
        return out
