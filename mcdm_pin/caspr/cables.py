"""CASPR's ``*_cables.xml``: one cable set of ideal cables.

Only ``cable_ideal`` is converted: springs, variable-stiffness cables and muscles change the force
with the length and are refused, naming the element and the type. Routes are lists of
``<attachment>`` points, the first possibly a rotating pulley (``base_rotating_pulley``,
``screw_base_rotating_pulley``: :mod:`.pulleys`). ``attachment_reference="com"`` points are measured
from the link's COM, ``"joint"`` from its joint point, both in the link frame; base points (link 0)
are absolute in either case.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import CasprError
from ._xml import child, integer, number, numbers, parse_xml, text
from .pulleys import PULLEYS, read_pulley

CABLE_TYPES = ("cable_ideal",)
OTHER_CABLES = {"cable_linear_spring": "a linear spring in series with the cable",
                "cable_passive_linear_spring": "a passive linear spring (its force follows its length)",
                "cable_vsd_torsion_spring": "a variable-stiffness device (torsion spring)",
                "cable_vsd_flexure_linear": "a variable-stiffness device (linear flexure)",
                "cable_vsd_polynomial": "a variable-stiffness device (polynomial)",
                "muscle_hill_type": "a Hill-type muscle",
                "pneumatic_artificial_muscle": "a pneumatic artificial muscle"}


@dataclass(frozen=True)
class CasprCable:
    name: str
    reference: str  # "com" or "joint"
    f_min: float
    f_max: float
    attachments: tuple[tuple[int, np.ndarray], ...]  # (link number, location as written)
    element: str
    pulley: object = None  # a pulleys.CasprPulley before the attachments (CASPR: first only), or None


@dataclass(frozen=True)
class CasprCableSet:
    path: Path
    id: str
    cables: tuple[CasprCable, ...]
    available: tuple[str, ...]
    default: str | None = None
    renamed: dict = field(default_factory=dict)  # {cable number (1-based): (CASPR name, our name)}


def cable_sets(path) -> tuple[tuple[str, ...], str | None]:
    """``(ids of the cable sets, default_cable_set)`` of a cables file."""
    path, root = parse_xml(path)
    sets = _sets(path, root)
    return tuple(sets), root.get("default_cable_set")


def _sets(path, root) -> dict:
    if root.tag != "cables":
        raise CasprError(path, f"<{root.tag}>", "expected the root element <cables>")
    sets = {}
    for el in root:
        if el.tag != "cable_set":
            raise CasprError(path, f"cables/<{el.tag}>", "unknown element; expected <cable_set>")
        sid = el.get("id")
        if not sid:
            raise CasprError(path, "cables/cable_set", "missing id attribute")
        if sid in sets:
            raise CasprError(path, f"cable_set[id={sid!r}]", "duplicate id (ids must be unique)")
        sets[sid] = el
    if not sets:
        raise CasprError(path, "cables", "no <cable_set>")
    return sets


def read_cables(path, bodies, cable_set: str | None = None) -> CasprCableSet:
    """Read one cable set of a CASPR ``*_cables.xml`` (default: ``default_cable_set``)."""
    path, root = parse_xml(path)
    sets = _sets(path, root)
    default = root.get("default_cable_set")
    if cable_set is None:
        if default is None:
            if len(sets) > 1:
                raise CasprError(path, "cables@default_cable_set",
                                 f"missing, and the file has {len(sets)} cable sets: choose one of "
                                 f"{', '.join(sets)} (--cable-set)")
            cable_set = next(iter(sets))
        elif default not in sets:
            raise CasprError(path, "cables@default_cable_set", f"names {default!r}, which is not a "
                                                               f"cable set; expected one of {', '.join(sets)}")
        else:
            cable_set = default
    elif cable_set not in sets:
        raise CasprError(path, "cable_set", f"no cable set {cable_set!r}; expected one of {', '.join(sets)}")
    cables, renamed = [], {}
    names: set[str] = set()
    for i, el in enumerate(sets[cable_set], start=1):
        cable, old = _read_cable(path, el, i, cable_set, len(bodies.links), names)
        if old is not None:
            renamed[i] = (old, cable.name)
        names.add(cable.name)
        cables.append(cable)
    if not cables:
        others = [s for s in sets if s != cable_set and len(sets[s])]
        hint = f"; choose another set ({', '.join(others)}) with --cable-set" if others else ""
        raise CasprError(path, f"cable_set[id={cable_set!r}]", f"the set has no cable; mcdm-pin needs at "
                                                               f"least one{hint}")
    return CasprCableSet(path=path, id=cable_set, cables=tuple(cables), available=tuple(sets),
                         default=default, renamed=renamed)


def _read_cable(path, el, i, set_id, n_links, names):
    name = el.get("name", "")
    where = f"cable_set[id={set_id!r}]/{el.tag}[{i}, name={name!r}]"
    if el.tag not in CABLE_TYPES:
        what = OTHER_CABLES.get(el.tag)
        reason = f"unsupported cable type <{el.tag}> ({what})" if what else f"unknown cable type <{el.tag}>"
        raise CasprError(path, where, f"{reason}; only <cable_ideal> is converted")
    if not name.strip():
        raise CasprError(path, where, "missing name attribute")
    old = None
    if name in names:
        # CASPR does not require unique names (the neck file has two pairs); the sidecar does
        k = 2
        while f"{name} #{k}" in names:
            k += 1
        old, name = name, f"{name} #{k}"
    ref = el.get("attachment_reference")
    if ref not in ("com", "joint"):
        raise CasprError(path, f"{where}@attachment_reference", f"expected 'com' or 'joint', got {ref!r}")
    props = child(path, el, "properties", where)
    f_min = number(path, text(path, props, "force_min", f"{where}/properties"), f"{where}/properties/force_min")
    f_max = number(path, text(path, props, "force_max", f"{where}/properties"), f"{where}/properties/force_max")
    if f_min < 0 or not f_max > f_min:
        raise CasprError(path, f"{where}/properties", f"expected 0 <= force_min < force_max, got "
                                                      f"force_min={f_min}, force_max={f_max}")
    atts, pulley = [], None
    for k, a in enumerate(child(path, el, "attachments", where), start=1):
        aw = f"{where}/attachments/{a.tag}[{k}]"
        if a.tag in PULLEYS:  # a rotating pulley: mcdm_pin.caspr.pulleys
            pulley = read_pulley(path, a, aw, k)
            continue
        if a.tag != "attachment":
            raise CasprError(path, aw, f"unknown element <{a.tag}>; expected <attachment>")
        link = integer(path, text(path, a, "link", aw), f"{aw}/link")
        if not 0 <= link <= n_links:
            raise CasprError(path, f"{aw}/link", f"expected a link number in 0..{n_links}, got {link}")
        atts.append((link, np.array(numbers(path, text(path, a, "location", aw), f"{aw}/location", 3))))
    if len(atts) < 2 - (pulley is not None):
        raise CasprError(path, f"{where}/attachments", f"expected at least two <attachment>, got {len(atts)}")
    if len({link for link, _ in atts} | ({0} if pulley else set())) < 2:
        raise CasprError(path, f"{where}/attachments", "every attachment is on the same link: the "
                                                       "cable cannot move anything")
    return CasprCable(name=name, reference=ref, f_min=f_min, f_max=f_max, attachments=tuple(atts),
                      element=where, pulley=pulley), old
