"""The sidecar's ``rotating_pulley`` route element (docs/sidecar.md): parsed into plain data, as the
other route elements are in :mod:`mcdm_pin.sidecar` (no Pinocchio here)."""

from __future__ import annotations

import math
from dataclasses import dataclass

ROTATING_KEYS = ("rotating_pulley", "link", "entry", "axis", "screw")
SCREW_KEYS = ("direction", "lead", "reference", "outlet")


@dataclass(frozen=True)
class RotatingPulleySpec:
    """A rotating pulley at the start or end of a route (fed from a winch on ``link``): ``radius``,
    ``entry`` point and ``axis`` (the cable's entry direction) in the link's frame; ``screw`` ``None``
    or ``(direction, lead, reference, outlet)`` of a screw-driven outlet (``entry`` is then the winch
    point)."""

    link: str
    radius: float
    entry: tuple[float, float, float]
    axis: tuple[float, float, float]
    screw: tuple | None = None
    key: str = ""


def parse_rotating(r, p, pkey: str) -> RotatingPulleySpec:
    """``{rotating_pulley: radius, link, entry, axis[, screw: {direction, lead, reference, outlet}]}``, read
    with the sidecar's reader ``r`` (its checks and messages); ``pkey`` the element's key path."""
    p = r.mapping(p, pkey, ROTATING_KEYS, required=("rotating_pulley", "link", "entry", "axis"))
    axis = r.vector(p["axis"], f"{pkey}.axis")
    if not math.sqrt(sum(a * a for a in axis)) > 1e-12:
        raise r.fail(f"{pkey}.axis", f"expected a nonzero vector (the cable's entry direction), got {list(axis)}")
    screw = None
    if p.get("screw") is not None:
        sk = f"{pkey}.screw"
        sp = r.mapping(p["screw"], sk, SCREW_KEYS, required=SCREW_KEYS)
        direction = r.vector(sp["direction"], f"{sk}.direction")
        lead = r.number(sp["lead"], f"{sk}.lead", lo=0.0)
        if not lead * math.sqrt(sum(a * a for a in direction)) < 1.0:
            raise r.fail(f"{sk}.lead", f"expected lead * |direction| < 1, got lead {lead!r}")
        screw = (direction, lead, r.number(sp["reference"], f"{sk}.reference", lo=0.0, lo_open=True),
                 r.number(sp["outlet"], f"{sk}.outlet"))
    return RotatingPulleySpec(link=r.string(p["link"], f"{pkey}.link"),
                              radius=r.number(p["rotating_pulley"], f"{pkey}.rotating_pulley", lo=0.0, lo_open=True),
                              entry=r.vector(p["entry"], f"{pkey}.entry"), axis=axis, screw=screw, key=pkey)
