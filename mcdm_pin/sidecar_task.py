"""The sidecar's ``task`` trajectories (a frame's poses over time, solved by inverse kinematics in
:mod:`mcdm_pin.ik`): YAML -> a validated :class:`~mcdm_pin.sidecar.TrajectorySpec` (no Pinocchio here).

.. code-block:: yaml

    trajectories:
      reach:
        type: task
        frame: forearm            # a frame of the model (a URDF link's name)
        point: [0, 0.24, 0]       # in the frame, m (default: its origin)
        coordinates: xyz          # kept coordinates, letters of xyzabg (default xyz)
        euler: zyx                # angles a b g: R = Rz(g) Ry(b) Rx(a) (zyx) or Rx(a) Ry(b) Rz(g) (xyz)
        poses:                    # rest-to-rest quintics between consecutive poses ...
          - {t: 0.0, y: [0.1, 0.5, 0.0]}
          - {t: 1.0, y: [0.2, 0.4, 0.1]}
        dt: 0.01
        # file: poses.csv         # ... or a CSV of poses: t and the coordinates' letters
        # q_seed: {shoulder: [0, 0.3, 0], elbow: 0.5}   # where the first IK starts (default: reference)
"""

from __future__ import annotations

from pathlib import Path

from .limits import MAX_SAMPLES
from .sidecar_reader import TrajectorySpec, _kind, _parse_q, _Reader

TASK_COORDINATES = "xyzabg"  # mcdm_pin.ik.space
TASK_EULER = ("zyx", "xyz")
TASK_KEYS = ("type", "frame", "point", "coordinates", "euler", "poses", "dt", "file", "q_seed")


def parse_task(r: _Reader, name, spec, base_dir: Path, key: str) -> TrajectorySpec:
    """A task-space trajectory: a frame, a point in it, the coordinates kept (letters of ``xyzabg``),
    and poses (``[{t, y}, ...]`` with ``dt``: rest-to-rest quintics between them) or a CSV ``file``."""
    spec = r.mapping(spec, key, TASK_KEYS, required=("type", "frame"))
    frame = r.string(spec["frame"], f"{key}.frame")
    point = r.vector(spec.get("point", [0.0, 0.0, 0.0]), f"{key}.point")
    coords = r.string(spec.get("coordinates", "xyz"), f"{key}.coordinates")
    if any(c not in TASK_COORDINATES for c in coords) or len(set(coords)) != len(coords):
        raise r.fail(f"{key}.coordinates", f"expected distinct letters of {TASK_COORDINATES!r} (x y z: the point's "
                                           f"position, a b g: Euler angles of the frame), got {coords!r}")
    euler = r.choice(spec.get("euler", "zyx"), f"{key}.euler", TASK_EULER)
    seed = _parse_q(r, spec["q_seed"], f"{key}.q_seed") if spec.get("q_seed") is not None else None
    if ("poses" in spec) == ("file" in spec):
        raise r.fail(key, "expected either 'poses' (with 'dt') or 'file' (a CSV of poses)")
    common = dict(name=name, type="task", key=key, frame=frame, point=point, coordinates=coords, euler=euler,
                  q_start=seed)
    if "file" in spec:
        if "dt" in spec:
            raise r.fail(f"{key}.dt", "'dt' goes with 'poses'; a CSV file gives its own times")
        return TrajectorySpec(file=(base_dir / r.string(spec["file"], f"{key}.file")).resolve(), **common)
    raw = spec["poses"]
    if not isinstance(raw, list) or len(raw) < 2:
        raise r.fail(f"{key}.poses", f"expected a list of at least two poses {{t: s, y: [...]}}, got {_kind(raw)}")
    poses = []
    for i, pose in enumerate(raw):
        pk = f"{key}.poses[{i}]"
        pose = r.mapping(pose, pk, ("t", "y"), required=("t", "y"))
        t = r.number(pose["t"], f"{pk}.t")
        if poses and not t > poses[-1][0]:
            raise r.fail(f"{pk}.t", f"expected a time after {poses[-1][0]!r} s, got {t!r}")
        poses.append((t, r.vector(pose["y"], f"{pk}.y", len(coords))))
    if "dt" not in spec:
        raise r.fail(f"{key}.dt", "missing; expected the sample time step (s) of the poses' quintics")
    dt = r.number(spec["dt"], f"{key}.dt", lo=0.0, lo_open=True)
    span = poses[-1][0] - poses[0][0]
    if span / dt + 1 > MAX_SAMPLES:
        raise r.fail(f"{key}.dt", f"expected at most {MAX_SAMPLES} samples (docs/limits.md), got {span / dt + 1:.3g}")
    return TrajectorySpec(poses=tuple(poses), dt=dt, duration=span, **common)
