"""Where an element sits in a model file: the loaders' refusals name its line (MJCF, OpenSim)."""

from __future__ import annotations

import re
from pathlib import Path


def line_of(path, pattern: re.Pattern) -> str:
    """`` (line N)`` of the first line of the file ``path`` that ``pattern`` matches; ``""`` when none
    does or there is no such file (a model built in code, an element from an included file)."""
    path = Path(path)
    if not path.is_file():
        return ""
    with open(path, encoding="utf-8", errors="replace") as fh:
        for n, line in enumerate(fh, 1):
            if pattern.search(line):
                return f" (line {n})"
    return ""
