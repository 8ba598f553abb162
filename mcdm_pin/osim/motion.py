r"""OpenSim motions (``.sto``/``.mot`` tables of coordinates, speeds, accelerations) as Pinocchio states.

A table has a header ending at ``endheader``, a row of column labels (``time`` first) and rows of
numbers (a row repeating the previous row's time and values, as OpenSim's CMC writes its last step,
is read once). With ``inDegrees=yes`` the rotational coordinates' columns (values, speeds, accelerations)
are in degrees; they are converted to radians here. A coordinate is translational when a
``SliderJoint`` carries it or a ``CustomJoint`` uses it only in translation axes; every other
coordinate is rotational.

:func:`motion_states` samples the three tables at given times (linear interpolation between rows: the
tables of OpenSim's CMC come at its own variable steps) and maps OpenSim's speeds and accelerations
to Pinocchio's ``v``, ``a`` (:meth:`~mcdm_pin.osim.load.OsimSource.velocity`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..exceptions import ModelError

DUPLICATE_TOL = 1e-6  # relative: a row repeating the previous time must repeat its values this closely


@dataclass(frozen=True)
class Table:
    """An OpenSim table: ``labels`` (columns after ``time``), ``time`` (T,), ``data`` (T, C)."""

    labels: tuple
    time: np.ndarray
    data: np.ndarray
    in_degrees: bool

    def column(self, label: str) -> np.ndarray:
        return self.data[:, self.labels.index(label)]


def read_table(path) -> Table:
    """Read a ``.sto``/``.mot`` file; ModelError names the file and line of anything malformed."""
    path = Path(path)
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    try:
        end = next(i for i, s in enumerate(lines) if s.strip().lower() == "endheader")
    except StopIteration:
        raise ModelError(f"{path}: no 'endheader' line") from None
    header = {k.strip().lower(): v.strip().lower() for k, _, v in (s.partition("=") for s in lines[:end]) if v}
    labels = lines[end + 1].split()
    if not labels or labels[0].lower() != "time":
        raise ModelError(f"{path}: line {end + 2}: expected column labels starting with 'time'")
    rows = []
    for n, s in enumerate(lines[end + 2:], end + 3):
        if not s.strip():
            continue
        try:
            row = [float(x) for x in s.split()]
        except ValueError:
            raise ModelError(f"{path}: line {n}: expected numbers") from None
        if len(row) != len(labels):
            raise ModelError(f"{path}: line {n}: expected {len(labels)} numbers, got {len(row)}")
        rows.append(row)
    data = np.array(rows, dtype=float).reshape(-1, len(labels))
    if not np.isfinite(data).all():
        raise ModelError(f"{path}: entries that are not finite numbers")
    same = np.flatnonzero(np.diff(data[:, 0]) == 0)
    if same.size:  # OpenSim's CMC writes its last step twice: a repeated row is read once
        a, b = data[same], data[same + 1]
        if np.any(np.abs(a - b) > DUPLICATE_TOL * np.maximum(1.0, np.abs(a))):
            raise ModelError(f"{path}: rows at time {data[same[0], 0]:g} s repeat the time with other values")
        data = np.delete(data, same + 1, axis=0)
    if np.any(np.diff(data[:, 0]) <= 0):
        raise ModelError(f"{path}: the time column is not increasing")
    return Table(tuple(labels[1:]), data[:, 0], data[:, 1:], header.get("indegrees", "no") == "yes")


def translational_coordinates(doc) -> set:
    """Names of the translational coordinates of a read document (module docstring)."""
    out, rotational = set(), set()
    for j in doc.joints:
        if j.tag == "SliderJoint":
            out.update(c.name for c in j.coordinates)
        for ax in j.axes:
            (rotational if ax.rotation else out).update(ax.coordinates)
    return out - rotational


def motion_states(source, doc, q_file, u_file, udot_file, times):
    """``(q, v, a)`` (T, nq), (T, nv), (T, nv) at ``times`` (s) from OpenSim's coordinate, speed and
    acceleration tables (module docstring; a :class:`Table` already read is taken as it is). ``source``:
    the robot's :class:`~mcdm_pin.osim.load.OsimSource`; ``doc``: its read document (which coordinates
    rotate)."""
    tables = [f if isinstance(f, Table) else read_table(f) for f in (q_file, u_file, udot_file)]
    times = np.asarray(times, dtype=float)
    names = source.maps.coordinates
    slide = translational_coordinates(doc)
    for t, f in zip(tables, (q_file, u_file, udot_file)):
        f = "a table" if isinstance(f, Table) else f
        missing = [n for n in names if n not in t.labels]
        if missing:
            raise ModelError(f"{f}: no column for coordinate(s) {missing}")
        if times.min() < t.time[0] - 1e-12 or times.max() > t.time[-1] + 1e-12:
            raise ModelError(f"{f}: times {times.min():g}..{times.max():g} s outside the table's "
                             f"{t.time[0]:g}..{t.time[-1]:g} s")

    def sample(t: Table) -> dict:
        scale = {n: (np.pi / 180.0 if t.in_degrees and n not in slide else 1.0) for n in names}
        return {n: np.interp(times, t.time, t.column(n)) * scale[n] for n in names}

    qs, us, udots = (sample(t) for t in tables)
    Q, V, A = [], [], []
    for k in range(len(times)):
        q = source.configuration({n: qs[n][k] for n in names})
        v, a = source.velocity(q, {n: us[n][k] for n in names}, {n: udots[n][k] for n in names})
        Q.append(q)
        V.append(v)
        A.append(a)
    return np.array(Q), np.array(V), np.array(A)
