"""Fuzzing the sidecar and the CASPR importer (issue 7, item 3).

Every mutated input must either load (and then be usable: its trajectories built, its terms
evaluated, one instant solved) or raise one of the package's own exceptions (:class:`McdmError`)
whose message names the key (sidecar) or the element (CASPR): never a bare ``KeyError``,
``TypeError``, ``IndexError``, ``ValueError``, ``RecursionError``, a segfault or a hang (a 20 s
alarm per example).

Inputs tried per run (fixed seed, no example database; ``MCDM_HYPOTHESIS_SEED=<n>`` explores others):
:data:`N_SIDECAR_TREE` structural mutations of the 2-link sidecar, :data:`N_SIDECAR_TEXT` mutations
of its YAML text, :data:`N_CASPR` mutations of CASPR's SR_model XML (the committed fixtures in
``tests/data/caspr/SR_model``).
"""

from __future__ import annotations

import contextlib
import copy
import math
import os
import signal
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, note, seed, settings
from hypothesis import strategies as st

from mcdm_pin import McdmError, Robot
from mcdm_pin.exceptions import CasprError, SidecarError

from .conftest import TWO_LINK, TWO_LINK_URDF

N_SIDECAR_TREE = 400
N_SIDECAR_TEXT = 200
N_CASPR = 250
TIMEOUT_S = 20
SEED = int(os.environ.get("MCDM_HYPOTHESIS_SEED", "20141121"))
SETTINGS = dict(deadline=None, database=None, print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                       HealthCheck.large_base_example, HealthCheck.filter_too_much])
SR = Path(__file__).resolve().parent / "data" / "caspr" / "SR_model"  # committed fixtures (README there)

COUNTS: dict[str, dict[str, int]] = {"sidecar": {}, "text": {}, "caspr": {}}


@contextlib.contextmanager
def time_limit(seconds: int):
    def fail(signum, frame):
        raise TimeoutError(f"example took more than {seconds} s (a hang)")

    old = signal.signal(signal.SIGALRM, fail)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def exercise(robot) -> None:
    """Use a loaded robot: every trajectory, the terms at q = 0, one instant solved."""
    from mcdm_pin import InverseDynamics, compute_terms, load_trajectory

    for name in robot.sidecar.trajectories:
        traj = load_trajectory(robot, name)
        assert np.all(np.isfinite(traj.q))
    compute_terms(robot, np.zeros(robot.nv))
    InverseDynamics.for_case(robot, 1).solve(np.zeros(robot.nv))


def outcome(kind: str, load) -> None:
    """Run ``load()``; it may succeed or raise McdmError naming the key; count what happened."""
    with time_limit(TIMEOUT_S):
        try:
            exercise(load())
            result = "loaded"
        except McdmError as exc:
            msg = str(exc)
            assert msg.strip(), f"empty message from {type(exc).__name__}"
            if isinstance(exc, SidecarError):
                assert exc.key or any(s in msg for s in ("malformed YAML", "cannot read", "file not found", "not UTF-8", "not a sidecar",
                                                     "expected a mapping with keys")), msg
            if isinstance(exc, CasprError):
                assert exc.element or "cannot" in msg or "malformed" in msg, msg
            result = type(exc).__name__
    COUNTS[kind][result] = COUNTS[kind].get(result, 0) + 1


# ----------------------------------------------------------------------------- sidecar: structure
def base_document() -> dict:
    data = yaml.safe_load(TWO_LINK.read_text())
    data["urdf"] = str(TWO_LINK_URDF)
    return data


def paths(node, prefix=()):
    """Every (path) to a container or leaf of the document."""
    yield prefix
    if len(prefix) > 12:  # do not descend into the deeply nested values we planted
        return
    if isinstance(node, dict):
        for k, v in node.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from paths(v, prefix + (i,))


def nested(depth: int, leaf=0.0):
    out = leaf
    for _ in range(depth):
        out = [out]
    return out


weird = st.one_of(
    st.none(), st.booleans(), st.integers(-(2**70), 2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([1e308, -1e308, 5e-324, 1e-300, 0.0, -0.0, 1e30, "1e400", "nan", ".inf", "1e3", "-", "",
                     "  ", "0x10", "1_000"]),
    st.text(max_size=12),
    st.text(alphabet="αβγ名前🙂\u200b\u202e\x00\t\n ", min_size=1, max_size=6),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=5),
    st.lists(st.integers(-3, 3), min_size=3, max_size=3),
    st.dictionaries(st.text(max_size=5), st.integers(), max_size=3),
    st.integers(1, 60).map(nested),
    st.just(nested(3000)),
)

OPS = ("replace", "delete", "unknown_key", "duplicate", "wrap_list", "wrap_dict", "swap_names", "unicode_key")


@st.composite
def mutated_documents(draw):
    doc = base_document()
    for _ in range(draw(st.integers(1, 3))):
        all_paths = list(paths(doc))
        path = draw(st.sampled_from(all_paths[1:]))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        key = path[-1]
        op = draw(st.sampled_from(OPS))
        if op == "replace":
            parent[key] = draw(weird)
        elif op == "delete":
            del parent[key]
        elif op == "unknown_key" and isinstance(parent[key], dict):
            parent[key][draw(st.text(min_size=1, max_size=8))] = draw(weird)
        elif op == "duplicate" and isinstance(parent, list):
            parent.insert(key, copy.deepcopy(parent[key]))  # e.g. a duplicate cable (same name)
        elif op == "wrap_list":
            parent[key] = [parent[key]]
        elif op == "wrap_dict":
            parent[key] = {"value": parent[key]}
        elif op == "swap_names" and isinstance(parent, dict) and len(parent) >= 2:
            # reorder / alias names: a joint claiming another's URDF joints, a cycle of links...
            other = draw(st.sampled_from([k for k in parent if k != key]))
            parent[key], parent[other] = copy.deepcopy(parent[other]), copy.deepcopy(parent[key])
        elif op == "unicode_key" and isinstance(parent, dict):
            parent[draw(st.text(alphabet="αβ名🙂\u202e", min_size=1, max_size=4))] = parent.pop(key)
    return doc


@seed(SEED)
@settings(max_examples=N_SIDECAR_TREE, **SETTINGS)
@given(mutated_documents())
def test_mutated_sidecar_loads_or_raises_mcdm_error(doc):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "robot.yaml"
        try:
            text = yaml.safe_dump(doc, allow_unicode=True, sort_keys=False)
        except RecursionError:
            text = "joints: " + "[" * 3000 + "]" * 3000
        path.write_text(text, encoding="utf-8")
        note(text[:3000])
        outcome("sidecar", lambda: Robot.load(path))


# ---------------------------------------------------------------------------------- sidecar: text
TEXT_ATTACKS = [
    "a: &x [*x]\n",  # a recursive alias (a cycle)
    "joints: &j {shoulder: *j}\n",
    "[" * 5000 + "]" * 5000,  # deep nesting
    "{a: " * 3000 + "1" + "}" * 3000,
    "version: 1\nversion: 2\n",  # duplicate keys
    "\ufeffversion: 1\n",
    "!!python/object/apply:os.system ['true']\n",
    "version: !!binary AAAA\n",
    "a: b: c\n",
    "\t- x\n",
    "x" * 100_000,
]


@st.composite
def mutated_texts(draw):
    text = TWO_LINK.read_text().replace("../urdf/two_link_sr.urdf", str(TWO_LINK_URDF))
    kind = draw(st.sampled_from(("flip", "truncate", "insert", "delete_line", "attack", "anchor")))
    if kind == "flip":
        for _ in range(draw(st.integers(1, 5))):
            i = draw(st.integers(0, len(text) - 1))
            text = text[:i] + draw(st.sampled_from(list(":-[]{}&*!|>'\"#%@`,?\t\n 0123456789.eE+") +
                                                   ["\x00", "\x85", "\u2028", "é"])) + text[i + 1:]
    elif kind == "truncate":
        text = text[:draw(st.integers(0, len(text)))]
    elif kind == "insert":
        i = draw(st.integers(0, len(text)))
        text = text[:i] + draw(st.text(max_size=20)) + text[i:]
    elif kind == "delete_line":
        lines = text.splitlines(keepends=True)
        del lines[draw(st.integers(0, len(lines) - 1))]
        text = "".join(lines)
    elif kind == "attack":
        text = draw(st.sampled_from(TEXT_ATTACKS))
    else:  # anchors and aliases: the same cable twice, a route that refers to itself
        text = text.replace("  - name: cable1\n", "  - &c1\n    name: cable1\n", 1)
        text += draw(st.sampled_from(["  - *c1\n", "  - {name: x, f_min: 0, f_max: 1, route: *c1}\n",
                                      "trajectories: {t: &t {type: quintic, q_start: *t}}\n"]))
    return text


@seed(SEED)
@settings(max_examples=N_SIDECAR_TEXT, **SETTINGS)
@given(mutated_texts())
def test_mutated_sidecar_text_loads_or_raises_mcdm_error(text):
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "robot.yaml"
        path.write_bytes(text.encode("utf-8", errors="surrogatepass"))
        note(repr(text[:2000]))
        outcome("text", lambda: Robot.load(path))


def test_invalid_utf8_sidecar(tmp_path):
    path = tmp_path / "robot.yaml"
    path.write_bytes(b"version: 1\nname: \xff\xfe\n")
    with pytest.raises(SidecarError, match="not UTF-8 text"):
        Robot.load(path)


# ----------------------------------------------------------------------------------------- CASPR
XML_VALUES = st.one_of(
    st.sampled_from(["", " ", "nan", "inf", "-inf", "1e400", "1e-400", "-1", "0", "1e308", "abc", "1 2",
                     "1 2 3 4", "0 0 0", "99", "-5", "2.5", "S_EULER_XYZ", "R_X", "U_XY", "SPHERICAL",
                     "com", "joint", "none", "名前🙂", "\u202e", "1,2,3"]),
    st.text(max_size=10).filter(lambda s: all(c.isprintable() for c in s)),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)
XML_OPS = ("text", "attr", "del_elem", "del_attr", "dup_elem", "parent_cycle", "deep", "rename_tag")


@st.composite
def mutated_caspr(draw):
    trees = {name: ET.parse(SR / f"SR_model_{name}.xml") for name in ("bodies", "cables")}
    for _ in range(draw(st.integers(1, 3))):
        which = draw(st.sampled_from(("bodies", "cables")))
        root = trees[which].getroot()
        elems = list(root.iter())
        parents = {c: p for p in root.iter() for c in p}
        el = draw(st.sampled_from(elems))
        op = draw(st.sampled_from(XML_OPS))
        if op == "text":
            el.text = draw(XML_VALUES)
        elif op == "attr":
            keys = list(el.attrib) + ["num", "type", "name", "ref", "attachment_reference", "default_cable_set"]
            el.set(draw(st.sampled_from(keys)), draw(XML_VALUES))
        elif op == "del_elem" and el in parents:
            parents[el].remove(el)
        elif op == "del_attr" and el.attrib:
            del el.attrib[draw(st.sampled_from(sorted(el.attrib)))]
        elif op == "dup_elem" and el in parents:
            parents[el].append(copy.deepcopy(el))  # duplicate link numbers / cable names
        elif op == "parent_cycle":
            nums = root.findall(".//parent/num")
            if nums:
                for n in nums:  # every link its own parent's child: 1 -> 2 -> 1
                    n.text = str(len(nums) - int(n.text) if n.text and n.text.strip().isdigit() else 1)
        elif op == "deep":
            inner = el
            for _ in range(draw(st.integers(1, 200))):
                child = ET.SubElement(inner, "x")
                inner = child
        elif op == "rename_tag" and el is not root:
            el.tag = draw(st.sampled_from(["link_rigid", "cable_ideal", "joint", "parent", "attachment", "bogus"]))
    return {k: ET.tostring(t.getroot(), encoding="unicode") for k, t in trees.items()}


@seed(SEED)
@settings(max_examples=N_CASPR, **SETTINGS)
@given(mutated_caspr())
def test_mutated_caspr_xml_imports_or_raises_mcdm_error(files):
    from mcdm_pin.caspr import import_caspr

    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        for k, text in files.items():
            (d / f"m_{k}.xml").write_text(text, encoding="utf-8")
            note(f"{k}:\n{text[:4000]}")

        def load():
            res = import_caspr(d / "m_bodies.xml", d / "m_cables.xml", d / "out", name="m")
            return Robot.load(res.sidecar)

        outcome("caspr", load)


@pytest.mark.parametrize("text", ["", "<bodies_system>", "<?xml version='1.0'?><!DOCTYPE x [<!ENTITY a "
                                  "'aaaaaaaaaa'><!ENTITY b '&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;'>]><x>&b;</x>",
                                  "\x00\x01", "<bodies_system>" + "<x>" * 5000 + "</x>" * 5000 + "</bodies_system>"])
def test_broken_caspr_xml_raises_caspr_error(tmp_path, text):
    from mcdm_pin.caspr import import_caspr

    bodies = tmp_path / "b_bodies.xml"
    bodies.write_text(text, encoding="utf-8")
    with time_limit(TIMEOUT_S), pytest.raises(McdmError):
        import_caspr(bodies, SR / "SR_model_cables.xml", tmp_path / "out")


def test_fuzz_counts_are_reported():
    """Both outcomes occur (the mutations reach past the first check) - counts from this run."""
    if not any(COUNTS.values()):  # run alone: run the fuzzers here (they fill COUNTS)
        test_mutated_sidecar_loads_or_raises_mcdm_error()
        test_mutated_sidecar_text_loads_or_raises_mcdm_error()
        test_mutated_caspr_xml_imports_or_raises_mcdm_error()
    ran = {k: v for k, v in COUNTS.items() if v}
    print(ran)
    for kind, counts in ran.items():
        total = sum(counts.values())
        assert total >= 50, (kind, counts)
        assert counts.get("loaded", 0) >= 5 and total - counts.get("loaded", 0) >= 5, (kind, counts)


def test_numbers_in_messages_are_finite_checks():
    """A sidecar number that overflows to inf when parsed from text is rejected by name."""
    doc = base_document()
    doc["gravity"] = ["1e400", 0.0, -9.81]
    from mcdm_pin.sidecar import parse_sidecar

    with pytest.raises(SidecarError, match=r"gravity\[0\]") as info:
        parse_sidecar(doc, path=None, base_dir=TWO_LINK.parent)
    assert "finite" in str(info.value)
