"""Write MyoSuite's elbow and arm models as standalone MJCF files under ``robots/myosuite/``.

Usage (from the repository root, with ``myosuite``/``myo_sim`` and ``mujoco`` installed)::

    python tools/vendor_myosuite.py [OUTPUT_DIR]

Each model is loaded as an ``mujoco.MjSpec`` and compiled once; then every body gets an explicit
``<inertial>`` equal to the compiled one (``body_mass``, ``body_ipos``, ``body_iquat``,
``body_inertia``, written with 17 significant digits), the compiler's ``inertiafromgeom`` becomes
``false``, and mesh geoms, meshes and file textures are removed. Joints, sites, wrap geoms (spheres,
cylinders), tendons, actuators, equalities and keyframes stay as MuJoCo writes them
(``MjSpec.to_xml``). Removing the meshes therefore changes no mass or inertia, and the files need
neither myosuite nor any mesh or texture file.
"""

from __future__ import annotations

import contextlib
import sys
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np

#: output file name -> how to load the MyoSuite model as an MjSpec.
MODELS = {
    "myoelbow_1dof6muscles.xml": ("file", "myoelbow"),
    "myoelbow_2dof6muscles.xml": ("file", "myoelbow_2dof"),
    "myoarm_r.xml": ("spec", "myoarm_r"),
}


def load_original(name: str) -> mujoco.MjSpec:
    """The MyoSuite model ``name`` of :data:`MODELS` as an MjSpec (myoarm_r via its written XML,
    the form the tests compile as the reference)."""
    import myo_sim

    how, key = MODELS[name]
    if how == "file":
        return mujoco.MjSpec.from_file(str(myo_sim.get_xml_path(key)))
    return mujoco.MjSpec.from_string(myo_sim.load_spec(key).to_xml())


def standalone_xml(spec: mujoco.MjSpec) -> str:
    """The MJCF text of ``spec`` without meshes and file textures, every body with its compiled
    inertia made explicit (see the module docstring). ``spec`` is modified."""
    original = spec.compile()
    for b, body in enumerate(spec.bodies):
        if b == 0:
            continue
        body.explicitinertial = True
        body.mass, body.ipos = original.body_mass[b], original.body_ipos[b]
        body.iquat, body.inertia = original.body_iquat[b], original.body_inertia[b]
        body.fullinertia = np.full(6, np.nan)
    for geom in [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]:
        spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    dropped = {t.name for t in spec.textures if t.file}
    for texture in [t for t in spec.textures if t.file]:
        spec.delete(texture)
    for material in spec.materials:
        material.textures = ["" if t in dropped else t for t in material.textures]
    spec.meshdir = ""
    spec.texturedir = ""
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.compiler.settotalmass = -1.0
    stripped = spec.compile()
    root = ET.fromstring(spec.to_xml())
    for compiler in root.iter("compiler"):
        compiler.attrib.pop("meshdir", None)
        compiler.attrib.pop("texturedir", None)
    _hoist_frames(root.find("worldbody"))
    _full_precision(root, original, stripped)
    ET.indent(root, space=" ")
    return ET.tostring(root, encoding="unicode") + "\n"


def header(name: str) -> str:
    """The provenance comment written at the top of each file (the licence notice MyoSuite's
    files carry, and where the details are)."""
    from importlib.metadata import version

    how, key = MODELS[name]
    source = f"myo_sim.get_xml_path({key!r})" if how == "file" else f"myo_sim.load_spec({key!r}).to_xml()"
    versions = f"myosuite {version('myosuite')}, myo_sim {version('myo_sim')}, mujoco {mujoco.__version__}"
    return (f"<!-- Written by tools/vendor_myosuite.py from MyoSuite's model {source}\n"
            f"     ({versions}):\n"
            "     mesh geoms, meshes and file textures removed, every body's compiled inertia explicit.\n"
            "     Copyright the MyoSuite authors (Vikash Kumar, Vittorio Caggiano, Huawei Wang and\n"
            "     contributors). Licensed under the Apache License, Version 2.0\n"
            "     (http://www.apache.org/licenses/LICENSE-2.0). See NOTICE.md in this folder. -->\n")


def _hoist_frames(parent: ET.Element) -> None:
    """Replace every ``<frame>`` by its children (their compiled poses, written later, include the
    frame's transform)."""
    for i, child in reversed(list(enumerate(parent))):
        _hoist_frames(child)
        if child.tag == "frame":
            if set(child.attrib) - {"pos", "quat", "euler", "axisangle", "xyaxes", "zaxis", "name"}:
                raise RuntimeError(f"<frame> with attributes {sorted(child.attrib)} cannot be hoisted")
            parent.remove(child)
            for k, grandchild in enumerate(list(child)):
                parent.insert(i + k, grandchild)


_ORIENTATION = ("euler", "axisangle", "xyaxes", "zaxis", "fromto")


def _full_precision(root: ET.Element, original: mujoco.MjModel, stripped: mujoco.MjModel) -> None:
    """Write, in full precision, each body's compiled inertia (``original``, with meshes) and the
    compiled pose of each body, joint, geom and site (``stripped``, the written model).

    MuJoCo numbers bodies in depth-first pre-order of the XML tree and the joints, geoms and sites
    of a body in their order inside it; names are checked against the compiled ones on the way.
    """
    world = root.find("worldbody")
    bodies = [world] + list(world.iter("body"))
    if len(bodies) != stripped.nbody:
        raise RuntimeError(f"{len(bodies)} bodies in the XML for {stripped.nbody} compiled")
    for b, body in enumerate(bodies):
        if b > 0:
            _check_name(stripped, mujoco.mjtObj.mjOBJ_BODY, b, body)
            _set(body, pos=stripped.body_pos[b], quat=stripped.body_quat[b])
            for old in body.findall("inertial"):
                body.remove(old)
            body.insert(0, ET.Element("inertial", {
                "pos": _numbers(original.body_ipos[b]), "quat": _numbers(original.body_iquat[b]),
                "mass": _numbers([original.body_mass[b]]),
                "diaginertia": _numbers(original.body_inertia[b])}))
        for tag, values in _ELEMENTS.items():
            _set_children(body, b, tag, stripped, values)


#: per element tag: its MuJoCo object type, body-id field, and compiled attribute -> field.
_ELEMENTS = {
    "joint": ("mjOBJ_JOINT", "jnt_bodyid", {"pos": "jnt_pos", "axis": "jnt_axis"}),
    "geom": ("mjOBJ_GEOM", "geom_bodyid", {"pos": "geom_pos", "quat": "geom_quat", "size": "geom_size"}),
    "site": ("mjOBJ_SITE", "site_bodyid", {"pos": "site_pos", "quat": "site_quat", "size": "site_size"}),
}


def _set_children(body: ET.Element, b: int, tag: str, stripped: mujoco.MjModel, values) -> None:
    """Write the compiled attributes of body ``b``'s ``<tag>`` children."""
    objtype, bodyid, fields = values
    elements, ids = body.findall(tag), np.flatnonzero(getattr(stripped, bodyid) == b)
    if len(elements) != len(ids):
        raise RuntimeError(f"body {b}: {len(elements)} <{tag}> for {len(ids)} compiled")
    for element, i in zip(elements, ids):
        _check_name(stripped, getattr(mujoco.mjtObj, objtype), i, element)
        _set(element, **{name: getattr(stripped, field)[i] for name, field in fields.items()})


def _check_name(compiled, objtype, i, element) -> None:
    expected = mujoco.mj_id2name(compiled, objtype, int(i)) or ""
    if element.get("name", "") != expected:
        raise RuntimeError(f"{objtype.name} {i}: XML order gives {element.get('name')!r}, "
                           f"compiled {expected!r}")


def _set(element: ET.Element, **values) -> None:
    """Set compiled values, dropping the alternative orientation forms. A body's zero ``pos`` and
    identity ``quat`` are written by omission (no default class reaches bodies; geoms, sites and
    joints always get theirs, since a default class could change them)."""
    for name in _ORIENTATION:
        element.attrib.pop(name, None)
    for name, value in values.items():
        element.attrib.pop(name, None)
        default = np.zeros(3) if name == "pos" else np.array([1.0, 0, 0, 0]) if name == "quat" else None
        if element.tag != "body" or default is None or not np.array_equal(value, default):
            element.set(name, _numbers(value))


def _numbers(values) -> str:
    """Shortest decimal text that reads back to the same doubles (``1`` for ``1.0``)."""
    text = (repr(float(v)) for v in np.asarray(values, dtype=float))
    return " ".join(t[:-2] if t.endswith(".0") else t for t in text)


def main(argv: list[str]) -> int:
    default = Path(__file__).resolve().parents[1] / "robots" / "myosuite"
    out = Path(argv[1]).resolve() if len(argv) > 1 else default
    out.mkdir(parents=True, exist_ok=True)
    for name in MODELS:
        with tempfile.TemporaryDirectory() as tmp, contextlib.chdir(tmp):  # MuJoCo's log file
            text = header(name) + standalone_xml(load_original(name))
        path = out / name
        path.write_text(text)
        print(f"{path}: {path.stat().st_size} bytes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
