"""Reading CASPR's XML: parsing (the DTD is never resolved) and typed readers whose errors name the
file and the element."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from ..exceptions import CasprError
from ..limits import MAX_XML_BYTES


def parse_xml(path) -> tuple[Path, ET.Element]:
    """The root element of ``path``; :class:`CasprError` if it cannot be read or is not XML."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        raise CasprError(path, "", "file not found") from None
    except OSError as exc:
        raise CasprError(path, "", f"cannot read the file ({exc.strerror or exc})") from None
    if size > MAX_XML_BYTES:
        raise CasprError(path, "", f"the file has {size} bytes; a CASPR XML file may have at most "
                                   f"{MAX_XML_BYTES} (docs/limits.md)")
    try:
        # expat does not fetch the external DTD CASPR's files declare; entities stay unresolved
        return path, ET.parse(path).getroot()
    except IsADirectoryError:
        raise CasprError(path, "", "is a folder; expected a CASPR XML file") from None
    except ET.ParseError as exc:
        raise CasprError(path, "", f"malformed XML ({exc})") from None
    except OSError as exc:
        raise CasprError(path, "", f"cannot read the file ({exc.strerror or exc})") from None
    except RecursionError:
        raise CasprError(path, "", "malformed XML (nested too deeply)") from None


def child(path, elem: ET.Element, tag: str, where: str) -> ET.Element:
    found = elem.find(tag)
    if found is None:
        raise CasprError(path, where, f"missing <{tag}> element")
    return found


def text(path, elem: ET.Element, tag: str, where: str) -> str:
    value = child(path, elem, tag, where).text
    if value is None or not value.strip():
        raise CasprError(path, f"{where}/{tag}", "empty; expected a value")
    return value


def numbers(path, value: str | None, where: str, n: int | None = None) -> tuple[float, ...]:
    """Whitespace-separated finite numbers (``n`` of them when given)."""
    if value is None:
        raise CasprError(path, where, f"missing; expected {n or 'some'} number{'s' if n != 1 else ''}")
    parts = value.split()
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise CasprError(path, where, f"expected whitespace-separated numbers, got {value.strip()[:80]!r}") from None
    if n is not None and len(values) != n:
        raise CasprError(path, where, f"expected {n} number{'s' if n != 1 else ''}, got {len(values)} "
                                      f"({value.strip()[:80]!r})")
    if not all(math.isfinite(v) for v in values):
        raise CasprError(path, where, f"expected finite numbers, got {value.strip()[:80]!r}")
    return values


def number(path, value, where: str) -> float:
    return numbers(path, value, where, 1)[0]


def integer(path, value, where: str) -> int:
    x = number(path, value, where)
    if x != int(x):
        raise CasprError(path, where, f"expected an integer, got {value.strip()!r}")
    return int(x)


def ident(name: str, num: int, taken: set[str]) -> str:
    """A URDF-safe, unique identifier for a CASPR name (letters, digits and '_')."""
    out = re.sub(r"[^A-Za-z0-9_]+", "_", name).strip("_") or f"link{num}"
    if out[0].isdigit():
        out = f"link_{out}"
    base, k = out, 2
    while out in taken:
        out = f"{base}_{num}" if k == 2 else f"{base}_{num}_{k}"
        k += 1
    taken.add(out)
    return out
