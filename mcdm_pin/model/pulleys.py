r"""Rotating (kingpin) pulleys and screw-driven winch outlets: the cable's exit point, computed at each
instant, as CASPR's ``BaseRotatingPulleyAttachment`` and ``ScrewDriveRotatingPulleyAttachment`` define
it (``src/Model/Cables/CableAttachments`` at CASPR commit ``a6971ee``, read again from their
description, not copied).

**Rotating pulley.** A pulley of radius :math:`R` swivels freely about the line through its *entry
point* :math:`F` along the *entry direction* :math:`\hat u` (the direction the cable runs in as it
reaches :math:`F`, from a winch on the same body; CASPR's ``cable_entry_vector``). That line is
tangent to the pulley at :math:`F`, so :math:`F` stays put while the pulley turns to face the cable's
other end :math:`B`. All points are in the frame of the body carrying the pulley (metres). With
:math:`d = B - F`, its part across the axis :math:`d_\perp = d - (d\cdot\hat u)\hat u` and
:math:`\hat e = d_\perp/|d_\perp|`:

.. math::

    C = F + R\hat e, \qquad
    B - C = (b_x, b_y) = (|d_\perp| - R,\; d\cdot\hat u) \text{ in the axes } (\hat e, \hat u),

the cable wraps from :math:`F` round the circle of centre :math:`C` by the angle

.. math::

    \theta = \operatorname{atan2}(b_x, b_y) + \operatorname{atan2}(R, s) \in (0, 2\pi), \qquad
    s = \sqrt{|B - C|^2 - R^2} = |B - A|,

and leaves it at the exit point :math:`A = C + R(-\cos\theta\,\hat e + \sin\theta\,\hat u)` along
:math:`(\sin\theta\,\hat e + \cos\theta\,\hat u)`, straight to :math:`B`. The cable's length from
:math:`F` is :math:`R\theta + |B - A|`: CASPR counts both, the arc as the attachment's
``length_offset`` (``R acos(n_1 \cdot n_2)``, the angle between the radii to :math:`F` and :math:`A`:
the same number for :math:`\theta \le \pi`; beyond, where :math:`B` lies behind the axis, ``acos``
folds the angle back and CASPR's length is no longer the cable's; here it is).

:math:`B` on the swivel axis (:math:`d_\perp = 0`: the plane of the pulley is undefined) or inside the
circle (:math:`|B - C| \le R`) has no exit point: the pass reports it (``REASON_*``).

**Derivative.** At fixed swivel angle, :math:`A` is the tangent point of the shortest path from
:math:`F` over the circle to :math:`B`, and turning the swivel moves :math:`B` out of the pulley's
plane only to second order in the length. So the length changes, to first order, as if :math:`A` were
a point fixed on the pulley's body: with :math:`A` so fixed at the instant, the straight-segment
formulas give :math:`L = \partial\ell/\partial q` and the wrenches exactly (the envelope theorem, as
for wraps: :mod:`mcdm_pin.model.routes`). The arc adds length and no wrench: the cable's pull on the
pulley and its winch, one body, is the segment :math:`A B`'s pull at :math:`A`.

**Screw-driven outlet** (CASPR's ``screw_base_rotating_pulley``): the pulley's entry point rides on
a winch whose drum advances along :math:`v` (``winch_vector``) by :math:`k = h/(\pi D)` (groove width
over the drum's circumference) per metre of cable paid out. CASPR's steady rule (every update after
its first): the paid-out length :math:`\delta` solves

.. math:: |B - W - k\delta v| = \ell_0 + \delta

(the larger root), :math:`W` the fixed winch point (``constant_winch_point``), :math:`\ell_0 = |B_0 -
W|` at the model's initial configuration, and the entry point is :math:`F = W + (t_0 + k\delta) v`,
:math:`t_0` the outlet's initial position (CASPR reads it from an encoder: 0.066851 m). The exit point
and arc then follow as above, with the pulley's own entry direction. CASPR's very first update
places the outlet at :math:`W + 0.03 v` instead; that one-off is not reproduced. Here :math:`F` moves
with :math:`q`: the exit point fixed at the instant gives the force the cable applies (CASPR's ``V``,
the physics of the robot), and ``L`` is the length's derivative at a fixed outlet; the full derivative
adds the outlet's motion, :math:`O(k)` smaller (the winch's screw, not the cable, moves it).

The functions are ``register_jitable``: plain Python when called from Python, compiled inline into the
route pass (:mod:`mcdm_pin.model.route_kernels`) by ``mcdm-pin compile``.
"""

from __future__ import annotations

import math

from ..jit import extending  # register_jitable: compiled inline into the njit route pass

register_jitable = extending.register_jitable

MINVAL = 1e-15
REASON_OK, REASON_ON_AXIS, REASON_INSIDE, REASON_SCREW = 0, 1, 2, 3
REASONS = {REASON_ON_AXIS: "the cable's other end lies on the pulley's swivel axis (the pulley's plane is "
                           "undefined)",
           REASON_INSIDE: "the cable's other end lies inside the pulley's circle (no tangent exit point)",
           REASON_SCREW: "the screw winch's paid-out length has no real solution"}


@register_jitable
def rotating_exit(F, u, radius, B):
    """The exit point of a rotating pulley (module docstring), all points in one frame.

    Args:
        F: (3-tuple) the entry point; u: the entry direction (any length > 0); radius: metres;
        B: the cable's other end.

    Returns ``(reason, arc, A)``: ``REASON_OK`` (0) or why there is none, the arc length
    :math:`R\\theta` (metres) and the exit point (3-tuple; zeros when there is none)."""
    zero = (0.0, 0.0, 0.0)
    un = math.sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2])
    if un < MINVAL:
        return REASON_ON_AXIS, 0.0, zero
    ux, uy, uz = u[0] / un, u[1] / un, u[2] / un
    dx, dy, dz = B[0] - F[0], B[1] - F[1], B[2] - F[2]
    along = dx * ux + dy * uy + dz * uz
    px, py, pz = dx - along * ux, dy - along * uy, dz - along * uz
    pn = math.sqrt(px * px + py * py + pz * pz)
    if pn < MINVAL * max(1.0, math.sqrt(dx * dx + dy * dy + dz * dz)):
        return REASON_ON_AXIS, 0.0, zero
    ex, ey, ez = px / pn, py / pn, pz / pn
    bx, by = pn - radius, along
    s2 = bx * bx + by * by - radius * radius
    if not s2 > 0.0:
        return REASON_INSIDE, 0.0, zero
    theta = math.atan2(bx, by) + math.atan2(radius, math.sqrt(s2))
    if theta < 0.0:
        theta += 2.0 * math.pi
    c, s = math.cos(theta), math.sin(theta)
    # A = C + R(-cos theta e + sin theta u), C = F + R e
    A = (F[0] + radius * ((1.0 - c) * ex + s * ux), F[1] + radius * ((1.0 - c) * ey + s * uy),
         F[2] + radius * ((1.0 - c) * ez + s * uz))
    return REASON_OK, radius * theta, A


@register_jitable
def screw_entry(W, v, lead, reference, outlet, B):
    """The entry point of a pulley on a screw-driven winch outlet (module docstring): ``(ok, F)``.

    ``W`` the fixed winch point, ``v`` the drum's travel direction (as given: CASPR does not normalise
    it), ``lead`` :math:`k` (m of travel per m of cable), ``reference`` :math:`\\ell_0` (m), ``outlet``
    :math:`t_0` (m along ``v``), ``B`` the cable's other end; the larger root of
    :math:`(1 - k^2 v\\cdot v)\\delta^2 + 2(\\ell_0 + k c\\cdot v)\\delta + \\ell_0^2 - c\\cdot c = 0`,
    :math:`c = B - W`, computed without cancellation."""
    cx, cy, cz = B[0] - W[0], B[1] - W[1], B[2] - W[2]
    cv = cx * v[0] + cy * v[1] + cz * v[2]
    vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    c1 = 1.0 - lead * lead * vv
    half_c2 = reference + lead * cv
    c3 = reference * reference - (cx * cx + cy * cy + cz * cz)
    disc = half_c2 * half_c2 - c1 * c3
    if disc < 0.0 or not c1 > 0.0:
        return False, (0.0, 0.0, 0.0)
    root = math.sqrt(disc)
    if half_c2 > 0.0:
        delta = -c3 / (half_c2 + root)  # = (-half_c2 + root) / c1, the larger root
    else:
        delta = (-half_c2 + root) / c1
    t = outlet + lead * delta
    return True, (W[0] + t * v[0], W[1] + t * v[1], W[2] + t * v[2])
