r"""A sidecar's ``task`` trajectory's task-space samples, from poses or a CSV (solved into a joint
trajectory by :func:`mcdm_pin.trajectory.task_trajectory`).

**Poses** ``[{t, y}, ...]`` with ``dt``: between consecutive poses every coordinate follows the
rest-to-rest quintic :math:`y(t) = y_i + (y_{i+1} - y_i)\,s(\tau)`, :math:`s = 10\tau^3 - 15\tau^4 +
6\tau^5`, :math:`\tau = (t - t_i)/(t_{i+1} - t_i)` (zero rates at every pose); each segment is sampled
at :math:`n = \lceil (t_{i+1} - t_i)/dt \rceil` equal steps (so every pose time is a sample and no step
exceeds ``dt``), the junctions once.

**CSV** ``file``: a header ``t`` and the coordinates' letters (any order), or no header and the columns
``t`` then the coordinates in the spec's order; at least 6 rows with strictly increasing times. The
rates are the derivatives of the interpolating quintic B-spline (``scipy.interpolate.
make_interp_spline(k=5)``), as for joint CSV trajectories.
"""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import TrajectoryError
from ..profiles import csv_rows, is_number, quintic_profile


def pose_samples(poses, dt: float):
    """``(t, y, yd, ydd)`` of rest-to-rest quintics through ``poses`` ``((t_i, y_i), ...)``."""
    ts, ys, yds, ydds = [], [], [], []
    for i in range(len(poses) - 1):
        (t0, y0), (t1, y1) = poses[i], poses[i + 1]
        y0, y1 = np.asarray(y0, dtype=float), np.asarray(y1, dtype=float)
        T = t1 - t0
        n = max(1, math.ceil(T / dt - 1e-9))
        tau = np.linspace(0.0, T, n + 1)[(0 if i == 0 else 1):]
        s, ds, dds = quintic_profile(tau, T)
        ts.append(t0 + tau)
        ys.append(y0 + np.outer(s, y1 - y0))
        yds.append(np.outer(ds, y1 - y0))
        ydds.append(np.outer(dds, y1 - y0))
    return np.concatenate(ts), np.vstack(ys), np.vstack(yds), np.vstack(ydds)


def csv_samples(path, coordinates: str):
    """``(t, y, yd, ydd)`` of a CSV of poses (module docstring)."""
    from scipy.interpolate import make_interp_spline

    rows = csv_rows(path)
    cols = ["t", *coordinates]
    order = list(range(len(cols)))
    first = 0
    if rows and not any(is_number(c) for c in rows[0]):
        head = [c.strip() for c in rows[0]]
        if sorted(head) != sorted(cols):
            raise TrajectoryError(f"{path}: row 1: header {head}; expected the columns {', '.join(cols)} (any order)")
        order, first = [head.index(c) for c in cols], 1
    try:
        data = np.array([[float(row[j]) for j in order] for row in rows[first:]], dtype=float)
    except (ValueError, IndexError):
        raise TrajectoryError(f"{path}: expected {len(cols)} numbers per row ({', '.join(cols)})") from None
    if any(len(row) != len(cols) for row in rows[first:]):
        raise TrajectoryError(f"{path}: expected {len(cols)} columns per row ({', '.join(cols)})")
    if len(data) < 6 or not np.all(np.isfinite(data)) or np.any(np.diff(data[:, 0]) <= 0):
        raise TrajectoryError(f"{path}: expected at least 6 rows of finite numbers with strictly increasing times "
                              f"(got {len(data)} rows)")
    t, y = data[:, 0], data[:, 1:]
    spline = make_interp_spline(t, y, k=5)
    return t, y, spline(t, 1), spline(t, 2)
