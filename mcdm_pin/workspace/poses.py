"""The poses of a workspace: a grid, a seeded random sample, or a CSV file.

Poses are given in **coordinates** (one number per degree of freedom, named as ``mcdm-pin info``
names them: ``robot.coordinate_names``). Coordinates that a pose set does not vary are held at the
values of ``at`` (default 0).

Every pose set is cut into chunks without being held whole: pose ``i`` of a grid follows from ``i``
(C order: the last axis varies fastest), and pose ``i`` of a random sample is drawn from the seeded
stream at its own offset (``PCG64.advance``), so the sample does not depend on the chunk size or on
which chunk is computed first.
"""

from __future__ import annotations

import csv
import hashlib
from pathlib import Path

import numpy as np

from ..limits import MAX_WORKSPACE_POSES
from .errors import WorkspaceError

_NO_LIMIT = 1e6  # |limit| at or above this (Pinocchio's stand-in for "none"): no joint limit


def coordinate_index(robot, name: str, what: str) -> int:
    """Index of coordinate ``name`` in ``robot.coordinate_names`` (``what`` names the option)."""
    names = list(robot.coordinate_names)
    if name not in names:
        raise WorkspaceError(f"{what}: unknown coordinate {name!r}; expected one of {', '.join(names)} "
                             f"(see mcdm-pin info)")
    i = names.index(name)
    couplings = getattr(robot, "couplings", None)
    if couplings is not None and i in set(couplings.dependent.tolist()):
        raise WorkspaceError(f"{what}: coordinate {name!r} follows a coupling; vary the independent "
                             f"coordinates ({', '.join(couplings.independent_names)})")
    return i


def coordinate_units(robot) -> list[str]:
    """``rad`` or ``m`` for every coordinate, from its Pinocchio joint's type."""
    units = ["rad"] * robot.nv
    model = robot.model
    for j in range(1, model.njoints):
        jm = model.joints[j]
        short = jm.shortname()
        if short.startswith("JointModelP") and not short.startswith("JointModelPlanar"):
            kinds = ["m"] * jm.nv  # prismatic (any axis)
        elif short in ("JointModelTranslation",):
            kinds = ["m"] * jm.nv
        elif short == "JointModelFreeFlyer":
            kinds = ["m"] * 3 + ["rad"] * 3
        elif short == "JointModelPlanar":
            kinds = ["m", "m", "rad"]
        else:
            continue
        units[jm.idx_v:jm.idx_v + jm.nv] = kinds
    return units


def coordinate_limits(robot) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper joint limits of every coordinate from the model (NaN where there is none: no
    finite limit, or a joint whose configuration is not its coordinates, e.g. a continuous joint)."""
    model = robot.model
    lo, hi = np.full(robot.nv, np.nan), np.full(robot.nv, np.nan)
    for j in range(1, model.njoints):
        jm = model.joints[j]
        if jm.nq != jm.nv:
            continue
        for k in range(jm.nv):
            a = float(model.lowerPositionLimit[jm.idx_q + k])
            b = float(model.upperPositionLimit[jm.idx_q + k])
            if np.isfinite(a) and np.isfinite(b) and max(abs(a), abs(b)) < _NO_LIMIT and a < b:
                lo[jm.idx_v + k], hi[jm.idx_v + k] = a, b
    return lo, hi


def _fixed(robot, at: dict | None, varied: set) -> tuple[np.ndarray, dict]:
    """The base pose (``at`` values, 0 elsewhere) and ``at`` as plain floats."""
    base = np.zeros(robot.nv)
    out = {}
    for name, value in (at or {}).items():
        i = coordinate_index(robot, name, "at")
        if name in varied:
            raise WorkspaceError(f"at: coordinate {name!r} is also varied; give it one role")
        value = float(value)
        if not np.isfinite(value):
            raise WorkspaceError(f"at {name}: expected a finite number, got {value!r}")
        base[i] = value
        out[name] = value
    return base, out


class PoseSet:
    """Base of the pose sets: ``len()``, ``chunk(start, stop)`` -> (n, nv) coordinates, ``describe()``
    (plain data for the store's attributes) and ``axes`` (the grid axes, empty unless a grid)."""

    axes: tuple = ()

    def __init__(self, robot):
        self.coordinates = tuple(robot.coordinate_names)
        self.nv = robot.nv

    def __len__(self) -> int:
        raise NotImplementedError

    def chunk(self, start: int, stop: int) -> np.ndarray:
        raise NotImplementedError

    def describe(self) -> dict:
        raise NotImplementedError

    @property
    def shape(self) -> tuple[int, ...]:
        """The grid's shape (``(len(self),)`` for a list of poses)."""
        return (len(self),)

    def all(self) -> np.ndarray:
        return self.chunk(0, len(self))


class Grid(PoseSet):
    """A regular grid: ``axes = {coordinate: (lo, hi, n)}`` (``np.linspace(lo, hi, n)`` each, in the
    order given; the last varies fastest), other coordinates at ``at`` (default 0)."""

    def __init__(self, robot, axes: dict, at: dict | None = None):
        super().__init__(robot)
        if not axes:
            raise WorkspaceError("grid: expected at least one axis COORD=LO:HI:N")
        built, idx = [], []
        for name, spec in axes.items():
            i = coordinate_index(robot, name, "grid")
            try:
                lo, hi, n = float(spec[0]), float(spec[1]), spec[2]
            except (TypeError, ValueError, IndexError):
                raise WorkspaceError(f"grid {name}: expected (lo, hi, n), got {spec!r}") from None
            if not (np.isfinite(lo) and np.isfinite(hi)):
                raise WorkspaceError(f"grid {name}: expected finite bounds, got {lo!r}:{hi!r}")
            if int(n) != n or n < 1:
                raise WorkspaceError(f"grid {name}: expected a positive whole number of points, got {n!r}")
            if n > 1 and not lo < hi:
                raise WorkspaceError(f"grid {name}: expected LO < HI, got {lo!r}:{hi!r}")
            total = int(n) * int(np.prod([len(v) for _, v in built], dtype=float))
            if total > MAX_WORKSPACE_POSES:
                raise WorkspaceError(f"grid {name}: the grid would have {total} poses; at most "
                                     f"{MAX_WORKSPACE_POSES} (docs/limits.md)")
            built.append((name, np.linspace(lo, hi, int(n))))
            idx.append(i)
        self.axes = tuple(built)
        self._idx = np.array(idx, dtype=int)
        self._spec = [dict(coordinate=name, lo=float(v[0]), hi=float(v[-1]), n=len(v)) for name, v in built]
        self.base, self.at = _fixed(robot, at, set(axes))

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for _, v in self.axes)

    def __len__(self) -> int:
        return int(np.prod(self.shape))

    def chunk(self, start: int, stop: int) -> np.ndarray:
        k = np.unravel_index(np.arange(start, stop), self.shape)
        q = np.tile(self.base, (stop - start, 1))
        for a, (_, values) in enumerate(self.axes):
            q[:, self._idx[a]] = values[k[a]]
        return q

    def describe(self) -> dict:
        return dict(kind="grid", axes=self._spec, at=self.at, n=len(self))


class RandomPoses(PoseSet):
    """``n`` poses drawn uniformly (seed ``seed``) in ``ranges = {coordinate: (lo, hi)}``; other
    coordinates at ``at``, or uniformly within their joint limits when they have finite ones."""

    def __init__(self, robot, n: int, seed: int = 0, ranges: dict | None = None, at: dict | None = None):
        super().__init__(robot)
        if int(n) != n or n < 1:
            raise WorkspaceError(f"random: expected a positive number of poses, got {n!r}")
        if n > MAX_WORKSPACE_POSES:
            raise WorkspaceError(f"random: expected at most {MAX_WORKSPACE_POSES} poses (docs/limits.md), got {n!r}")
        if int(seed) != seed or seed < 0:
            raise WorkspaceError(f"seed: expected a whole number >= 0, got {seed!r}")
        self.n, self.seed = int(n), int(seed)
        ranges = dict(ranges or {})
        self.base, self.at = _fixed(robot, at, set(ranges))
        lo, hi = coordinate_limits(robot)
        self.lo, self.hi = lo.copy(), hi.copy()
        for name, spec in ranges.items():
            i = coordinate_index(robot, name, "range")
            try:
                a, b = float(spec[0]), float(spec[1])
            except (TypeError, ValueError, IndexError):
                raise WorkspaceError(f"range {name}: expected (lo, hi), got {spec!r}") from None
            if not (np.isfinite(a) and np.isfinite(b) and a < b):
                raise WorkspaceError(f"range {name}: expected finite LO < HI, got {a!r}:{b!r}")
            self.lo[i], self.hi[i] = a, b
        for name in self.at:
            i = coordinate_index(robot, name, "at")
            self.lo[i] = self.hi[i] = self.base[i]
        missing = [c for c, a in zip(self.coordinates, self.lo) if not np.isfinite(a)]
        if missing:
            raise WorkspaceError(f"random: coordinates {', '.join(missing)} have no finite joint limit; "
                                 f"give each a range (COORD=LO:HI) or a fixed value (at COORD=VALUE)")

    def __len__(self) -> int:
        return self.n

    def chunk(self, start: int, stop: int) -> np.ndarray:
        bits = np.random.PCG64(self.seed)
        bits.advance(start * self.nv)  # one 64-bit draw per double: pose i starts at i * nv
        u = np.random.Generator(bits).random((stop - start, self.nv))
        return self.lo + (self.hi - self.lo) * u

    def describe(self) -> dict:
        return dict(kind="random", n=self.n, seed=self.seed,
                    ranges={c: [float(a), float(b)] for c, a, b in zip(self.coordinates, self.lo, self.hi)
                            if c not in self.at},
                    at=self.at)


class PosesFile(PoseSet):
    """Poses from a CSV file: a header row of coordinate names (all or some; the others at ``at``,
    default 0) then one pose per row; or, without a header, rows of all nv coordinates in order."""

    def __init__(self, robot, path, at: dict | None = None):
        super().__init__(robot)
        self.path = Path(path)
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise WorkspaceError(f"{self.path}: poses file not found") from None
        except (OSError, UnicodeDecodeError) as exc:
            raise WorkspaceError(f"{self.path}: cannot read the poses file ({exc})") from None
        self.sha256 = hashlib.sha256(text.encode()).hexdigest()
        rows = [r for r in csv.reader(text.splitlines()) if r and any(c.strip() for c in r)]
        if not rows:
            raise WorkspaceError(f"{self.path}: no poses in the file")
        header = [c.strip() for c in rows[0]]
        if _numeric(header):
            names = list(self.coordinates)
        else:
            names, rows = header, rows[1:]
            for k, name in enumerate(names):
                coordinate_index(robot, name, f"{self.path}: header column {k + 1}")
            if len(set(names)) != len(names):
                raise WorkspaceError(f"{self.path}: header names a coordinate twice: {', '.join(names)}")
        self.columns = names
        self.base, self.at = _fixed(robot, at, set(names))
        cols = [self.coordinates.index(n) for n in names]
        q = np.tile(self.base, (len(rows), 1))
        for r, row in enumerate(rows):
            line = f"pose {r + 1}"
            if len(row) != len(names):
                raise WorkspaceError(f"{self.path}: {line}: expected {len(names)} numbers "
                                     f"({', '.join(names)}), got {len(row)}")
            try:
                values = [float(c) for c in row]
            except ValueError:
                raise WorkspaceError(f"{self.path}: {line}: expected numbers, got {row}") from None
            if not np.all(np.isfinite(values)):
                raise WorkspaceError(f"{self.path}: {line}: expected finite numbers, got {row}")
            q[r, cols] = values
        if not len(q):
            raise WorkspaceError(f"{self.path}: no poses in the file (only a header)")
        self.q = q

    def __len__(self) -> int:
        return len(self.q)

    def chunk(self, start: int, stop: int) -> np.ndarray:
        return self.q[start:stop].copy()

    def describe(self) -> dict:
        return dict(kind="file", path=str(self.path), sha256=self.sha256, columns=self.columns,
                    at=self.at, n=len(self))


def _numeric(row) -> bool:
    try:
        [float(c) for c in row]
        return True
    except ValueError:
        return False
