"""A sidecar's ``springs:``: passive springs whose tension is known, a function of their length
(:mod:`mcdm_pin.model.springs`; the format in ``docs/sidecar.md``). Plain data, no Pinocchio."""

from __future__ import annotations

from dataclasses import dataclass

from .limits import MAX_CABLES, MAX_ROUTE_POINTS
from .sidecar_reader import _kind

SPRING_KEYS = ("name", "stiffness", "rest_length", "tension_only", "route")


@dataclass(frozen=True)
class SpringSpec:
    """A passive spring (:mod:`mcdm_pin.model.springs`): a route as a cable's, ``stiffness`` (N/m) and
    ``rest_length`` (m); its tension ``stiffness (length - rest_length)`` is known, not solved for."""

    name: str
    stiffness: float
    rest_length: float
    route: tuple
    tension_only: bool = False
    key: str = ""


def parse_springs(r, raw, parse_route_element) -> tuple[SpringSpec, ...]:
    """``springs:`` a list of ``{name, stiffness, rest_length, route[, tension_only]}``, read with the
    sidecar's reader ``r`` (its key paths and messages) and route-element parser."""
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise r.fail("springs", f"expected a list of springs {{name, stiffness, rest_length, route}}, got {_kind(raw)}")
    if len(raw) > MAX_CABLES:
        raise r.fail("springs", f"expected at most {MAX_CABLES} springs (docs/limits.md), got {len(raw)}")
    out, names = [], {}
    for i, spec in enumerate(raw):
        key = f"springs[{i}]"
        spec = r.mapping(spec, key, SPRING_KEYS, required=("name", "stiffness", "rest_length", "route"))
        name = r.string(spec["name"], f"{key}.name")
        if name in names:
            raise r.fail(f"{key}.name", f"spring name {name!r} is already used by springs[{names[name]}]")
        names[name] = i
        only = spec.get("tension_only", False)
        if not isinstance(only, bool):
            raise r.fail(f"{key}.tension_only", f"expected true or false, got {_kind(only)}")
        route = spec["route"]
        if not isinstance(route, list) or len(route) < 2 or len(route) > MAX_ROUTE_POINTS:
            got = f"{len(route)} point(s)" if isinstance(route, list) else _kind(route)
            raise r.fail(f"{key}.route", f"expected a list of 2 to {MAX_ROUTE_POINTS} {{link, point}}, got {got}")
        out.append(SpringSpec(name=name, stiffness=r.number(spec["stiffness"], f"{key}.stiffness", lo=0.0),
                              rest_length=r.number(spec["rest_length"], f"{key}.rest_length", lo=0.0),
                              route=tuple(parse_route_element(r, p, f"{key}.route[{k}]") for k, p in enumerate(route)),
                              tension_only=only, key=key))
    return tuple(out)
