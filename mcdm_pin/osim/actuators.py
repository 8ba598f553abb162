r"""OpenSim's ``CoordinateActuator``\ s as :class:`~mcdm_pin.model.actuators.Actuator`\ s.

A ``CoordinateActuator`` applies the generalized force :math:`\tau = F_{opt}\, c` to its coordinate
(``optimal_force`` :math:`F_{opt}`, N m or N; control :math:`c` in ``[min_control, max_control]``).
As an actuator of the robot its unknown is :math:`\tau` on the coordinate's velocity entry, bounded by
:math:`F_{opt}\,[c_{min}, c_{max}]`, weighed by :math:`w/F_{opt}^2` so that the objective's term is
:math:`w\,c^2` (OpenSim's static optimisation and RMR weigh controls; ``w = 1`` unless given). An
infinite control range (OpenSim's default) is bounded at :data:`CONTROL_CAP` (an actuator must have
finite bounds; the cap is listed in the notes and no answer of a well-posed problem reaches it).
Actuators with ``appliesForce`` false are left out (listed in the notes).
"""

from __future__ import annotations

import math

from ..exceptions import ModelError
from ..model.actuators import Actuator

CONTROL_CAP = 1e4  # |control| bound replacing an infinite control range


def read_coordinate_actuators(root, model, joints, weights: dict | None = None):
    r"""``(actuators, notes)``: the ``<CoordinateActuator>``\ s of the ``<Model>`` element ``root``, in
    the file's order, labelled with their names.

    Args:
        root: the parsed ``<Model>`` element.
        model: the :class:`~mcdm_pin.osim.model.OsimModel` (coordinate names -> ``v`` entries).
        joints: the robot's physical joints (the actuator sits on the one holding its coordinate).
        weights: ``{actuator name: w}`` of ``w c^2`` (default 1 each); unknown names raise ModelError.
    """
    weights = dict(weights or {})
    index = {n: int(v) for n, v in zip(model.coordinates, model.coordinate_v)}
    out, notes, capped = [], [], []
    for el in root.iter("CoordinateActuator"):
        name = el.get("name", "")
        where = f"CoordinateActuator {name!r}"
        if (el.findtext("appliesForce") or "true").strip().lower() == "false":
            notes.append(f"{where}: appliesForce is false (left out)")
            continue
        coord = (el.findtext("coordinate") or "").strip()
        if coord not in index:
            raise ModelError(f"{where}: coordinate {coord!r} is not a coordinate of the model")
        f_opt = _number(el, "optimal_force", where, 1.0)
        if not f_opt > 0:
            raise ModelError(f"{where}: optimal_force must be > 0, got {f_opt!r}")
        lo, hi = _number(el, "min_control", where, -math.inf), _number(el, "max_control", where, math.inf)
        if not lo < hi:
            raise ModelError(f"{where}: min_control {lo!r} must be below max_control {hi!r}")
        if math.isinf(lo) or math.isinf(hi):
            capped.append(name)
        lo, hi = max(lo, -CONTROL_CAP), min(hi, CONTROL_CAP)
        w = float(weights.pop(name, 1.0))
        out.append(Actuator.on_coordinate(joints, index[coord], f_opt * lo, f_opt * hi, w / f_opt ** 2, label=name))
    if weights:
        raise ModelError(f"actuator weights given for unknown CoordinateActuator(s) {sorted(weights)}")
    if capped:
        notes.append(f"CoordinateActuator(s) {capped}: infinite control range bounded at +-{CONTROL_CAP:g}")
    return tuple(out), notes


def _number(el, tag, where, default) -> float:
    text = el.findtext(tag)
    if text is None or not text.strip():
        return default
    word = text.strip().lower()
    if word in ("inf", "+inf", "infinity"):
        return math.inf
    if word in ("-inf", "-infinity"):
        return -math.inf
    try:
        value = float(text)
    except ValueError:
        raise ModelError(f"{where}: <{tag}> expected a number, got {text.strip()!r}") from None
    if math.isnan(value):
        raise ModelError(f"{where}: <{tag}> is NaN")
    return value
