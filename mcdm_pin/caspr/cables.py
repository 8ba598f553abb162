"""CASPR's ``*_cables.xml``: one cable set of cables (unknown tensions) and passive springs (known ones).

What each CASPR cable model becomes (``src/Model/Cables/CableModels`` at ``a6971ee``):

- ``cable_ideal``: a cable, its tension the unknown within ``[force_min, force_max]``.
- ``cable_linear_spring`` and the variable-stiffness cables ``cable_vsd_torsion_spring``,
  ``cable_vsd_flexure_linear``, ``cable_vsd_polynomial``: CASPR keeps them *active* (``isActive``
  true): in inverse dynamics each is a cable whose tension is the unknown, within ``[force_min,
  force_max]``, exactly as an ideal cable. Their stiffness parameters (``K_cable``, the torsion springs,
  the flexure's force-deformation coefficients, the polynomial's) give the cable's stiffness ``K`` as a
  function of that tension and its length, which CASPR uses in stiffness analysis, not in inverse
  dynamics; they are read (:attr:`CasprCable.stiffness`) and named in the sidecar's description.
- ``cable_passive_linear_spring``: a passive spring (CASPR's ``isActive`` false), its tension
  *given* by its length, ``K (length - l0)`` (not clipped at zero, as in CASPR's
  ``CableModelPassiveLinearSpring.update``): a sidecar ``springs:`` entry
  (:mod:`mcdm_pin.model.springs`), moved to the right-hand side of the equation of motion.
- ``muscle_hill_type``, ``pneumatic_artificial_muscle`` (no model of the library uses them): refused.

Routes are lists of ``<attachment>`` points, the first possibly a rotating pulley
(``base_rotating_pulley``, ``screw_base_rotating_pulley``: :mod:`.pulleys`). ``attachment_reference="com"`` points are measured from the
link's COM, ``"joint"`` from its joint point, both in the link frame; base points (link 0) are absolute
in either case.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import CasprError
from ._xml import child, integer, number, numbers, parse_xml, text
from .pulleys import PULLEYS, read_pulley

CABLE_TYPES = ("cable_ideal",)
# active cables whose stiffness follows their tension: in inverse dynamics, cables (docstring); the
# stiffness parameters each reads
STIFFNESS_CABLES = {"cable_linear_spring": ("K",),
                    "cable_vsd_torsion_spring": ("K_cable", "num_torsion_springs", "torsion_spring_stiffness",
                                                 "torsion_spring_length"),
                    "cable_vsd_flexure_linear": ("K_cable", "vsd_force_deformation_relation"),
                    "cable_vsd_polynomial": ("K_cable", "num_stiffness_polynomial_coeff")}
SPRING_TYPES = ("cable_passive_linear_spring",)
OTHER_CABLES = {"muscle_hill_type": "a Hill-type muscle",
                "pneumatic_artificial_muscle": "a pneumatic artificial muscle"}


@dataclass(frozen=True)
class CasprCable:
    """A cable (``kind`` its CASPR element) or, ``kind == "cable_passive_linear_spring"``, a passive
    spring: then ``f_min``/``f_max`` are unused and ``stiffness`` holds ``K`` (N/m) and ``l0`` (m)."""

    name: str
    reference: str  # "com" or "joint"
    f_min: float
    f_max: float
    attachments: tuple[tuple[int, np.ndarray], ...]  # (link number, location as written)
    element: str
    pulley: object = None  # a pulleys.CasprPulley before the attachments (CASPR: first only), or None
    kind: str = "cable_ideal"
    stiffness: dict = field(default_factory=dict)  # CASPR's stiffness parameters, as written

    @property
    def passive(self) -> bool:
        """A passive spring: its tension is known (``K (l - l0)``), not solved for."""
        return self.kind in SPRING_TYPES


@dataclass(frozen=True)
class CasprCableSet:
    path: Path
    id: str
    cables: tuple[CasprCable, ...]  # the active cables (unknown tensions), in CASPR's order
    available: tuple[str, ...]
    default: str | None = None
    renamed: dict = field(default_factory=dict)  # {cable number (1-based): (CASPR name, our name)}
    note: str = ""  # why this set was taken when it is not the file's default (the default is empty)
    springs: tuple[CasprCable, ...] = ()  # the passive springs (known tensions), in CASPR's order


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
    asked = cable_set
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
    note = ""
    if asked is None and not len(sets[cable_set]):
        # an empty default set (PlanarSnakeArm's 'Empty'): the first set with a cable, said so
        others = [s for s in sets if len(sets[s])]
        if others:
            note = (f"the default cable set {cable_set!r} has no cable; took the first set with cables, "
                    f"{others[0]!r} (choose another with --cable-set)")
            cable_set = others[0]
    cables, renamed = [], {}
    names: set[str] = set()
    for i, el in enumerate(sets[cable_set], start=1):
        cable, old = _read_cable(path, el, i, cable_set, len(bodies.links), names)
        if old is not None:
            renamed[i] = (old, cable.name)
        names.add(cable.name)
        cables.append(cable)
    springs = tuple(c for c in cables if c.passive)
    cables = [c for c in cables if not c.passive]
    if not cables:
        others = [s for s in sets if s != cable_set and len(sets[s])]
        hint = f"; choose another set ({', '.join(others)}) with --cable-set" if others else ""
        raise CasprError(path, f"cable_set[id={cable_set!r}]", f"the set has no cable; mcdm-pin needs at "
                                                               f"least one{hint}")
    return CasprCableSet(path=path, id=cable_set, cables=tuple(cables), available=tuple(sets),
                         default=default, renamed=renamed, note=note, springs=springs)


def _read_cable(path, el, i, set_id, n_links, names):
    name = el.get("name", "")
    where = f"cable_set[id={set_id!r}]/{el.tag}[{i}, name={name!r}]"
    if el.tag not in CABLE_TYPES + SPRING_TYPES + tuple(STIFFNESS_CABLES):
        what = OTHER_CABLES.get(el.tag)
        reason = f"unsupported cable type <{el.tag}> ({what})" if what else f"unknown cable type <{el.tag}>"
        raise CasprError(path, where, f"{reason}; expected <cable_ideal>, <cable_passive_linear_spring>, "
                                      f"<cable_linear_spring> or a <cable_vsd_*>")
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
    pw = f"{where}/properties"
    stiffness: dict = {}
    if el.tag in SPRING_TYPES:  # CableModelPassiveLinearSpring.LoadXmlObj: <K>, <l0>
        f_min = f_max = 0.0
        for k in ("K", "l0"):
            stiffness[k] = number(path, text(path, props, k, pw), f"{pw}/{k}")
            if not stiffness[k] >= 0:
                raise CasprError(path, f"{pw}/{k}", f"expected a number >= 0, got {stiffness[k]}")
    else:
        f_min = number(path, text(path, props, "force_min", pw), f"{pw}/force_min")
        f_max = number(path, text(path, props, "force_max", pw), f"{pw}/force_max")
        if f_min < 0 or not f_max > f_min:
            raise CasprError(path, pw, f"expected 0 <= force_min < force_max, got "
                                       f"force_min={f_min}, force_max={f_max}")
        for k in STIFFNESS_CABLES.get(el.tag, ()):  # given, not used by inverse dynamics
            stiffness[k] = text(path, props, k, pw).strip()
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
                      element=where, pulley=pulley, kind=el.tag, stiffness=stiffness), old
