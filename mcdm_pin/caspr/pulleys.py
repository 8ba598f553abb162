r"""CASPR's pulley attachments -> rotating pulleys of the model layer (:mod:`mcdm_pin.model.pulleys`).

CASPR (``src/Model/Cables/CableAttachments`` and ``CableModelBase.LoadSegmentsXmlObj`` at ``a6971ee``)
has two, each allowed only as a cable's first attachment and fixed to the base (link 0):

- ``<base_rotating_pulley>`` (``BaseRotatingPulleyAttachment``): ``fixed_location`` the point ``F``
  where the cable enters the pulley, ``cable_entry_vector`` its direction there, ``pulley_radius``.
  The pulley swivels about that entry line to face the cable's next attachment; the cable's length
  is the arc on the pulley (the attachment's ``length_offset``) plus the straight segment from the
  exit point.
- ``<screw_base_rotating_pulley>`` (``ScrewDriveRotatingPulleyAttachment``): the same pulley
  (``pulley_radius``, ``cable_pulley_entry_vector``) on a winch outlet that a screw moves along
  ``winch_vector`` from ``constant_winch_point`` by ``winch_groove_width / (pi * 2 winch_radius)`` per
  metre of cable paid out, measured from the model's initial configuration (``q_initial``, CASPR's
  first update) where the outlet stands at :data:`OUTLET` (CASPR's ``obtainInitialOutletPose``:
  ``28032e-6 + 0.038819`` m, a stand-in for an encoder reading).

Of CASPR's library, ``SpiderBot_UR3`` (cable set ``CUcablerobot``, its default) and ``CAROCA``
(``with_rotating_pulleys``) use the first, ``SpiderBot_UR3_Test`` (both sets) the second.

Each becomes a sidecar ``rotating_pulley`` element at the start of the route, on the ``base`` link
(docs/sidecar.md); a screw's reference length :math:`\ell_0 = |B(q_\text{initial}) - W|` is computed
on the imported robot (:func:`fill_screw_references`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..exceptions import CasprError
from ._xml import number, numbers, text

PULLEYS = ("base_rotating_pulley", "screw_base_rotating_pulley")
OUTLET = 28032e-6 + 0.038819
"""Metres: CASPR's initial outlet position on a screw-driven winch (``obtainInitialOutletPose``)."""


@dataclass(frozen=True)
class CasprPulley:
    """A pulley attachment as read: ``entry`` (``fixed_location``, or the ``constant_winch_point`` of a
    screw) and ``axis`` (the cable's entry vector) in the base frame, metres; ``radius``; with a screw,
    ``winch_vector``, ``lead`` (groove width over the drum's circumference); ``element`` for
    messages."""

    tag: str
    entry: tuple[float, float, float]
    axis: tuple[float, float, float]
    radius: float
    winch_vector: tuple[float, float, float] | None
    lead: float | None
    element: str

    @property
    def screw(self) -> bool:
        return self.winch_vector is not None


def read_pulley(path, el, where: str, position: int) -> CasprPulley:
    """The pulley attachment ``el`` (``where`` names it); ``position`` its 1-based place among the
    cable's attachments (CASPR accepts it only first)."""
    if position != 1:
        raise CasprError(path, where, f"<{el.tag}> must be the cable's first attachment (CASPR asserts it), "
                                      f"found at position {position}")

    def vec(tag):
        return numbers(path, text(path, el, tag, where), f"{where}/{tag}", 3)

    def positive(tag):
        x = number(path, text(path, el, tag, where), f"{where}/{tag}")
        if not x > 0:
            raise CasprError(path, f"{where}/{tag}", f"expected a number > 0 (metres), got {x!r}")
        return x

    if el.tag == "base_rotating_pulley":
        entry, axis, winch, lead = vec("fixed_location"), vec("cable_entry_vector"), None, None
    else:
        entry, axis, winch = vec("constant_winch_point"), vec("cable_pulley_entry_vector"), vec("winch_vector")
        groove = number(path, text(path, el, "winch_groove_width", where), f"{where}/winch_groove_width")
        lead = groove / (math.pi * 2.0 * positive("winch_radius"))
        if not (groove >= 0 and lead * math.hypot(*winch) < 1):
            raise CasprError(path, f"{where}/winch_groove_width", f"expected 0 <= groove width < the drum's "
                                                                 f"circumference / |winch_vector|, got {groove!r}")
    if not math.hypot(*axis) > 0:
        raise CasprError(path, where, "the cable's entry vector is zero; expected a direction")
    return CasprPulley(tag=el.tag, entry=entry, axis=axis, radius=positive("pulley_radius"), winch_vector=winch,
                       lead=lead, element=where)


def sidecar_element(p: CasprPulley) -> dict:
    """The sidecar route element of ``p`` (its screw's ``reference`` a placeholder of 1 m until
    :func:`fill_screw_references`)."""
    out = {"rotating_pulley": p.radius, "link": "base", "entry": _list(p.entry), "axis": _list(p.axis)}
    if p.screw:
        out["screw"] = {"direction": _list(p.winch_vector), "lead": p.lead, "reference": 1.0, "outlet": OUTLET}
    return out


def _list(v) -> list:
    return [float(x) + 0.0 for x in v]


def fill_screw_references(cables: list, robot, bodies, layout) -> bool:
    """Write each screw pulley's reference length :math:`|B - W|` at CASPR's ``q_initial`` into the
    sidecar ``cables`` (data), ``B`` the route point the pulley faces, measured on ``robot`` (the
    imported robot, ``layout`` its CASPR links' velocity indices). Returns whether any was written."""
    import pinocchio as pin

    from .sampling import coordinates_from_caspr

    screws = [c for c in cables if "screw" in c["route"][0]]
    if not screws:
        return False
    q0 = np.concatenate([link.q_initial for link in bodies.links])
    q = robot.configuration(coordinates_from_caspr(bodies, layout, q0, robot.nv))
    model = robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    for c in screws:
        first, b = c["route"][0], c["route"][1]
        B = data.oMf[model.getFrameId(b["link"])].act(np.array(b["point"]))
        first["screw"]["reference"] = float(np.linalg.norm(B - np.array(first["entry"])))
    return True
