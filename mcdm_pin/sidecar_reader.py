"""The sidecar reader's parts shared by the sidecar's modules (:mod:`mcdm_pin.sidecar` and its
``sidecar_*`` parsers): the checked reading of values with their key paths (:class:`_Reader`), the
short descriptions of bad values its messages use, a configuration's reading, and the trajectory spec."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .exceptions import SidecarError
from .limits import MAX_MAGNITUDE

_FLOAT_RE = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


@dataclass(frozen=True)
class TrajectorySpec:
    """A named trajectory. ``type`` is ``quintic`` (q_start, q_end, duration, dt, spherical), ``csv``
    (file, resolved to an absolute path) or ``task`` (a task-space trajectory solved by inverse
    kinematics, :mod:`mcdm_pin.ik`: ``frame``, ``point``, ``coordinates``, ``euler``, and ``poses``
    ``((t, y), ...)`` with ``dt``, or a CSV ``file`` of poses; ``q_start``: the IK's first seed)."""

    name: str
    type: str
    q_start: Any = None
    q_end: Any = None
    duration: float | None = None
    dt: float | None = None
    spherical: str = "axis-angle"
    file: Path | None = None
    key: str = ""
    frame: str | None = None
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    coordinates: str = "xyz"
    euler: str = "zyx"
    poses: tuple = ()


class _Reader:
    def __init__(self, path: Path | None):
        self.path = path

    def fail(self, key: str, expected: str) -> SidecarError:
        return SidecarError(self.path, key, expected)

    def mapping(self, value, key: str, allowed: tuple[str, ...], required: tuple[str, ...] = ()):
        if not isinstance(value, dict):
            raise self.fail(key, f"expected a mapping with keys {_names(allowed)}, got {_kind(value)}")
        for k in value:
            if not isinstance(k, str):
                raise self.fail(key, f"keys must be strings, got {k!r}")
            if k not in allowed:
                raise self.fail(_join(key, k), f"unknown key {k!r}; expected one of {_names(allowed)}")
        for k in required:
            if k not in value:
                raise self.fail(_join(key, k), f"missing required key {k!r}")
        return value

    def number(self, value, key: str, *, lo=None, hi=None, lo_open=False, hi_open=False) -> float:
        if isinstance(value, bool) or value is None:
            raise self.fail(key, f"expected a number, got {_kind(value)}")
        if isinstance(value, str):
            # a quoted number in plain decimal notation is accepted (data built in code, old files)
            if not _FLOAT_RE.match(value.strip()):
                raise self.fail(key, f"expected a number, got the string {_short(value)}")
            value = float(value)
        if not isinstance(value, (int, float)):
            raise self.fail(key, f"expected a number, got {_kind(value)}")
        try:
            x = float(value)
        except OverflowError:
            raise self.fail(key, f"expected a number of magnitude at most {MAX_MAGNITUDE:g}, got an integer "
                                 f"of {len(str(abs(value)))} digits") from None
        if not math.isfinite(x):
            raise self.fail(key, f"expected a finite number, got {value!r}")
        if abs(x) > MAX_MAGNITUDE:
            raise self.fail(key, f"expected a number of magnitude at most {MAX_MAGNITUDE:g} (larger values "
                                 f"overflow in the dynamics), got {x!r}")
        if lo is not None and (x < lo or (lo_open and x == lo)):
            raise self.fail(key, f"expected a number {'>' if lo_open else '>='} {lo}, got {x!r}")
        if hi is not None and (x > hi or (hi_open and x == hi)):
            raise self.fail(key, f"expected a number {'<' if hi_open else '<='} {hi}, got {x!r}")
        return x

    def vector(self, value, key: str, n: int | None = 3) -> tuple[float, ...]:
        if not isinstance(value, (list, tuple)):
            raise self.fail(key, f"expected a list of {n or 'some'} numbers, got {_kind(value)}")
        if n is not None and len(value) != n:
            raise self.fail(key, f"expected a list of {n} numbers, got {len(value)}")
        return tuple(self.number(v, f"{key}[{i}]") for i, v in enumerate(value))

    def string(self, value, key: str) -> str:
        if not isinstance(value, str) or not value.strip():
            raise self.fail(key, f"expected a non-empty string, got {_kind(value)}")
        return value

    def choice(self, value, key: str, choices: tuple[str, ...]) -> str:
        if value not in choices:
            raise self.fail(key, f"expected one of {_names(choices)}, got {value!r}")
        return value


def _short(text: str, n: int = 60) -> str:
    return repr(text[:n]) + ("..." if len(text) > n else "")


def _kind(value) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, bool):
        return f"the boolean {value}"
    if isinstance(value, (dict, list, str)):
        text = repr(value)
        return f"{type(value).__name__} {text[:60]}{'...' if len(text) > 60 else ''}"
    return f"{type(value).__name__} {value!r}"


def _names(names) -> str:
    names = list(names)
    shown = ", ".join(repr(n) for n in names[:25])
    return shown + (f", ... ({len(names)} in all)" if len(names) > 25 else "")


def _join(key: str, sub: str) -> str:
    return f"{key}.{sub}" if key else sub


def _parse_q(r: _Reader, value, key: str):
    """A configuration: a list of numbers (one per coordinate, in the model's order) or a mapping
    physical joint name -> number or list of numbers (joints left out stay at 0)."""
    if isinstance(value, list):
        return tuple(r.number(v, f"{key}[{i}]") for i, v in enumerate(value))
    if isinstance(value, dict):
        out = {}
        for j, v in value.items():
            r.string(j, f"{key}.{j}")
            if isinstance(v, list):
                out[j] = tuple(r.number(x, f"{key}.{j}[{i}]") for i, x in enumerate(v))
            else:
                out[j] = (r.number(v, f"{key}.{j}"),)
        return out
    raise r.fail(key, f"expected a list of numbers or a mapping joint: value(s), got {_kind(value)}")
