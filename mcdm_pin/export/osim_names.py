"""Names as OpenSim accepts them, and the written file read back.

**The mapping** (every name OpenSim sees: the model, bodies, joints, coordinates, cables and their
path points). A name keeps the characters ``A-Z a-z 0-9 _ - . ( ) [ ] #``; a letter with an accent
or another compatibility form becomes its ASCII letters (``ä`` -> ``a``, ``ﬁ`` -> ``fi``); every other
character (space, tab, newline, NUL and other control characters, ``\\ / * + : & < > " '``, non-Latin
letters) becomes ``_``. An empty name, or one of dots only, becomes ``_`` followed by it. Names are
unique within their kind (bodies, joints, coordinates, cables; ``ground`` is taken by the base): a name
already legal keeps its spelling, a rewritten one that meets a taken name gets ``#2``, ``#3``, ...
Why: OpenSim refuses whitespace and ``\\ / * +`` in a component's name (and can then crash), and it
writes other characters into the XML file unchecked (NUL as ``&#x00;``, which no XML reader reads).
"""

from __future__ import annotations

import string
import unicodedata
from xml.etree import ElementTree

from ..exceptions import ModelError

KEEP = frozenset(string.ascii_letters + string.digits + "_-.()[]#")


def _legal(name: str) -> str:
    out = []
    for ch in str(name):
        if ch in KEEP:
            out.append(ch)
            continue
        ascii_ = "".join(c for c in unicodedata.normalize("NFKD", ch) if c in KEEP and c not in "#")
        out.append(ascii_ or "_")
    text = "".join(out)
    return "_" + text if not text.strip(".") else text


def legal_names(names, taken=()) -> dict[str, str]:
    """``{name: its OpenSim name}`` for the distinct ``names`` of one kind (module docstring); ``taken``:
    names already used (e.g. ``ground``)."""
    names = list(dict.fromkeys(str(n) for n in names))
    used = set(taken)
    out = {}
    for n in names:  # legal names first: they keep their spelling
        if _legal(n) == n and n not in used:
            out[n] = n
            used.add(n)
    for n in names:
        if n in out:
            continue
        base = _legal(n)
        new, k = base, 2
        while new in used:
            new, k = f"{base}#{k}", k + 1
        out[n] = new
        used.add(new)
    return {n: out[n] for n in names}


def osim_name(name: str, taken: set) -> str:
    """One name made legal and unique among ``taken`` (updated)."""
    new = legal_names([name], taken)[str(name)]
    taken.add(new)
    return new


def check_written(path, expected: dict[str, list[str]], shown=None) -> None:
    """Read the written ``.osim`` back as XML and check that it holds exactly the ``expected`` names
    per set (``BodySet``, ``JointSet``, ``ForceSet``): a file an XML reader refuses, or one whose names
    differ from those meant, raises :class:`ModelError` naming the file (``shown``, default ``path``)."""
    where = path if shown is None else shown
    try:
        root = ElementTree.parse(str(path)).getroot()
    except (ElementTree.ParseError, OSError) as exc:
        raise ModelError(f"{where}: the written OpenSim file cannot be read back as XML ({exc})") from None
    model = root.find("Model")
    if model is None:
        raise ModelError(f"{where}: the written file has no <Model> element")
    for tag, names in expected.items():
        objects = model.find(f"{tag}/objects")
        found = [] if objects is None else [e.get("name") for e in objects]
        if found != list(names):
            raise ModelError(f"{where}: {tag} holds {found}, expected {list(names)}")
