"""URDF -> ``pin.Model``: Pinocchio's parser, the checks it does not make, native joints a URDF cannot name.

A URDF has no ball joint; a sidecar may declare a URDF ``floating`` joint a ``spherical`` joint, which
:func:`replace_joints` turns into a ``JointModelSpherical`` (or ``JointModelSphericalZYX``) in place,
keeping every body, frame and limit of the model. Pinocchio maps a URDF ``planar`` joint to
``JointModelPlanar`` (motion in the xy plane of the joint frame) whatever its ``<axis>`` says:
:func:`urdf_joint_axes` reads the axes so that the loader can refuse any other.
"""

from __future__ import annotations

import os
import site
import sys
import tempfile
import warnings
import xml.etree.ElementTree as ET
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pinocchio as pin

from .exceptions import InertiaWarning, ModelError
from .limits import MAX_JOINTS, MAX_MAGNITUDE, MAX_URDF_BYTES


def package_share_dirs() -> list[Path]:
    """Folders that hold installed packages for ``package://`` URIs, in search order:
    ``ROS_PACKAGE_PATH`` entries, ``AMENT_PREFIX_PATH``/share, and every ``cmeel.prefix/share``
    in this interpreter's site-packages (where example-robot-data installs its robots)."""
    dirs: list[Path] = []
    for entry in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry))
    for entry in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry) / "share")
    candidates = list(site.getsitepackages()) + [site.getusersitepackages()] + sys.path
    for sp in candidates:
        share = Path(sp) / "cmeel.prefix" / "share"
        if share.is_dir() and share not in dirs:
            dirs.append(share)
    return dirs


@contextmanager
def _captured_stderr():
    """What C/C++ code writes to file descriptor 2 meanwhile (urdfdom reports through it)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        os.dup2(tmp.fileno(), 2)
        box: list[str] = []
        try:
            yield box
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            box.append(tmp.read(65536).decode("utf-8", "replace"))


def load_model(urdf_path) -> pin.Model:
    """Pinocchio's model of a URDF file. Everything the parser reports (urdfdom prints an ``Error:``
    and still returns a model when, e.g., a mass is not a number: that link would silently lose its
    inertia) is fatal; the model is then checked (:func:`check_urdf`, :func:`check_model_numbers`)."""
    path = Path(urdf_path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the URDF ({exc.strerror or exc})") from None
    if size > MAX_URDF_BYTES:
        raise ModelError(f"{path}: the URDF has {size} bytes; at most {MAX_URDF_BYTES} are read (docs/limits.md)")
    joints = check_urdf(path)
    try:
        with _captured_stderr() as said:
            model = pin.buildModelFromUrdf(str(path))
    except Exception as exc:  # pinocchio raises ValueError/RuntimeError with urdfdom's text
        reason = " ".join((said[0] if said else "").split()) or (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        raise ModelError(f"{path}: cannot load the URDF ({reason[:300]})") from None
    report = " ".join(said[0].split()) if said else ""
    if report:
        raise ModelError(f"{path}: the URDF parser reported: {report[:300]}")
    if model.njoints > MAX_JOINTS:
        raise ModelError(f"{path}: {model.njoints} joints; at most {MAX_JOINTS} are supported (docs/limits.md)")
    del joints
    check_model_numbers(model, path)
    check_urdf_inertias(path)
    return model


_AXIS_TYPES = ("revolute", "continuous", "prismatic", "planar")


def check_urdf(path) -> dict:
    """What Pinocchio's URDF parser accepts but a dynamics model cannot use, refused by name: ``<mimic>``
    joints (a coordinate slaved to another), zero joint axes. Returns :func:`urdf_joint_axes`."""
    try:
        root = ET.parse(str(path)).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"{path}: malformed XML ({exc})") from None
    except OSError as exc:
        raise ModelError(f"{path}: cannot read the URDF ({exc.strerror or exc})") from None
    if root.tag != "robot":
        raise ModelError(f"{path}: the root element is <{root.tag}>, not <robot>: not a URDF")
    for el in root.iter("joint"):
        if el.find("mimic") is not None:
            raise ModelError(f"{path}: joint {el.get('name')!r}: <mimic> joints are not supported (a coordinate "
                             f"slaved to another); lock the joint (locked_joints) or make it independent")
    axes = urdf_joint_axes(path, root)
    for name, (kind, axis) in axes.items():
        if kind in _AXIS_TYPES and not np.linalg.norm(axis) > 1e-12:
            raise ModelError(f"{path}: joint {name!r}: <axis xyz> is zero; expected a direction")
    return axes


def check_model_numbers(model: pin.Model, source) -> None:
    """Reject masses, inertias and placements that are not finite or so large that the dynamics
    overflow (a CASPR mass of 1e308 kg gave inf terms and crashed the solver: tests/test_fuzz.py)."""
    for j in range(model.njoints):
        inertia = model.inertias[j]
        checks = (("mass", np.array([inertia.mass]), "kg"), ("centre of mass", inertia.lever, "m"),
                  ("inertia", inertia.inertia, "kg m^2"),
                  ("joint origin", model.jointPlacements[j].translation, "m"))
        for what, values, unit in checks:
            values = np.asarray(values, dtype=float)
            if not np.all(np.isfinite(values)) or np.abs(values).max(initial=0.0) > MAX_MAGNITUDE:
                owner = "the fixed base" if j == 0 else f"the body moved by joint {model.names[j]!r}"
                raise ModelError(f"{source}: {what} of {owner} is {values.tolist()} {unit}; expected "
                                 f"finite numbers of magnitude at most {MAX_MAGNITUDE:g}")
        owner = "the fixed base" if j == 0 else f"the body moved by joint {model.names[j]!r}"
        if inertia.mass < 0:
            raise ModelError(f"{source}: mass of {owner} is {inertia.mass!r} kg; expected >= 0")
        eig = np.linalg.eigvalsh(0.5 * (inertia.inertia + inertia.inertia.T))
        tol = 1e-12 * max(1.0, float(np.abs(eig).max()))
        if eig.min() < -tol:  # (the triangle inequality: check_urdf_inertias, check_model_inertias)
            raise ModelError(f"{source}: inertia of {owner} has principal moments {np.round(eig, 12).tolist()} "
                             f"kg m^2; expected a positive semidefinite inertia (moments >= 0)")


# ----------------------------------------------------------------------------- impossible inertias
TRIANGLE_REL, TRIANGLE_ABS = 1e-9, 1e-15
"""Principal moments ``A <= B <= C`` of a rotational inertia about the centre of mass satisfy
``A + B >= C`` for every body (``A + B - C = 2 sum m z^2 >= 0`` along C's axis); a model may break it by
``TRIANGLE_REL * C + TRIANGLE_ABS`` (kg m^2: rounding of moments that are all ~0) before it is called
impossible."""

CASPR_PROVENANCE = "Converted by mcdm-pin import-caspr from "
"""The opening comment :mod:`mcdm_pin.caspr.writer` writes in every URDF it converts: such a URDF gives
CASPR's inertias as CASPR ships them, and one no body can have is accepted with an
:class:`~mcdm_pin.exceptions.InertiaWarning` instead of refused (docs/limits.md)."""


def principal_moments(inertia) -> np.ndarray:
    """The principal moments of a (3, 3) rotational inertia, ascending, kg m^2."""
    I = np.asarray(inertia, dtype=float)
    return np.linalg.eigvalsh(0.5 * (I + I.T))


def breaks_triangle(moments) -> bool:
    """Whether ascending principal moments ``(A, B, C)`` break ``A + B >= C`` (beyond :data:`TRIANGLE_REL`)."""
    a, b, c = (float(x) for x in moments)
    return a + b < c - TRIANGLE_REL * abs(c) - TRIANGLE_ABS


def moments_text(items) -> str:
    """``'link' [A, B, C]`` for the first few of ``items`` (link name, moments) and how many in all
    (a name given as ``(label,)`` is shown as it is)."""
    def one(name, mom) -> str:
        return f"{name[0] if isinstance(name, tuple) else repr(name)} [{', '.join(f'{x:.9g}' for x in mom)}]"

    shown = "; ".join(one(name, mom) for name, mom in items[:4])
    return shown + (f"; ... ({len(items)} in all)" if len(items) > 4 else "")


def urdf_impossible_inertias(path) -> list[tuple[str, np.ndarray]]:
    """``[(link name, ascending principal moments)]`` of the links of a URDF whose ``<inertia>``
    breaks the triangle inequality (:func:`breaks_triangle`). Values that are not numbers are left to
    the URDF parser, which reports them."""
    try:
        root = ET.parse(str(path)).getroot()
    except (ET.ParseError, OSError):
        return []
    out = []
    for link in root.iter("link"):
        el = link.find("inertial/inertia")
        if el is None:
            continue
        try:
            v = {k: float(el.get(k, "0")) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
        except ValueError:
            continue
        I = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]])
        if not np.all(np.isfinite(I)):
            continue
        moments = principal_moments(I)
        if breaks_triangle(moments):
            out.append((link.get("name"), moments))
    return out


def shipped_by_caspr(path) -> bool:
    """Whether the URDF opens with the comment of mcdm-pin's CASPR import (:data:`CASPR_PROVENANCE`,
    before its ``<robot>`` element)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            head = fh.read(4096)
    except OSError:
        return False
    head = head.split("<robot", 1)[0]
    start = head.find("<!--")
    return start >= 0 and CASPR_PROVENANCE in head[start:]


def check_urdf_inertias(path) -> None:
    """Refuse a URDF with a link whose inertia no body can have (:class:`ModelError` naming the links
    and their principal moments); a URDF converted from CASPR (:func:`shipped_by_caspr`) is accepted
    with an :class:`~mcdm_pin.exceptions.InertiaWarning`, because CASPR ships those inertias."""
    bad = urdf_impossible_inertias(path)
    if not bad:
        return
    what = (f"{len(bad)} link(s) have principal moments of inertia (kg m^2, about the centre of mass) that "
            f"no body can have, breaking A + B >= C: {moments_text(bad)}")
    if not shipped_by_caspr(path):
        raise ModelError(f"{path}: {what}; expected moments with A + B >= C (a body's inertia; docs/limits.md)")
    warnings.warn(f"{path}: {what}; accepted as CASPR ships them (the dynamics are those of these numbers, not "
                  f"of a physical body; docs/limits.md)", InertiaWarning, stacklevel=3)


def check_model_inertias(model: pin.Model, source="pin.Model") -> None:
    """Refuse a ``pin.Model`` with a body whose inertia no body can have (:class:`ModelError` naming
    the joint that moves it and its principal moments)."""
    bad = []
    for j in range(1, model.njoints):
        moments = principal_moments(model.inertias[j].inertia)
        if breaks_triangle(moments):
            bad.append(((f"the body of joint {model.names[j]!r}",), moments))
    if bad:
        raise ModelError(f"{source}: {len(bad)} body(ies) have principal moments of inertia (kg m^2, about the "
                         f"centre of mass) that no body can have, breaking A + B >= C: {moments_text(bad)}; "
                         f"expected moments with A + B >= C (docs/limits.md)")


def urdf_joint_axes(urdf_path, root=None) -> dict[str, tuple[str, np.ndarray]]:
    """``{joint name: (URDF type, axis)}`` as the file writes them (axis default +x, URDF's)."""
    root = ET.parse(str(urdf_path)).getroot() if root is None else root
    out = {}
    for el in root.iter("joint"):
        axis_el = el.find("axis")
        axis = np.array([1.0, 0.0, 0.0])
        if axis_el is not None and axis_el.get("xyz"):
            try:
                axis = np.array([float(x) for x in axis_el.get("xyz").split()], dtype=float)
            except ValueError:
                raise ModelError(f"{urdf_path}: joint {el.get('name')!r}: <axis xyz> is not three numbers") from None
        out[el.get("name")] = (el.get("type"), axis)
    return out


_ARRAYS_Q = ("lowerPositionLimit", "upperPositionLimit", "positionLimitMargin")
_ARRAYS_V = ("velocityLimit", "lowerVelocityLimit", "upperVelocityLimit", "effortLimit", "lowerEffortLimit",
             "upperEffortLimit", "friction", "lowerDryFrictionLimit", "upperDryFrictionLimit", "damping",
             "armature")


def replace_joints(model: pin.Model, replacements: dict[int, object]) -> pin.Model:
    """A copy of ``model`` in which joint ``j`` becomes ``replacements[j]`` (a Pinocchio joint model):
    same tree, placements, bodies, frames and names; the limits of the other joints are kept, the
    replaced joints take their type's defaults."""
    new = pin.Model()
    new.name = model.name
    new.gravity = model.gravity
    for j in range(1, model.njoints):
        jm = replacements.get(j, model.joints[j])
        jid = new.addJoint(int(model.parents[j]), jm, model.jointPlacements[j], model.names[j])
        assert jid == j
        new.inertias[j] = model.inertias[j]
    for f in list(model.frames)[1:]:
        new.addFrame(pin.Frame(f.name, f.parentJoint, f.parentFrame, f.placement, f.type, f.inertia), False)
    for j in range(1, model.njoints):
        if j in replacements:
            continue
        old, nj = model.joints[j], new.joints[j]
        for name in _ARRAYS_Q:
            if hasattr(model, name):
                arr = getattr(new, name).copy()
                arr[nj.idx_q:nj.idx_q + nj.nq] = getattr(model, name)[old.idx_q:old.idx_q + old.nq]
                setattr(new, name, arr)
        for name in _ARRAYS_V:
            if hasattr(model, name):
                arr = getattr(new, name).copy()
                arr[nj.idx_v:nj.idx_v + nj.nv] = getattr(model, name)[old.idx_v:old.idx_v + old.nv]
                setattr(new, name, arr)
    return new
