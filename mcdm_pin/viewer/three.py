"""three.js objects as Meshcat's browser client receives them (lowered JSON), and the rotations and
quaternions the animation needs. Nothing here knows about robots."""

from __future__ import annotations

import base64
import uuid as _uuid_mod

import numpy as np

from ..extras import optional

RX90 = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # takes +y to +z (URDF cylinders lie on z)


class Command(dict):
    """A lowered Meshcat command (what ``meshcat.Visualizer`` sends), replayable live or in HTML."""

    def lower(self):
        return self


def uuid() -> str:
    return str(_uuid_mod.uuid1())


def hex_color(rgb) -> int:
    r, g, b = (int(round(255 * float(np.clip(c, 0, 1)))) for c in rgb[:3])
    return (r << 16) + (g << 8) + b


def pack(x: np.ndarray, dtype) -> dict:
    """A typed array as Meshcat packs it (msgpack extension types)."""
    umsgpack = optional("umsgpack", "the viewer")

    x = np.asarray(x, dtype=dtype)
    code, name = {np.dtype(np.float32): (0x17, "Float32Array"),
                  np.dtype(np.uint32): (0x16, "Uint32Array")}[x.dtype]
    return {"itemSize": int(x.shape[1]) if x.ndim == 2 else 1, "type": name,
            "array": umsgpack.Ext(code, x.tobytes("C")), "normalized": False}


# ------------------------------------------------------------------------------------------ objects
def obj(geometry: dict | None, material: dict, name: str = "body", extra: dict | None = None,
        kind: str = "Mesh") -> dict:
    """A three.js object JSON for one mesh, line set or sprite (``geometry`` and ``material`` as
    lowered dicts; a sprite has no geometry)."""
    data = {"metadata": {"version": 4.5, "type": "Object"}, "materials": [material],
            "object": {"uuid": uuid(), "type": kind, "name": name, "material": material["uuid"],
                       "matrix": np.eye(4).flatten().tolist()}}
    if geometry is not None:
        data["geometries"] = [geometry]
        data["object"]["geometry"] = geometry["uuid"]
    for k, v in (extra or {}).items():
        data.setdefault(k, []).extend(v)
    return data


def material(rgb, kind: str = "MeshLambertMaterial", opacity: float = 1.0, **extra) -> dict:
    m = {"uuid": uuid(), "type": kind, "color": hex_color(rgb), "side": 2,
         "transparent": bool(opacity < 1.0), "opacity": float(opacity), "depthWrite": bool(opacity >= 1.0)}
    if kind in ("MeshLambertMaterial", "MeshPhongMaterial"):
        m["reflectivity"] = 0.5
    m.update(extra)
    return m


def cylinder(height, radius_top, radius_bottom, segments: int = 24) -> dict:
    """Along +y, centred on the origin."""
    return {"uuid": uuid(), "type": "CylinderGeometry", "radiusTop": float(radius_top),
            "radiusBottom": float(radius_bottom), "height": float(height), "radialSegments": segments}


def sphere(radius) -> dict:
    return {"uuid": uuid(), "type": "SphereGeometry", "radius": float(radius), "widthSegments": 20,
            "heightSegments": 20}


def box(size) -> dict:
    return {"uuid": uuid(), "type": "BoxGeometry", "width": float(size[0]), "height": float(size[1]),
            "depth": float(size[2])}


def mesh(vertices: np.ndarray, faces: np.ndarray) -> dict:
    """An indexed triangle mesh with smooth (area-weighted) vertex normals."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(faces, dtype=np.int64)
    n = np.zeros_like(v)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    for k in range(3):
        np.add.at(n, f[:, k], face_n)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return {"uuid": uuid(), "type": "BufferGeometry",
            "data": {"attributes": {"position": pack(v, np.float32), "normal": pack(n, np.float32)},
                     "index": pack(f.reshape(-1), np.uint32)}}


def line_segments(points: np.ndarray, colors: np.ndarray) -> dict:
    """Line segments between consecutive pairs of ``points`` (2k, 3), coloured per vertex (2k, 3)."""
    geometry = {"uuid": uuid(), "type": "BufferGeometry",
                "data": {"attributes": {"position": pack(points, np.float32),
                                        "color": pack(colors, np.float32)}}}
    mat = {"uuid": uuid(), "type": "LineBasicMaterial", "vertexColors": 2, "color": 0xFFFFFF}
    return obj(geometry, mat, kind="LineSegments")


def sprite(png: bytes, width: float, height: float) -> tuple[dict, np.ndarray]:
    """A label that always faces the camera: (object, its 4x4 scale matrix for ``width`` x ``height``
    metres). Drawn over everything else, so that it is never hidden inside a link."""
    image = {"uuid": uuid(), "url": "data:image/png;base64," + base64.b64encode(png).decode("ascii")}
    texture = {"uuid": uuid(), "image": image["uuid"], "wrap": [1001, 1001], "repeat": [1, 1]}
    mat = {"uuid": uuid(), "type": "SpriteMaterial", "map": texture["uuid"], "transparent": True,
           "depthTest": False, "depthWrite": False, "sizeAttenuation": True, "color": 0xFFFFFF}
    out = obj(None, mat, kind="Sprite", extra={"textures": [texture], "images": [image]})
    out["object"]["renderOrder"] = 10
    return out, T(scale=(width, height, 1.0))


# ---------------------------------------------------------------------------------------- geometry
def T(R=None, p=None, scale=None) -> np.ndarray:
    """A 4x4 transform ``[R diag(scale) | p]``."""
    out = np.eye(4)
    if R is not None:
        out[:3, :3] = R
    if scale is not None:
        out[:3, :3] = out[:3, :3] @ np.diag(np.broadcast_to(np.asarray(scale, float), (3,)))
    if p is not None:
        out[:3, 3] = p
    return out


def rot_y_to(v: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) taking +y to the unit vectors along ``v`` (N, 3); a zero vector
    gives the identity, -y a half turn about x."""
    v = np.asarray(v, dtype=float).reshape(-1, 3)
    n = np.linalg.norm(v, axis=1)
    u = np.where(n[:, None] > 1e-15, v / np.where(n > 1e-15, n, 1.0)[:, None], [0.0, 1.0, 0.0])
    # Rodrigues with axis y x u (unnormalised, |.| = sin), cos = u_y: R = I + K + K^2 / (1 + c)
    c = u[:, 1]
    k = np.stack([u[:, 2], np.zeros_like(c), -u[:, 0]], axis=1)
    K = np.zeros((len(u), 3, 3))
    K[:, 0, 1], K[:, 0, 2] = -k[:, 2], k[:, 1]
    K[:, 1, 0], K[:, 1, 2] = k[:, 2], -k[:, 0]
    K[:, 2, 0], K[:, 2, 1] = -k[:, 1], k[:, 0]
    flip = c < -1 + 1e-12
    denom = np.where(flip, 1.0, 1.0 + c)
    R = np.eye(3) + K + (K @ K) / denom[:, None, None]
    R[flip] = np.diag([1.0, -1.0, -1.0])
    return R


def rotation_between(a, b) -> np.ndarray:
    """The smallest rotation taking the direction ``a`` to the direction ``b`` (3, 3); opposite
    directions: a half turn about an axis normal to ``a``."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    v, c = np.cross(a, b), float(a @ b)
    if c < -1 + 1e-12:
        n = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
        n /= np.linalg.norm(n)
        return 2.0 * np.outer(n, n) - np.eye(3)
    K = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + K + K @ K / (1.0 + c)


def quat_xyzw(R: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations -> (N, 4) quaternions [x, y, z, w] (three.js order), sign-continuous."""
    import pinocchio as pin

    R = np.asarray(R, dtype=float).reshape(-1, 3, 3)
    q = np.array([pin.Quaternion(m).coeffs() for m in R]).reshape(-1, 4)  # Eigen's order: x, y, z, w
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for k in range(1, len(q)):
        if q[k] @ q[k - 1] < 0:
            q[k] = -q[k]
    return q
