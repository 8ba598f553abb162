"""What every command shares: the one-line usage error, the parser, option parsers and text tables."""

from __future__ import annotations

import argparse

import numpy as np

from ..exceptions import McdmError
from ..vocabulary import CONE_TYPES


class UsageError(McdmError):
    """Bad command-line arguments."""


class Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, no usage block; "mcdm-pin: error: " is printed by main
        command = self.prog.partition(" ")[2]  # "mcdm-pin solve" -> "solve"; "mcdm-pin" -> ""
        raise UsageError(f"{command + ': ' if command else ''}{message} (see --help)")


# ---------------------------------------------------------------------------------------- helpers
def parse_pairs(text: str, option: str, allow_all: bool = False) -> dict[str, str]:
    out = {}
    for item in text.split(","):
        item = item.strip()
        if not item:
            continue
        if "=" not in item:
            raise UsageError(f"{option}: expected NAME=VALUE[,NAME=VALUE...], got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip()] = v.strip()
    if not out:
        raise UsageError(f"{option}: expected NAME=VALUE[,NAME=VALUE...], got {text!r}")
    return out


def parse_float(text: str, option: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise UsageError(f"{option}: expected a number, got {text!r}") from None
    if not np.isfinite(x):
        raise UsageError(f"{option}: expected a finite number, got {text!r}")
    return x


def _check_joint(robot, name: str, option: str):
    if name not in robot.joint_names:
        raise UsageError(f"{option}: unknown joint {name!r}; expected one of {', '.join(robot.joint_names)}")


def parse_weights(robot, text: str | None):
    """``JOINT=ALPHA[:BETA],...`` -> (alpha dict, beta dict)."""
    if not text:
        return None, None
    alpha, beta = {}, {}
    for name, value in parse_pairs(text, "--weights").items():
        _check_joint(robot, name, "--weights")
        a, _, b = value.partition(":")
        alpha[name] = parse_float(a, f"--weights {name}")
        if b:
            beta[name] = parse_float(b, f"--weights {name}")
        for v in (alpha[name], beta.get(name, 0.0)):
            if v < 0:
                raise UsageError(f"--weights {name}: weights must be >= 0, got {value!r}")
    return alpha, beta


def parse_cones(robot, text: str | None):
    """``JOINT=DEG,...`` or ``all=DEG`` -> {joint: degrees}."""
    if not text:
        return None
    out = {}
    for name, value in parse_pairs(text, "--cone").items():
        deg = parse_float(value, f"--cone {name}")
        if not 0.0 < deg < 90.0:
            raise UsageError(f"--cone {name}: expected an angle in (0, 90) degrees, got {value!r}")
        if name == "all":
            for j in robot.joints:
                if j.type == "spherical":
                    out[j.name] = deg
            if not out:
                raise UsageError("--cone all: the robot has no spherical joint")
        else:
            _check_joint(robot, name, "--cone")
            if robot.joint(name).type not in CONE_TYPES:
                raise UsageError(f"--cone {name}: cones apply to spherical joints only (and to MJCF composite "
                                 f"joints)")
            out[name] = deg
    return out


def printable(text) -> str:
    """``text`` with control characters escaped (a name must not move the cursor or print a fake line)."""
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def table(headers, rows) -> str:
    cells = [[printable(c) for c in headers]] + [[printable(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = []
    for k, r in enumerate(cells):
        lines.append("  ".join(c.rjust(w) if k and numeric(c) else c.ljust(w) for c, w in zip(r, widths)))
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(line.rstrip() for line in lines)


def numeric(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


def check_outputs(outputs, inputs=(), option: str = "--out") -> list:
    """Check every output path before any work is done: its folder exists and is writable, it is not a
    folder, it is not given twice, and it is none of the run's input files (never overwrite an input).
    ``outputs``: ``[(option, path)]`` or paths; ``inputs``: ``[(what, path)]``."""
    import os
    from pathlib import Path

    seen: dict = {}
    resolved_inputs = {}
    for what, path in inputs:
        if path is not None:
            resolved_inputs[Path(path).resolve()] = what
    checked = []
    for item in outputs:
        opt, path = item if isinstance(item, tuple) else (option, item)
        path = Path(path)
        full = path.resolve()
        if full in seen:
            raise UsageError(f"{opt} {path}: given twice")
        seen[full] = True
        if full in resolved_inputs:
            raise UsageError(f"{opt} {path}: is an input of this run ({resolved_inputs[full]}); choose another file")
        folder = full.parent
        if not folder.is_dir():
            raise UsageError(f"{opt} {path}: the folder {path.parent} does not exist")
        if full.is_dir():
            raise UsageError(f"{opt} {path}: is a folder; expected a file name")
        if not os.access(folder, os.W_OK) or (full.exists() and not os.access(full, os.W_OK)):
            raise UsageError(f"{opt} {path}: cannot be written (no permission)")
        checked.append(path)
    return checked
