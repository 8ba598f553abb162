"""MuJoCo's spatial tendons, muscles and joint couplings -> our cables, muscles and couplings.

Read from the *compiled* ``mujoco.MjModel`` (MuJoCo resolved defaults, includes and frames), with the
Pinocchio frames of :func:`mcdm_pin.mjcf.model.build_model`:

- a spatial tendon driven by a muscle actuator becomes a muscle cable named after the actuator; one
  driven by a plain ``motor``/``general`` actuator with a control range that only pulls becomes a cable
  with those bounds (times gain and gear); a plain motor on a hinge or slide joint becomes an actuator
  of that joint (a hybrid robot's motor; unbounded without a control or force range, kept finite by its
  weight in the objective); a tendon no actuator drives exerts no force of its
  own (MuJoCo's passive tendon stiffness and damping are refused where set) and is left out, with a
  note, as is a muscle whose whole path lies on one body;
- a route's ``site`` is a :class:`~mcdm_pin.model.cables.RoutePoint` on the site's frame, a ``geom``
  (sphere or cylinder) a :class:`~mcdm_pin.model.cables.Wrap` on the geom's frame (its ``sidesite`` the
  wrap's side point), a ``pulley`` a :class:`~mcdm_pin.model.cables.Pulley`;
- an ``equality joint`` is a :class:`~mcdm_pin.model.couplings.Coupling` of the two joints'
  coordinates (MuJoCo's ``y - y0 = p(x - x0)`` is ``q_y = p(q_x)`` in Pinocchio's coordinates, which are
  measured from ``qpos0``).

Everything else that acts on the bodies is refused with the element and the reason: fixed tendons,
tendons with stiffness or damping, other equality constraints (connect, weld, tendon, flex), and other
actuators (dynamics, bias, no gain, on sites or bodies, on ball or free joints, a tendon motor that
could push).
"""

from __future__ import annotations

import math

from dataclasses import dataclass

import numpy as np

from ..exceptions import ModelError
from ..model.cables import Cable, Pulley, RoutePoint, Wrap
from ..model.couplings import Coupling
from ..model.muscles import from_mujoco


@dataclass(frozen=True)
class TendonSet:
    """What :func:`read_tendons` found: ``cables`` (Cable list), the muscles' params and cable names
    (``None``, () without muscles), ``notes`` (what was left out and why), ``joint_motors``
    ``(name, MuJoCo joint id, lo, hi)`` of the bounded motors on hinge and slide joints."""

    cables: list
    muscles: object
    muscle_cables: tuple
    notes: tuple
    joint_motors: tuple = ()


def _refuse(source: str, what: str, why: str):
    return ModelError(f"{source}: {what}: {why}")


def _route(mj, mjm, t: int, source: str, tname: str) -> list:
    import mujoco

    W = mujoco.mjtWrap
    route = []
    for i in range(int(mj.tendon_adr[t]), int(mj.tendon_adr[t] + mj.tendon_num[t])):
        kind, obj, prm = int(mj.wrap_type[i]), int(mj.wrap_objid[i]), float(mj.wrap_prm[i])
        if kind == W.mjWRAP_SITE:
            route.append(RoutePoint(int(mjm.site_frame[obj]), (0.0, 0.0, 0.0)))
        elif kind in (W.mjWRAP_SPHERE, W.mjWRAP_CYLINDER):
            gtype = int(mj.geom_type[obj])
            want = mujoco.mjtGeom.mjGEOM_SPHERE if kind == W.mjWRAP_SPHERE else mujoco.mjtGeom.mjGEOM_CYLINDER
            if gtype != want:
                raise _refuse(source, f"tendon {tname!r}", f"wrap geom {obj} is not a sphere or cylinder")
            side = None if prm < 0 else RoutePoint(int(mjm.site_frame[int(prm)]), (0.0, 0.0, 0.0))
            gname = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_GEOM, obj) or f"geom:#{obj}"
            route.append(Wrap(int(mjm.geom_frame[obj]), "sphere" if kind == W.mjWRAP_SPHERE else "cylinder",
                              float(mj.geom_size[obj, 0]), side=side, name=gname))
        elif kind == W.mjWRAP_PULLEY:
            route.append(Pulley(prm))
        else:
            raise _refuse(source, f"tendon {tname!r}", "a fixed tendon (a linear combination of joint "
                                                       "coordinates) is not a cable; not supported")
    return route


def _check_tendon(mj, t: int, source: str, tname: str, notes: list) -> None:
    for field, label in (("tendon_stiffness", "stiffness"), ("tendon_damping", "damping"),
                         ("tendon_frictionloss", "frictionloss")):
        value = np.atleast_1d(getattr(mj, field)[t])
        if np.any(value != 0):
            raise _refuse(source, f"tendon {tname!r}", f"passive tendon {label} {value.tolist()} is not "
                                                       f"supported (a known force of the tendon)")
    if int(mj.tendon_limited[t]):
        lo, hi = (float(x) for x in mj.tendon_range[t])
        notes.append(f"tendon {tname!r}: its length limit [{lo:.6g}, {hi:.6g}] m is a constraint MuJoCo applies "
                     f"only at the limit; the inverse dynamics here take it as inactive")


def read_tendons(mj, mjm, source: str) -> TendonSet:
    """Cables, muscles, joint motors and notes from the compiled model ``mj`` and its Pinocchio frames
    ``mjm``."""
    import mujoco

    found = from_mujoco(mj)
    motors = _motors(mj, source, found.skipped)
    by_tendon = {int(t): ("muscle", k) for k, t in enumerate(found.tendon_ids)}
    for i, (kind, lo, hi) in motors.items():
        if kind == "tendon":
            t = int(mj.actuator_trnid[i, 0])
            if t in by_tendon:
                raise _refuse(source, f"actuator {_actuator_name(mj, i)!r}", "a second actuator on a tendon; "
                                                                             "expected one actuator per tendon")
            by_tendon[t] = ("motor", i)
    if len(by_tendon) != len(found.tendon_ids) + sum(1 for k, _, _ in motors.values() if k == "tendon"):
        raise _refuse(source, "actuators", "two muscles drive one tendon; expected one muscle per tendon")
    cables, names, notes = [], [], []
    params = found.params
    ceiling = _tension_ceilings(params) if params.size else np.zeros(0)
    for t in range(mj.ntendon):
        tname = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_TENDON, t) or f"tendon:#{t}"
        _check_tendon(mj, t, source, tname, notes)
        if t not in by_tendon:
            notes.append(f"tendon {tname!r}: no actuator drives it, so it exerts no force; not a cable")
            continue
        route = _route(mj, mjm, t, source, tname)
        kind, k = by_tendon[t]
        cname = params.names[k] if kind == "muscle" else _actuator_name(mj, k)
        if len(_route_bodies(mj, mjm, t)) < 2:
            notes.append(f"{'muscle' if kind == 'muscle' else 'actuator'} {cname!r}: its whole path (tendon "
                         f"{tname!r}) lies on one body, so it moves nothing and its pull cancels inside that "
                         f"body; left out")
            continue
        if kind == "muscle":
            # the static bounds only enclose the tension; each instant's range follows the muscle's state
            cables.append(Cable(cname, tuple(route), 0.0, float(ceiling[k])))
            names.append(cname)
        else:
            cables.append(Cable(cname, tuple(route), *motors[k][1:]))
    order = [params.names.index(n) for n in names]
    muscles = _subset(params, order) if names else None
    joint_motors = tuple((_actuator_name(mj, i), int(mj.actuator_trnid[i, 0]), lo, hi)
                         for i, (kind, lo, hi) in motors.items() if kind == "joint")
    return TendonSet(cables, muscles, tuple(names), tuple(notes), joint_motors)


def _actuator_name(mj, i: int) -> str:
    return mj.actuator(int(i)).name or f"actuator {int(i)}"


def _route_bodies(mj, mjm, t: int) -> set:
    """The Pinocchio joints carrying tendon ``t``'s sites and wrap geoms."""
    import mujoco

    W = mujoco.mjtWrap
    out = set()
    for i in range(int(mj.tendon_adr[t]), int(mj.tendon_adr[t] + mj.tendon_num[t])):
        kind, obj = int(mj.wrap_type[i]), int(mj.wrap_objid[i])
        if kind == W.mjWRAP_SITE:
            out.add(int(mjm.body_joint[mj.site_bodyid[obj]]))
        elif kind in (W.mjWRAP_SPHERE, W.mjWRAP_CYLINDER):
            out.add(int(mjm.body_joint[mj.geom_bodyid[obj]]))
    return out


def _motors(mj, source: str, skipped) -> dict:
    """The non-muscle actuators this loader reads: ``{actuator id: (kind, lo, hi)}`` with ``kind``
    ``tendon`` (a cable pulling with tension in ``[lo, hi]`` N) or ``joint`` (a hinge or slide motor with
    generalised force in ``[lo, hi]``): a ``motor``/``general`` actuator without dynamics, with a fixed
    gain ``k``, no bias, and its control range ``[c0, c1]`` when limited (``forcerange`` too). Its force
    on the transmission is ``g k c`` (gear ``g``), so a tendon's tension is ``-g k c``: read only when it
    can only pull. A joint motor without either range is unbounded (``-inf``, ``inf``): its weight in the
    objective keeps its torque finite. Every other actuator is refused, naming it and why."""
    import mujoco

    out = {}
    for name, why in skipped:
        i = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_ACTUATOR, name) if not name.startswith("actuator ") \
            else int(name.split()[1])
        trn = mujoco.mjtTrn(int(mj.actuator_trntype[i])).name.removeprefix("mjTRN_").lower()
        g, k = float(mj.actuator_gear[i, 0]), float(mj.actuator_gainprm[i, 0])
        fail = None
        if trn not in ("tendon", "joint"):
            fail = f"on a {trn}"
        elif int(mj.actuator_dyntype[i]) != mujoco.mjtDyn.mjDYN_NONE:
            fail = "has activation dynamics (only a muscle's are read)"
        elif int(mj.actuator_gaintype[i]) != mujoco.mjtGain.mjGAIN_FIXED or \
                int(mj.actuator_biastype[i]) != mujoco.mjtBias.mjBIAS_NONE:
            fail = "is not a plain motor (a fixed gain, no bias)"
        elif g * k == 0.0:
            fail = "has no gain (gear or gain zero), so it exerts no force"
        if fail is None and trn == "joint":
            j = int(mj.actuator_trnid[i, 0])
            if int(mj.jnt_type[j]) not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
                fail = "drives a ball or free joint"
        if fail is not None:
            raise _refuse(source, f"actuator {name!r}", f"{why}; it {fail} ({trn} transmission): only muscles, "
                                                        f"plain motors on hinge/slide joints and plain "
                                                        f"motors on tendons that only pull are read from MJCF")
        # no control range: an unbounded force (a joint motor keeps it finite through its weight in the
        # objective, as CASPR's joint motors do; a tendon motor that could push is refused below)
        lo, hi = (sorted(g * k * float(c) for c in mj.actuator_ctrlrange[i]) if int(mj.actuator_ctrllimited[i])
                  else (-math.inf, math.inf))
        if int(mj.actuator_forcelimited[i]):
            flo, fhi = (g * float(x) for x in sorted(mj.actuator_forcerange[i]))
            lo, hi = max(lo, min(flo, fhi)), min(hi, max(flo, fhi))
        if trn == "tendon":
            lo, hi = -hi, -lo  # tension pulls: the tendon's force is minus the actuator's
            if lo < 0 or not hi > lo:
                raise _refuse(source, f"actuator {name!r}", f"a motor on a tendon whose tension range "
                                                            f"[{lo:.6g}, {hi:.6g}] N is not within [0, inf) with "
                                                            f"width: a cable only pulls")
        out[i] = (trn, lo, hi)
    return out


def _tension_ceilings(params) -> np.ndarray:
    """(m,) a tension no state of each muscle can exceed within its length range (its static upper
    bound): 10 x the largest force at full activation and a lengthening speed of 1e3 m/s over 5
    lengths spanning the range, at least 1 N (all muscles in one evaluation)."""
    from ..model.muscles import force_range

    lr = params.lengthrange / params.gear[:, None]
    lengths = np.linspace(lr[:, 0], lr[:, 1], 5)  # (5, m)
    top = force_range(params, lengths, np.full_like(lengths, 1e3)).f_max.max(axis=0)
    return np.maximum(1.0, 10.0 * top)


def _subset(params, idx):
    from dataclasses import fields

    idx = np.asarray(idx, dtype=int)
    kw = {}
    for f in fields(params):
        v = getattr(params, f.name)
        kw[f.name] = tuple(v[i] for i in idx) if f.name == "names" else np.asarray(v)[idx]
    return type(params)(**kw)


def read_couplings(mj, mjm, source: str) -> list:
    """The ``equality joint`` couplings of ``mj`` (active ones), as :class:`Coupling` over Pinocchio's
    ``v`` indices; other equality constraints are refused."""
    import mujoco

    out = []
    for e in range(mj.neq):
        ename = mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_EQUALITY, e) or f"equality:#{e}"
        if not int(mj.eq_active0[e]):
            continue
        if int(mj.eq_type[e]) != mujoco.mjtEq.mjEQ_JOINT:
            kind = mujoco.mjtEq(int(mj.eq_type[e])).name
            raise _refuse(source, f"equality {ename!r}", f"{kind} constraints (closed loops) are not supported; "
                                                        f"only joint couplings are")
        j1, j2 = int(mj.eq_obj1id[e]), int(mj.eq_obj2id[e])
        for j in (j1, j2):
            if j >= 0 and int(mj.jnt_type[j]) not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
                raise _refuse(source, f"equality {ename!r}", f"joint {mjm.joint_names[j]!r} is not a hinge or "
                                                            f"slide")
        coef = tuple(float(x) for x in mj.eq_data[e, :5])
        out.append(Coupling(int(mjm.jnt_idx_v[j1]), int(mjm.jnt_idx_v[j2]) if j2 >= 0 else -1, coef, ename))
    return out
