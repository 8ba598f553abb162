"""What a file on the command line is (by its content, not only its name), so that a robot given where
a results file belongs, a URDF given where its sidecar belongs, or two files swapped, get one line that
names each file and what to pass instead."""

from __future__ import annotations

import re
from pathlib import Path

from ._common import UsageError

WHAT = {
    "results": "a results file (.npz, from mcdm-pin solve --out)",
    "sidecar": "a cable sidecar (YAML)",
    "urdf": "a URDF (XML robot description)",
    "mjcf": "a MuJoCo MJCF file",
    "osim": "an OpenSim model (.osim)",
    "xml": "an XML file",
    "csv": "a CSV file",
    "binary": "a binary file",
    "missing": "not found",
}


def file_kind(path) -> str:
    """``results``, ``sidecar``, ``urdf``, ``mjcf``, ``xml``, ``csv``, ``binary`` or ``missing``: read from the
    first bytes of the file (a ``.npz`` is a zip archive; a URDF is XML with a ``<robot`` element),
    then from its extension. Text that is none of these counts as a sidecar (the YAML loader then
    says what is wrong with it)."""
    p = Path(path)
    if not p.is_file():
        return "missing"
    with p.open("rb") as fh:
        head = fh.read(4096)
    suffix = p.suffix.lower()
    if head.startswith(b"PK\x03\x04") or suffix == ".npz":
        return "results"
    try:
        text = head.decode("utf-8")
    except UnicodeDecodeError as exc:  # a multi-byte character cut at the end of the head is fine
        if exc.start < len(head) - 4:
            return "binary"
        text = head[:exc.start].decode("utf-8")
    if "\x00" in text:
        return "binary"
    stripped = text.lstrip("\ufeff \t\r\n")
    if stripped.startswith("<") or suffix in (".urdf", ".xml", ".mjcf", ".osim"):
        if suffix == ".osim" or "<OpenSimDocument" in text:
            return "osim"
        if re.search(r"<mujoco[\s>]", text):
            return "mjcf"
        return "urdf" if "<robot" in text or suffix == ".urdf" else "xml"
    if suffix == ".csv":
        return "csv"
    return "sidecar"


def _sidecars_naming(urdf: Path) -> list[Path]:
    """Sidecars near a URDF (its folder, the folder above, and a ``robots/`` folder beside it) whose
    text names the URDF's file."""
    places = {urdf.parent, urdf.parent.parent, urdf.parent.parent / "robots"}
    found = []
    for folder in places:
        for path in sorted(folder.glob("*.y*ml")):
            try:
                if urdf.name in path.read_text(encoding="utf-8", errors="replace")[:20000]:
                    found.append(path)
            except OSError:
                continue
    return sorted(set(found))


def robot_file(path, where: str = "ROBOT") -> str:
    """``path`` if it can be a robot's sidecar; otherwise a :class:`UsageError` saying what it is and
    what to pass instead."""
    kind = file_kind(path)
    if kind in ("sidecar", "missing", "mjcf", "osim"):  # missing: the loader's own message names the file
        return str(path)
    if kind == "urdf":
        near = _sidecars_naming(Path(path))
        hint = (f" (here: {', '.join(str(p) for p in near)})" if near else
                " (write one that names it: docs/sidecar.md)")
        raise UsageError(f"{where}: {path} is a URDF; mcdm-pin reads a robot from its cable sidecar "
                         f"(YAML), which names the URDF and adds the joints and cables: pass the "
                         f"sidecar instead{hint}")
    if kind == "xml":
        raise UsageError(f"{where}: {path} is an XML file, not a cable sidecar (YAML); CASPR models are "
                         f"converted with mcdm-pin import-caspr")
    raise UsageError(f"{where}: {path} is {WHAT[kind]}, not a cable sidecar (YAML)")


def robot_and_results(first, second) -> tuple[str, str]:
    """(sidecar, results) from two paths given in either order, told apart by their content."""
    kinds = (file_kind(first), file_kind(second))
    if kinds[0] == "results" and kinds[1] != "results":
        first, second = second, first
        kinds = kinds[::-1]
    if kinds[1] != "results" or kinds[0] == "results":
        raise UsageError(f"expected a robot's sidecar (YAML) and a results file (.npz), in either order; "
                         f"got {first} ({WHAT[kinds[0]]}) and {second} ({WHAT[kinds[1]]})")
    return robot_file(first), str(second)
