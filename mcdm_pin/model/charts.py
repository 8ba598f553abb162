r"""Coordinates (one number per degree of freedom) and Pinocchio's configuration vector.

Pinocchio's configuration ``q`` has ``nq`` entries (a quaternion joint stores 4 numbers, a continuous
joint cos/sin); its velocity ``v`` and acceleration ``a`` have ``nv`` entries: the joint frame's twist
in its own (child) frame and that twist's time derivative. Users type and read **coordinates**, ``nv``
numbers, joint by joint:

=======================================  =============================================  ===========
Pinocchio joint                          coordinates                                    names
=======================================  =============================================  ===========
``JointModelSpherical`` (quaternion)     rotation vector :math:`\theta` = log3(R)       NAME.rx/ry/rz
``JointModelFreeFlyer``                  position p (parent frame), rotation vector     NAME.x/y/z/rx/ry/rz
``JointModelPlanar``                     x, y, angle                                    NAME.x/y/theta
continuous (``RUB*``)                    the angle                                      NAME
every joint with nq == nv                the configuration itself                       NAME or NAME.0, .1, ...
=======================================  =============================================  ===========

(A composite joint is charted part by part.) Rates map to the tangent space exactly:
:math:`\omega = J_r(\theta)\dot\theta`, :math:`\dot\omega = J_r\ddot\theta + \dot J_r\dot\theta` with
:math:`J_r` the right Jacobian of SO(3) (``pin.Jexp3``), and for a translation expressed in the parent
frame :math:`v = R^T\dot p`, :math:`\dot v = R^T\ddot p - \omega\times v`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import ModelError, StateError

# chart kinds
IDENTITY, ANGLE, BALL, FREE, PLANAR = "identity", "angle", "ball", "free", "planar"

# a quaternion's norm, or the norm of a (cos, sin) pair, may differ from 1 by this much (it is then
# normalised); beyond it the configuration is refused
UNIT_NORM_TOL = 1e-6


@dataclass(frozen=True)
class Part:
    """One charted piece of the configuration: a primitive Pinocchio joint (or a composite's part)."""

    kind: str
    joint: str  # the Pinocchio joint's name
    idx_q: int
    nq: int
    idx_v: int
    nv: int
    suffixes: tuple[str, ...]  # coordinate name suffixes ("" for a single coordinate)


def _primitive_parts(jm, name: str, idx_q: int, idx_v: int, tag: str) -> list[Part]:
    short = jm.shortname()
    if short == "JointModelComposite":
        jm = jm.extract() if hasattr(jm, "extract") else jm
        parts = []
        for k, sub in enumerate(jm.joints):
            parts += _primitive_parts(sub, name, idx_q + sub.idx_q - jm.idx_q, idx_v + sub.idx_v - jm.idx_v,
                                      f"{tag}{k}.")
        return parts
    if short == "JointModelMimic":
        raise ModelError(f"joint {name!r} is a JointModelMimic: mimic joints (a coordinate slaved to "
                         f"another) are not supported")
    if short == "JointModelSpherical":
        return [Part(BALL, name, idx_q, 4, idx_v, 3, tuple(tag + s for s in ("rx", "ry", "rz")))]
    if short == "JointModelFreeFlyer":
        return [Part(FREE, name, idx_q, 7, idx_v, 6, tuple(tag + s for s in ("x", "y", "z", "rx", "ry", "rz")))]
    if short == "JointModelPlanar":
        return [Part(PLANAR, name, idx_q, 4, idx_v, 3, tuple(tag + s for s in ("x", "y", "theta")))]
    if short.startswith("JointModelRUB") or short == "JointModelRevoluteUnboundedUnaligned":
        return [Part(ANGLE, name, idx_q, 2, idx_v, 1, (tag.rstrip("."),) if tag else ("",))]
    if jm.nq != jm.nv:
        raise ModelError(f"joint {name!r} is a {short} (nq={jm.nq}, nv={jm.nv}), whose configuration has "
                         f"no coordinate chart in mcdm-pin")
    if jm.nv == 1:
        return [Part(IDENTITY, name, idx_q, 1, idx_v, 1, (tag.rstrip("."),) if tag else ("",))]
    return [Part(IDENTITY, name, idx_q, jm.nq, idx_v, jm.nv, tuple(f"{tag}{i}" for i in range(jm.nv)))]


def chart_parts(model: pin.Model) -> tuple[Part, ...]:
    """Every charted piece of ``model``'s configuration, in Pinocchio's joint order."""
    parts: list[Part] = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        parts += _primitive_parts(jm, model.names[j], jm.idx_q, jm.idx_v, "")
    return tuple(parts)


def _name(part: Part, suffix: str) -> str:
    return f"{part.joint}.{suffix}" if suffix else part.joint


def coordinate_names(model: pin.Model) -> tuple[str, ...]:
    """Name of each coordinate (nv)."""
    names = [""] * model.nv
    for p in chart_parts(model):
        for i, s in enumerate(p.suffixes):
            names[p.idx_v + i] = _name(p, s)
    return tuple(names)


def configuration_names(model: pin.Model) -> tuple[str, ...]:
    """Name of each entry of Pinocchio's configuration vector (nq)."""
    names = [""] * model.nq
    for p in chart_parts(model):
        if p.kind == BALL:
            sub = ("qx", "qy", "qz", "qw")
        elif p.kind == FREE:
            sub = ("x", "y", "z", "qx", "qy", "qz", "qw")
        elif p.kind == PLANAR:
            sub = ("x", "y", "cos", "sin")
        elif p.kind == ANGLE:
            sub = ("cos", "sin")
        else:
            sub = p.suffixes
        for i, s in enumerate(sub):
            names[p.idx_q + i] = _name(p, s)
    return tuple(names)


def _unit_blocks(parts) -> list[tuple[Part, int, int]]:
    """``(part, start, length)`` of each block of ``q`` that must have unit norm: a quaternion
    (ball, free joint) or a (cos, sin) pair (continuous, planar joint)."""
    out = []
    for p in parts:
        if p.kind == BALL:
            out.append((p, p.idx_q, 4))
        elif p.kind == FREE:
            out.append((p, p.idx_q + 3, 4))
        elif p.kind == ANGLE:
            out.append((p, p.idx_q, 2))
        elif p.kind == PLANAR:
            out.append((p, p.idx_q + 2, 2))
    return out


def check_configuration(model: pin.Model, q, name: str = "q", parts=None,
                        coordinates: bool = False) -> np.ndarray:
    """``q`` as Pinocchio's configuration of ``model``: a finite vector of length nq whose quaternions
    and (cos, sin) pairs have unit norm to :data:`UNIT_NORM_TOL` (returned normalised, a copy);
    :class:`~mcdm_pin.exceptions.StateError` naming ``name``, the joint and the norm otherwise.
    ``coordinates``: a vector of length nv is accepted too, as coordinates (converted). Every entry
    point (``solve``, ``solve_trajectory``, the functions of :mod:`mcdm_pin.model.terms`) checks a
    configuration here."""
    nq, nv = model.nq, model.nv
    try:
        arr = np.asarray(q, dtype=float)
    except (TypeError, ValueError):
        raise StateError(f"{name}: expected {nq} numbers, got {type(q).__name__}") from None
    sizes = (nq, nv) if coordinates else (nq,)
    if arr.ndim != 1 or arr.shape[0] not in sizes:
        want = f"{nq}" if nq == nv or not coordinates else f"{nq} (configuration) or {nv} (coordinates)"
        raise StateError(f"{name}: expected a vector of length {want}, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        bad = np.flatnonzero(~np.isfinite(arr))
        raise StateError(f"{name}: expected finite numbers, entries {bad.tolist()} are not")
    if nq == nv:
        return arr
    parts = chart_parts(model) if parts is None else parts
    if arr.shape[0] == nv:
        return configuration(model, arr, parts)
    out = arr.copy()
    for p, s, n in _unit_blocks(parts):
        norm = float(np.linalg.norm(out[s:s + n]))
        if not abs(norm - 1.0) <= UNIT_NORM_TOL:
            what = f"the quaternion of joint {p.joint!r}" if n == 4 else f"(cos, sin) of joint {p.joint!r}"
            raise StateError(f"{name}: {what} has norm {norm:.9g}; expected 1")
        out[s:s + n] /= norm
    return out


def check_configurations(model: pin.Model, Q, name: str = "q", parts=None) -> np.ndarray:
    """Rows of ``Q`` (N, nq), each checked as :func:`check_configuration` (the first bad row is named
    ``name[k]``); returns them normalised (``Q`` itself when nothing changes)."""
    Q = np.asarray(Q, dtype=float)
    if Q.ndim != 2 or Q.shape[1] != model.nq:
        raise StateError(f"{name}: expected an array of shape (N, {model.nq}), got shape {Q.shape}")
    for k in np.flatnonzero(~np.isfinite(Q).all(axis=1))[:1]:
        check_configuration(model, Q[k], f"{name}[{k}]", parts)  # raises, naming the entries
    if model.nq == model.nv:
        return Q
    parts = chart_parts(model) if parts is None else parts
    out = Q
    for p, s, n in _unit_blocks(parts):
        norms = np.linalg.norm(Q[:, s:s + n], axis=1)
        bad = ~(np.abs(norms - 1.0) <= UNIT_NORM_TOL)
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            check_configuration(model, Q[k], f"{name}[{k}]", parts)
        if np.any(norms != 1.0):
            out = out.copy() if out is Q else out
            out[:, s:s + n] /= norms[:, None]
    return out


def _quat(R: np.ndarray) -> np.ndarray:
    return pin.Quaternion(R).normalized().coeffs()  # x, y, z, w


def _rot(quat_xyzw) -> np.ndarray:
    x, y, z, w = quat_xyzw
    return pin.Quaternion(w, x, y, z).normalized().toRotationMatrix()


def _rz(theta: float) -> np.ndarray:
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def configuration(model: pin.Model, x, parts=None) -> np.ndarray:
    """Coordinates (nv) -> configuration (nq)."""
    x = np.asarray(x, dtype=float)
    q = np.empty(model.nq)
    for p in parts or chart_parts(model):
        c = x[p.idx_v:p.idx_v + p.nv]
        if p.kind == IDENTITY:
            q[p.idx_q:p.idx_q + p.nq] = c
        elif p.kind == ANGLE:
            q[p.idx_q:p.idx_q + 2] = np.cos(c[0]), np.sin(c[0])
        elif p.kind == BALL:
            q[p.idx_q:p.idx_q + 4] = _quat(pin.exp3(c))
        elif p.kind == FREE:
            q[p.idx_q:p.idx_q + 3] = c[:3]
            q[p.idx_q + 3:p.idx_q + 7] = _quat(pin.exp3(c[3:]))
        else:  # planar
            q[p.idx_q:p.idx_q + 4] = c[0], c[1], np.cos(c[2]), np.sin(c[2])
    return q


def coordinates(model: pin.Model, q, parts=None) -> np.ndarray:
    """Configuration (nq) -> coordinates (nv); rotation vectors have angles in [0, pi]."""
    q = np.asarray(q, dtype=float)
    x = np.empty(model.nv)
    for p in parts or chart_parts(model):
        c = q[p.idx_q:p.idx_q + p.nq]
        if p.kind == IDENTITY:
            x[p.idx_v:p.idx_v + p.nv] = c
        elif p.kind == ANGLE:
            x[p.idx_v] = np.arctan2(c[1], c[0])
        elif p.kind == BALL:
            x[p.idx_v:p.idx_v + 3] = pin.log3(_rot(c))
        elif p.kind == FREE:
            x[p.idx_v:p.idx_v + 3] = c[:3]
            x[p.idx_v + 3:p.idx_v + 6] = pin.log3(_rot(c[3:]))
        else:
            x[p.idx_v:p.idx_v + 3] = c[0], c[1], np.arctan2(c[3], c[2])
    return x


def _skew(w) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def right_jacobian_rate(theta, theta_dot) -> np.ndarray:
    r""":math:`\frac{d}{dt} J_r(\theta(t))` for :math:`J_r(\theta) = I - c_1 [\theta]_\times
    + c_2 [\theta]_\times^2`, :math:`c_1 = (1-\cos a)/a^2`, :math:`c_2 = (a - \sin a)/a^3`,
    :math:`a = |\theta|` (series below :math:`a = 10^{-4}`)."""
    th, thd = np.asarray(theta, dtype=float), np.asarray(theta_dot, dtype=float)
    a = float(np.linalg.norm(th))
    if a < 1e-4:
        a2 = a * a
        c1, c2 = 0.5 - a2 / 24.0, 1.0 / 6.0 - a2 / 120.0
        dc1, dc2 = -1.0 / 12.0 + a2 / 180.0, -1.0 / 60.0 + a2 / 1260.0  # (dc/da) / a
    else:
        s, c = np.sin(a), np.cos(a)
        c1, c2 = (1.0 - c) / a**2, (a - s) / a**3
        dc1 = (a * s - 2.0 * (1.0 - c)) / a**4
        dc2 = ((1.0 - c) * a - 3.0 * (a - s)) / a**5
    adot_over_a = float(th @ thd)  # a * da/dt
    T, Td = _skew(th), _skew(thd)
    return -(dc1 * adot_over_a) * T - c1 * Td + (dc2 * adot_over_a) * (T @ T) + c2 * (Td @ T + T @ Td)


def tangent(model: pin.Model, x, xd, xdd, parts=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coordinates and their first and second time derivatives (nv each) -> Pinocchio's ``(q, v, a)``
    (module docstring)."""
    x, xd, xdd = (np.asarray(z, dtype=float) for z in (x, xd, xdd))
    q = configuration(model, x, parts)
    v, a = xd.copy(), xdd.copy()
    for p in parts or chart_parts(model):
        i = p.idx_v
        if p.kind in (IDENTITY, ANGLE):
            continue
        if p.kind == BALL:
            th, thd, thdd = x[i:i + 3], xd[i:i + 3], xdd[i:i + 3]
            Jr = pin.Jexp3(th)
            v[i:i + 3] = Jr @ thd
            a[i:i + 3] = Jr @ thdd + right_jacobian_rate(th, thd) @ thd
        elif p.kind == FREE:
            th, thd, thdd = x[i + 3:i + 6], xd[i + 3:i + 6], xdd[i + 3:i + 6]
            Jr = pin.Jexp3(th)
            w = Jr @ thd
            wd = Jr @ thdd + right_jacobian_rate(th, thd) @ thd
            R = pin.exp3(th)
            vl = R.T @ xd[i:i + 3]
            v[i:i + 3], v[i + 3:i + 6] = vl, w
            a[i:i + 3], a[i + 3:i + 6] = R.T @ xdd[i:i + 3] - np.cross(w, vl), wd
        else:  # planar: v_xy = Rz^T p_dot, a_xy = Rz^T p_ddot - w x v
            R = _rz(x[i + 2])[:2, :2]
            w = xd[i + 2]
            vl = R.T @ xd[i:i + 2]
            v[i:i + 2] = vl
            a[i:i + 2] = R.T @ xdd[i:i + 2] - w * np.array([-vl[1], vl[0]])
    return q, v, a
