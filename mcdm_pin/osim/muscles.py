"""OpenSim muscle elements (``.osim`` XML) -> :class:`~mcdm_pin.model.muscles_osim.OpenSimMuscle`: the
properties each kind reads, with OpenSim 4.6's defaults where the file leaves one out, and the changes
OpenSim makes to Millard's curves for its damped model (:mod:`mcdm_pin.model.muscles_osim`)."""

from __future__ import annotations

import math

from ..exceptions import ModelError
from ..model.muscles_osim import (KINDS, MIN_DAMPING, SIGNIFICANT, OpenSimMuscle, active_force_length_curve,
                                  fiber_force_length_curve, force_velocity_curve)

_ACTIVE = {"min_norm_active_fiber_length": 0.47 - 0.0259, "transition_norm_fiber_length": 0.73,
           "max_norm_active_fiber_length": 1.8123, "shallow_ascending_slope": 0.8616, "minimum_value": 0.1}
_VELOCITY = {"concentric_slope_at_vmax": 0.0, "concentric_slope_near_vmax": 0.25, "isometric_slope": 5.0,
             "eccentric_slope_at_vmax": 0.0, "eccentric_slope_near_vmax": 0.15,
             "max_eccentric_velocity_force_multiplier": 1.4, "concentric_curviness": 0.6,
             "eccentric_curviness": 0.9}
_PASSIVE = {"strain_at_zero_force": 0.0, "strain_at_one_norm_force": 0.7}
_PASSIVE_OPTIONAL = ("stiffness_at_low_force", "stiffness_at_one_norm_force", "curviness")


def _number(el, tag: str, where: str, default=None) -> float:
    node = None if el is None else el.find(tag)
    if node is None or node.text is None or not node.text.strip():
        if default is None:
            raise ModelError(f"{where}: missing <{tag}>")
        return float(default)
    try:
        x = float(node.text.split()[0])
    except ValueError:
        raise ModelError(f"{where}: <{tag}>: expected a number, got {node.text.strip()!r}") from None
    if not math.isfinite(x):
        raise ModelError(f"{where}: <{tag}>: expected a finite number, got {node.text.strip()!r}")
    return x


def _curve_element(force, tag: str):
    node = force.find(tag)
    if node is None:
        return None
    inner = node.find(tag)  # <ActiveForceLengthCurve><ActiveForceLengthCurve name=...> in 4.x files
    return inner if inner is not None else node


def _millard_curves(force, damping: float, where: str) -> tuple:
    el = _curve_element(force, "ActiveForceLengthCurve")
    a = {k: _number(el, k, f"{where}: ActiveForceLengthCurve", v) for k, v in _ACTIVE.items()}
    el = _curve_element(force, "ForceVelocityCurve")
    v = {k: _number(el, k, f"{where}: ForceVelocityCurve", d) for k, d in _VELOCITY.items()}
    el = _curve_element(force, "FiberForceLengthCurve")
    p = {k: _number(el, k, f"{where}: FiberForceLengthCurve", d) for k, d in _PASSIVE.items()}
    given = [el is not None and el.find(k) is not None and (el.find(k).text or "").strip() for k in _PASSIVE_OPTIONAL]
    if all(given):
        k_low, k_iso, curv = (_number(el, k, f"{where}: FiberForceLengthCurve") for k in _PASSIVE_OPTIONAL)
    elif not any(given):
        k_iso, k_low, curv = 2.0 / (p["strain_at_one_norm_force"] - p["strain_at_zero_force"]), 0.2, 0.75
    else:
        raise ModelError(f"{where}: FiberForceLengthCurve: stiffness_at_low_force, stiffness_at_one_norm_force "
                         f"and curviness must all be given or all be left out (OpenSim's rule)")
    if damping >= MIN_DAMPING:  # OpenSim's damped model
        a["minimum_value"] = 0.0
        v["concentric_slope_at_vmax"] = min(v["concentric_slope_at_vmax"], 0.0)
        v["eccentric_slope_at_vmax"] = min(v["eccentric_slope_at_vmax"], 0.0)
    fl = active_force_length_curve(a["min_norm_active_fiber_length"], a["transition_norm_fiber_length"],
                                   a["max_norm_active_fiber_length"], a["minimum_value"], a["shallow_ascending_slope"])
    fv = force_velocity_curve(v["max_eccentric_velocity_force_multiplier"], v["concentric_slope_at_vmax"],
                              v["concentric_slope_near_vmax"], v["isometric_slope"], v["eccentric_slope_at_vmax"],
                              v["eccentric_slope_near_vmax"], v["concentric_curviness"], v["eccentric_curviness"])
    fp = fiber_force_length_curve(p["strain_at_zero_force"], p["strain_at_one_norm_force"], k_low, k_iso, curv)
    return (fl, fv, fp), a["min_norm_active_fiber_length"]


def read_muscle(force, file) -> OpenSimMuscle:
    """The muscle of an OpenSim force element (a kind of :data:`~mcdm_pin.model.muscles_osim.KINDS`)."""
    name = force.get("name")
    where = f"{file}: {force.tag} {name!r}"
    if force.tag not in KINDS:
        raise ModelError(f"{where}: {force.tag} is not modelled with a rigid tendon; expected one of {KINDS}")
    f0 = _number(force, "max_isometric_force", where)
    lo = _number(force, "optimal_fiber_length", where)
    ls = _number(force, "tendon_slack_length", where)
    alpha0 = _number(force, "pennation_angle_at_optimal", where, 0.0)
    vmax = _number(force, "max_contraction_velocity", where, 10.0)
    if force.tag == KINDS[0]:
        damping = _number(force, "fiber_damping", where, 0.1)
        damping = damping if damping >= MIN_DAMPING else 0.0
        a_min = _number(force, "minimum_activation", where, 0.01)
        a_min = min(max(a_min, 0.0), 1.0) if damping > 0 else a_min
        max_pen = _number(force, "maximum_pennation_angle", where, math.acos(0.1))
        curves, x0 = _millard_curves(force, damping, where)
        h = lo * math.sin(alpha0)
        pen_min = h / math.sin(max_pen) if max_pen > SIGNIFICANT else 0.01 * lo
        return OpenSimMuscle(name, force.tag, f0, lo, ls, alpha0, vmax, damping, a_min, 1.0, curves, max_pen,
                             max(SIGNIFICANT, x0 * lo, pen_min))
    if force.tag == "Thelen2003Muscle":
        return _thelen(force, where, name, f0, lo, ls, alpha0, vmax)
    damping = _number(force, "fiber_damping", where, 0.0)
    width = _number(force, "active_force_width_scale", where, 1.0)
    e0 = _number(force, "passive_fiber_strain_at_one_norm_force", where, 0.6)
    node = force.find("ignore_passive_fiber_force")
    passive = not (node is not None and (node.text or "").strip().lower() == "true")
    a_min = _number(force, "min_control", where, 0.0)
    a_max = _number(force, "max_control", where, 1.0)
    return OpenSimMuscle(name, force.tag, f0, lo, ls, alpha0, vmax, damping, max(a_min, 0.0), min(a_max, 1.0),
                         (width, e0, passive))


_THELEN = {"KshapeActive": 0.45, "KshapePassive": 5.0, "FmaxMuscleStrain": 0.6, "Af": 0.25, "Flen": 1.4,
           "fv_linear_extrap_threshold": 0.95}


def _thelen(force, where, name, f0, lo, ls, alpha0, vmax) -> OpenSimMuscle:
    """Thelen2003Muscle: its curve constants (OpenSim 4.6's defaults where left out, and its checks),
    the activation in ``[minimum_activation, 1]`` and the pennation model's minimum fiber length."""
    c = {k: _number(force, k, where, d) for k, d in _THELEN.items()}
    for k in ("KshapeActive", "KshapePassive", "FmaxMuscleStrain", "Af"):
        if not c[k] > 0:
            raise ModelError(f"{where}: <{k}>: expected a number > 0, got {c[k]!r}")
    if not c["Flen"] > 1.0:
        raise ModelError(f"{where}: <Flen>: expected a number > 1, got {c['Flen']!r}")
    if not 1.0 / c["Flen"] < c["fv_linear_extrap_threshold"] < 1.0:
        raise ModelError(f"{where}: <fv_linear_extrap_threshold>: expected a number in (1/Flen, 1), got "
                         f"{c['fv_linear_extrap_threshold']!r}")
    a_min = _number(force, "minimum_activation", where, 0.01)
    if not 0.01 <= a_min <= 1.0:
        raise ModelError(f"{where}: <minimum_activation>: expected a number in [0.01, 1] (OpenSim's rule), "
                         f"got {a_min!r}")
    max_pen = _number(force, "maximum_pennation_angle", where, math.acos(0.1))
    if not 0.0 <= max_pen <= math.pi / 2:
        raise ModelError(f"{where}: <maximum_pennation_angle>: expected a number in [0, pi/2], got {max_pen!r}")
    h = lo * math.sin(alpha0)
    min_fiber = h / math.sin(max_pen) if max_pen > SIGNIFICANT else 0.01 * lo
    return OpenSimMuscle(name, force.tag, f0, lo, ls, alpha0, vmax, 0.0, a_min, 1.0,
                         tuple(c[k] for k in _THELEN), max_pen, min_fiber)
