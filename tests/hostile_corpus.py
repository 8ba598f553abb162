"""A corpus of hostile inputs of our own making, for every input the project reads.

Run ``python -m tests.hostile_corpus`` to list it by class (the CASPR XML class is in
``tests/hostile_caspr.py``); ``tests/test_hostile.py`` runs every case
through the command line in a forked child under a time and a memory bound and asserts: exit status 2,
exactly one line on stderr that names the file and the field, no traceback, and no file created or
changed. Each case is a small function of the valid 2-link files, so a failure prints a reproducible
input.
"""

from __future__ import annotations

import io
import re
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
URDF = (REPO / "urdf" / "two_link_sr.urdf").read_text()
SIDECAR = (REPO / "robots" / "two_link_sr.yaml").read_text().replace("../urdf/two_link_sr.urdf", "arm.urdf")
SIDECAR += """  wave:
    type: csv
    file: wave.csv
"""


def _csv_rows(n: int = 12) -> str:
    return "t,q1_x,q2_y,q3_z,q4_x\n" + "".join(f"{k * 0.05:.2f},{0.1 * k / n:.4f},0,0,{-0.05 * k / n:.4f}\n"
                                               for k in range(n))


CSV = _csv_rows()


@dataclass(frozen=True)
class Sparse:
    """A file of ``size`` bytes that starts with ``head`` (the rest zeros), written sparse: a size limit
    is tested without holding the bytes in memory."""

    head: bytes
    size: int


@dataclass
class Case:
    """One hostile input: files written into an empty folder, the command line run there, and what the
    one-line error must name (``file``: a file name, ``field``: a regular expression)."""

    klass: str
    name: str
    files: dict[str, bytes | str | Sparse]
    argv: list[str]
    field: str
    file: str | None = None
    reason: str = ""
    extra: dict = field(default_factory=dict)


def _base(**over) -> dict[str, bytes | str]:
    files = {"arm.urdf": URDF, "robot.yaml": SIDECAR, "wave.csv": CSV}
    files.update(over)
    return files


def _sub(text: str, old: str, new: str, count: int = 1) -> str:
    if old not in text:
        raise AssertionError(f"corpus: {old!r} not in the base text")
    return text.replace(old, new, count)


INFO = ["info", "robot.yaml"]


def sidecar_cases() -> list[Case]:
    cases = []

    def add(name, text, field, argv=INFO, **kw):
        cases.append(Case("sidecar", name, _base(**{"robot.yaml": text}), list(argv), field, "robot.yaml", **kw))

    s = SIDECAR
    add("empty file", "", r"expected a mapping")
    add("not a mapping", "- 1\n- 2\n", r"expected a mapping")
    add("binary", b"\x89PNG\r\n\x1a\n\x00\x00", r"robot\.yaml is a binary file, not a cable sidecar")
    add("tab indentation", s.replace("  shoulder:", "\tshoulder:", 1), r"malformed YAML at line")
    add("unclosed bracket", _sub(s, "[0.0, 0.0, -9.81]", "[0.0, 0.0, -9.81"), r"malformed YAML at line")
    add("duplicate key f_max", _sub(s, "    f_max: 1000.0\n", "    f_max: 1000.0\n    f_max: 0.5\n"),
        r"duplicate key 'f_max' at line \d+ \(first at line \d+\)")
    add("duplicate cables block", s + "\n" + s[s.index("cables:"):s.index("trajectories:")],
        r"duplicate key 'cables'")
    add("duplicate joint", _sub(s, "  elbow:", "  shoulder:"), r"duplicate key 'shoulder'")
    add("sexagesimal number", _sub(s, "f_max: 1000.0", "f_max: 1:30"), r"cables\[0\]\.f_max: expected a number, got the string '1:30'")
    add("yes as number", _sub(s, "f_min: 0.001", "f_min: yes"), r"cables\[0\]\.f_min: expected a number, got the string 'yes'")
    add("400 digits", _sub(s, "f_max: 1000.0", "f_max: " + "9" * 400), r"cables\[0\]\.f_max: expected a number of magnitude at most")
    add("alias bomb", "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n" for p, c in zip("abcdefgh", "bcdefghi")),
        r"expands to more than \d+ nodes through its aliases")
    add("recursive alias", "version: &a [*a]\n", r"malformed YAML at line 1: a recursive alias")
    add("python tag", "!!python/object/apply:os.system ['echo hacked']\n", r"malformed YAML")
    add("unknown top key", "colour: red\n" + s, r"colour: unknown key 'colour'")
    add("missing version", s.replace("version: 1\n", ""), r"version: missing required key")
    add("version 2", _sub(s, "version: 1", "version: 2"), r"version: expected one of \[1\]")
    add("version true", _sub(s, "version: 1", "version: true"), r"version: expected one of \[1\]")
    add("missing urdf", _sub(s, "urdf: arm.urdf\n", ""), r"urdf: missing required key")
    add("urdf not found", _sub(s, "urdf: arm.urdf", "urdf: nothere.urdf"), r"urdf: URDF file not found")
    add("urdf is a number", _sub(s, "urdf: arm.urdf", "urdf: 5"), r"urdf: expected a non-empty string")
    add("package escape", _sub(s, "urdf: arm.urdf", "urdf: package://example-robot-data/../../../etc/passwd"),
        r"urdf: .* leaves the package")
    add("package unknown", _sub(s, "urdf: arm.urdf", "urdf: package://no_such_pkg/robot.urdf"),
        r"urdf: cannot resolve 'package://no_such_pkg/robot.urdf'")
    add("gravity 2 numbers", _sub(s, "gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, -9.81]"), r"gravity: expected a list of 3 numbers")
    add("gravity nan", _sub(s, "gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, 0.0, .nan]"), r"gravity\[2\]: expected a finite number")
    add("gravity inf", _sub(s, "gravity: [0.0, 0.0, -9.81]", "gravity: [0.0, 0.0, -.inf]"), r"gravity\[2\]: expected a finite number")
    add("joints empty", _sub(s, s[s.index("joints:"):s.index("cables:")], "joints: {}\n"), r"joints: expected a non-empty mapping")
    add("joint type wrong", _sub(s, "type: revolute", "type: hinge"), r"joints\.elbow\.type: expected one of")
    add("spherical two joints", _sub(s, "urdf_joints: [q1_x, q2_y, q3_z]", "urdf_joints: [q1_x, q2_y]"),
        r"joints\.shoulder\.urdf_joints: a spherical joint needs a list of 1 or 3")
    add("unknown urdf joint", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q9_x]"), r"joints\.elbow\.urdf_joints\[0\]: unknown URDF joint 'q9_x'")
    add("urdf joint used twice", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q3_z]"),
        r"joints\.elbow\.urdf_joints\[0\]: URDF joint 'q3_z' is already used")
    add("joint missing", _sub(s, s[s.index("  elbow:"):s.index("cables:")], ""), r"joints: URDF joint\(s\) 'q4_x' are movable but belong to no physical joint")
    add("socket axis not unit", _sub(s, "socket_axis: [0.0, 0.0, 1.0]", "socket_axis: [0.0, 0.0, 2.0]"),
        r"joints\.shoulder\.socket_axis: expected a unit vector")
    add("alpha negative", _sub(s, "alpha: 1.0", "alpha: -1.0"), r"joints\.shoulder\.alpha: expected a number >= 0")
    add("beta string", _sub(s, "beta: 0.0", "beta: big"), r"joints\.shoulder\.beta: expected a number, got the string 'big'")
    add("cone 90", _sub(s, "cone_deg: 30.0", "cone_deg: 90"), r"joints\.shoulder\.cone_deg: expected a number < 90")
    add("cone 0", _sub(s, "cone_deg: 30.0", "cone_deg: 0"), r"joints\.shoulder\.cone_deg: expected a number > 0")
    add("cone on revolute", _sub(s, "    alpha: 0.0\n    beta: 0.0\ncables", "    alpha: 0.0\n    beta: 0.0\n    cone_deg: 20\ncables"),
        r"joints\.elbow\.cone_deg: a stability cone is defined for spherical joints only")
    add("parametrization on revolute", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q4_x]\n    parametrization: quaternion"),
        r"joints\.elbow\.parametrization: a parametrization is chosen for spherical joints only")
    add("quaternion on a triple", _sub(s, "urdf_joints: [q1_x, q2_y, q3_z]", "urdf_joints: [q1_x, q2_y, q3_z]\n    parametrization: quaternion"),
        r"joints\.shoulder\.parametrization: expected one of 'euler-xyz'")
    add("spherical from one revolute", _sub(s, "urdf_joints: [q1_x, q2_y, q3_z]", "urdf_joints: [q1_x]"),
        r"joints\.shoulder\.urdf_joints: a spherical joint needs 3 revolute URDF joints .* or 1 URDF 'floating' joint")
    add("actuated wrong count", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q4_x]\n    actuated: {min: [-1, -1], max: [1, 1]}"),
        r"joints\.elbow\.actuated\.min: expected 1 bound")
    add("actuated max below min", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q4_x]\n    actuated: {min: [1], max: [-1]}"),
        r"joints\.elbow\.actuated\.max\[0\]: expected max > min")
    add("actuated unknown key", _sub(s, "urdf_joints: [q4_x]", "urdf_joints: [q4_x]\n    actuated: {min: [1], max: [2], gain: 3}"),
        r"joints\.elbow\.actuated\.gain: unknown key")
    add("locked unknown", _sub(s, "joints:\n", "locked_joints: {nope: 0.1}\njoints:\n"), r"locked_joints\.nope: unknown URDF joint 'nope'")
    add("locked and used", _sub(s, "joints:\n", "locked_joints: {q4_x: 0.1}\njoints:\n"),
        r"joints\.elbow\.urdf_joints\[0\]: URDF joint 'q4_x' is also listed in locked_joints")
    add("cables not a list", _sub(s, s[s.index("cables:"):s.index("trajectories:")], "cables: {a: 1}\n"), r"cables: expected a non-empty list of cables")
    add("cable name duplicate", _sub(s, "name: cable2", "name: cable1"), r"cables\[1\]\.name: cable name 'cable1' is already used by cables\[0\]")
    add("cable name missing", _sub(s, "  - name: cable2\n", "  - \n"), r"cables\[1\]: missing required key 'name'|cables\[1\]")
    add("f_min negative", _sub(s, "f_min: 0.001", "f_min: -1"), r"cables\[0\]\.f_min: expected a number >= 0")
    add("f_max below f_min", _sub(s, "f_max: 1000.0", "f_max: 0.0001"), r"cables\[0\]\.f_max: expected f_max > f_min")
    add("route one point", _sub(s, "      - {link: link1, point: [0.05, 0.0, 0.1]}\n", ""), r"cables\[0\]\.route: expected a list of at least two")
    add("route unknown link", _sub(s, "{link: link1, point: [0.05, 0.0, 0.1]}", "{link: link9, point: [0.05, 0.0, 0.1]}"),
        r"cables\[0\]\.route\[1\]\.link: unknown link 'link9'")
    add("route massless link", _sub(s, "{link: link1, point: [0.05, 0.0, 0.1]}", "{link: link1_ry, point: [0.05, 0.0, 0.1]}"),
        r"cables\[0\]\.route\[1\]\.link: link 'link1_ry' is an intermediate massless link")
    add("route point 2 numbers", _sub(s, "point: [0.05, 0.0, 0.1]", "point: [0.05, 0.0]"), r"cables\[0\]\.route\[1\]\.point: expected a list of 3 numbers")
    add("route same body", _sub(s, "{link: link1, point: [0.05, 0.0, 0.1]}", "{link: base, point: [0.05, 0.0, 0.1]}"),
        r"cables\[0\]\.route: .*no segment spanning two different bodies")
    add("route point unknown key", _sub(s, "{link: link1, point: [0.05, 0.0, 0.1]}", "{link: link1, point: [0.05, 0.0, 0.1], via: 1}"),
        r"cables\[0\]\.route\[1\]\.via: unknown key")
    add("trajectory unknown type", _sub(s, "    type: quintic\n", "    type: spline\n"), r"trajectories\.traj1\.type: expected one of")
    add("dt > duration", _sub(s, "    dt: 0.01\n", "    dt: 2.0\n"), r"trajectories\.traj1\.dt: expected dt <= duration")
    add("1e7 samples", _sub(s, "    dt: 0.01\n", "    dt: 1e-9\n"), r"trajectories\.traj1\.dt: expected at most \d+ samples")
    add("duration negative", _sub(s, "    duration: 1.0\n", "    duration: -1.0\n"), r"trajectories\.traj1\.duration: expected a number > 0")
    add("q_start wrong length", _sub(s, "q_start: [0.2, -0.2, -0.1, 0.2]", "q_start: [0.2, -0.2, -0.1]"),
        r"trajectories\.traj2\.q_start: expected 4 values", argv=["solve", "robot.yaml", "-t", "traj2"])
    add("q_end unknown joint", _sub(s, "q_end: [-0.5, 0.5, 0.2, -0.2]", "q_end: {wrist: 0.1}"),
        r"trajectories\.traj2\.q_end\.wrist: unknown joint 'wrist'", argv=["solve", "robot.yaml", "-t", "traj2"])
    add("csv missing file key", _sub(s, "    file: wave.csv\n", ""), r"trajectories\.wave\.file: missing required key 'file'")
    return cases


def urdf_cases() -> list[Case]:
    cases = []

    def add(name, text, field):
        cases.append(Case("urdf", name, _base(**{"arm.urdf": text}), list(INFO), field, "arm.urdf"))

    def add_group(name, text, field):  # the URDF breaks what the sidecar says of its joints
        cases.append(Case("urdf", name, _base(**{"arm.urdf": text}), list(INFO), field, "robot.yaml",
                          extra={"also": "arm.urdf"}))

    u = URDF
    add("empty", "", r"malformed XML|cannot load")
    add("not xml", "robot: yes\n", r"malformed XML")
    add("root not robot", u.replace("<robot name", "<robo name").replace("</robot>", "</robo>"), r"not <robot>")
    add("mass abc", _sub(u, '<mass value="0.1"/>', '<mass value="abc"/>'), r"mass \[abc\] is not a float")
    add("mass negative", _sub(u, '<mass value="0.1"/>', '<mass value="-0.1"/>'), r"mass|[Mm]ass")
    add("inertia negative", _sub(u, 'ixx="1"', 'ixx="-1"'), r"principal moments")
    add("inertia indefinite", _sub(u, 'ixx="1" ixy="0"', 'ixx="1" ixy="5"'), r"principal moments")
    add("inertia nan", _sub(u, 'ixx="1"', 'ixx="nan"'), r"inertia|nan")
    add("mass 1e308", _sub(u, '<mass value="0.1"/>', '<mass value="1e308"/>'), r"mass of .* magnitude at most")
    add("zero axis", _sub(u, '<axis xyz="0 1 0"/>', '<axis xyz="0 0 0"/>'), r"joint 'q2_y': <axis xyz> is zero")
    add("axis text", _sub(u, '<axis xyz="0 1 0"/>', '<axis xyz="0 one 0"/>'), r"q2_y|axis")
    add("mimic", _sub(u, '<joint name="q4_x" type="revolute">', '<joint name="q4_x" type="revolute"><mimic joint="q1_x"/>'),
        r"joint 'q4_x': <mimic> joints are not supported")
    add("two roots", _sub(u, '<link name="link1_rx"/>', '<link name="link1_rx"/><link name="stray"/>'), r"root link|[Rr]oot")
    add("unknown parent", _sub(u, '<parent link="link1"/><child link="link2"/>', '<parent link="linkX"/><child link="link2"/>'),
        r"linkX|parent")
    add("joint type ball", _sub(u, '<joint name="q4_x" type="revolute">', '<joint name="q4_x" type="spherical">'), r"spherical|type")
    add_group("offset inside triple", _sub(u, '<parent link="link1_rx"/><child link="link1_ry"/>\n    <origin xyz="0 0 0"',
                                     '<parent link="link1_rx"/><child link="link1_ry"/>\n    <origin xyz="0 0 0.1"'),
        r"joints\.shoulder\.urdf_joints: .*must meet at one point")
    add_group("mass inside triple", _sub(u, '<link name="link1_ry"/>', '<link name="link1_ry"><inertial><mass value="1"/>'
                                   '<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>'),
        r"joints\.shoulder\.urdf_joints: .*must be massless")
    add_group("axes not orthogonal", _sub(u, '<axis xyz="0 1 0"/>', '<axis xyz="1 1 0"/>'), r"joints\.shoulder\.urdf_joints: .*must be orthogonal")
    add("binary", b"\x00\x01\x02\xff" * 10, r"malformed XML|cannot")
    add("entity expansion", '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
        '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]><robot name="&d;"/>',
        r"URDF|XML|entit")
    return cases


def csv_cases() -> list[Case]:
    cases = []
    argv = ["solve", "robot.yaml", "-t", "wave", "-q"]

    def add(name, text, field):
        cases.append(Case("csv", name, _base(**{"wave.csv": text}), list(argv), field, "wave.csv"))

    rows = CSV.splitlines(keepends=True)
    data = "".join(rows[1:])
    add("empty", "", r"expected .* columns|at least 6 samples|no samples")
    add("header only", rows[0], r"at least 6 samples|columns")
    add("typo in first data row", "0.0,0.0,0,0,x\n" + "".join(rows[2:]), r"row 1, column 5: expected a number, got 'x'")
    add("typo later", rows[0] + "".join(rows[1:4]) + "0.15,0,0,zero,0\n" + "".join(rows[5:]), r"row 5, column 4: expected a number")
    add("byte order mark then data row typo", "\ufeff0.0,0,0,0,y\n" + "".join(rows[2:]), r"row 1, column 5")
    add("wrong column count", data.replace(",0,0,", ",0,", 1), r"row \d+: expected \d+ columns")
    add("too few columns", "".join(r.rsplit(",", 1)[0] + "\n" for r in rows[1:]), r"row 1: expected 5 columns")
    add("times not increasing", rows[0] + rows[1] + rows[3] + rows[2] + "".join(rows[4:]), r"times must increase strictly; row \d+")
    add("duplicate time", rows[0] + rows[1] + rows[1] + "".join(rows[2:]), r"times must increase strictly")
    add("nan", rows[0] + rows[1].replace(",0,0,", ",nan,0,") + "".join(rows[2:]), r"row \d+, column \d+: expected a finite number")
    add("inf", rows[0] + rows[1].replace(",0,0,", ",inf,0,") + "".join(rows[2:]), r"row \d+, column \d+: expected a finite number")
    add("five samples", "".join(rows[:6]), r"at least 6 samples")
    add("binary", b"\xff\xfe\x00\x00" * 20, r"not UTF-8")
    add("rate columns with wrong header", "t,a,b,c,d," + ",".join(f"qd:{n}" for n in "abcd") + "," + ",".join(f"qdd:{n}" for n in "abcd")
        + "\n" + "".join(f"{k * 0.1},0,0,0,0,0,0,0,0,0,0,0,0\n" for k in range(8)), r"row 1, column 2: header 'a'.*'q1_x'")
    add("semicolons", CSV.replace(",", ";"), r"row 1: one cell .* separated by ';'; expected commas")
    add("mixed header", "t,q1_x,2,q3_z,q4_x\n" + data, r"row 1, column 1: expected a number")
    return cases


def cli_cases() -> list[Case]:
    cases = []

    def add(name, argv, field, file=None, files=None):
        cases.append(Case("cli", name, files or _base(), list(argv), field, file))

    add("no such robot", ["info", "nope.yaml"], r"file not found", "nope.yaml")
    add("robot is a folder", ["info", "."], r"is a folder", ".")
    add("robot is the urdf", ["info", "arm.urdf"], r"arm\.urdf is a URDF; .* pass the sidecar instead", "arm.urdf")
    add("solve on the urdf", ["solve", "arm.urdf", "-t", "traj1"], r"arm\.urdf is a URDF; .* pass the sidecar instead", "arm.urdf")
    add("robot is the csv", ["info", "wave.csv"], r"wave\.csv is a CSV file, not a cable sidecar", "wave.csv")
    add("unknown command", ["fly"], r"invalid choice: 'fly'")
    add("solve without trajectory", ["solve", "robot.yaml"], r"the following arguments are required: --trajectory/-t")
    add("unknown trajectory", ["solve", "robot.yaml", "-t", "nope"], r"no trajectory 'nope'", "robot.yaml")
    add("case 4", ["solve", "robot.yaml", "-t", "traj1", "--case", "4"], r"--case: invalid choice")
    add("case text", ["solve", "robot.yaml", "-t", "traj1", "--case", "three"], r"--case: invalid")
    add("weights syntax", ["solve", "robot.yaml", "-t", "traj1", "--case", "2", "--weights", "shoulder"], r"--weights: expected NAME=VALUE")
    add("weights unknown joint", ["solve", "robot.yaml", "-t", "traj1", "--case", "2", "--weights", "knee=1"], r"--weights: unknown joint 'knee'")
    add("weights negative", ["solve", "robot.yaml", "-t", "traj1", "--case", "2", "--weights", "shoulder=-1"], r"--weights shoulder: weights must be >= 0")
    add("weights nan", ["solve", "robot.yaml", "-t", "traj1", "--case", "2", "--weights", "shoulder=nan"], r"--weights shoulder: expected a finite number")
    add("cone 95", ["solve", "robot.yaml", "-t", "traj1", "--case", "3", "--cone", "shoulder=95"], r"--cone shoulder: expected an angle in \(0, 90\)")
    add("cone on elbow", ["solve", "robot.yaml", "-t", "traj1", "--case", "3", "--cone", "elbow=20"], r"--cone elbow: cones apply to spherical joints only")
    add("cone with case 1", ["solve", "robot.yaml", "-t", "traj1", "--cone", "shoulder=20"], r"--cone applies to --case 3 only")
    add("samples 0", ["solve", "robot.yaml", "-t", "traj1", "--samples", "0"], r"--samples: expected a positive number")
    add("samples text", ["solve", "robot.yaml", "-t", "traj1", "--samples", "ten"], r"--samples: invalid int value")
    add("smoothing negative", ["solve", "robot.yaml", "-t", "traj1", "--smoothing", "-1"], r"--smoothing: expected a weight >= 0")
    add("workers 0", ["solve", "robot.yaml", "-t", "traj1", "--workers", "0"], r"--workers: expected a positive number")
    add("solver unknown", ["solve", "robot.yaml", "-t", "traj1", "--solver", "gurobi"], r"unknown solver 'gurobi'")
    add("out suffix", ["solve", "robot.yaml", "-t", "traj1", "--out", "run.txt"], r"--out: expected a \.npz or \.csv file name")
    add("out missing folder", ["solve", "robot.yaml", "-t", "traj1", "--out", "nofolder/run.npz"], r"--out .*nofolder.*(does not exist|no such folder)", "nofolder")
    add("out is the input csv", ["solve", "robot.yaml", "-t", "wave", "--out", "wave.csv"], r"--out .*wave\.csv.* input", "wave.csv")
    add("out is the sidecar", ["solve", "robot.yaml", "-t", "traj1", "--out", "robot.yaml"], r"--out: expected a \.npz or \.csv")
    add("two outs same file", ["solve", "robot.yaml", "-t", "traj1", "--out", "a.npz", "--out", "a.npz"], r"--out .*a\.npz.* twice", "a.npz")
    add("out is a folder", ["solve", "robot.yaml", "-t", "traj1", "--out", "dir.npz"], r"--out .*dir\.npz.*folder", "dir.npz",
        files=_base(**{"dir.npz/keep": "x"}))
    add("html suffix", ["solve", "robot.yaml", "-t", "traj1", "--html", "view.png"], r"--html: expected a file name ending in \.html")
    add("plot no results", ["plot", "none.npz", "--out", "figs"], r"file not found", "none.npz")
    add("plot bad figure", ["plot", "wave.csv", "--out", "figs", "--figures", "pie"], r"--figures: unknown figure 'pie'")
    add("view bad size", ["view", "robot.yaml", "--results", "wave.csv", "--size", "big"], r"--size: expected WIDTHxHEIGHT")
    add("verify swapped text file", ["verify", "wave.csv", "robot.yaml"], r"wave\.csv|results", "wave.csv")
    return cases


def command_cases() -> list[Case]:
    """The commands beyond solve: workspace and export-opensim."""
    cases = []
    ws = ["workspace", "robot.yaml", "--out", "ws.zarr", "--no-margins", "--scheduler", "inline", "-q"]

    def add(name, argv, field, file=None, files=None):
        cases.append(Case("commands", name, files or _base(), list(argv), field, file))

    add("workspace grid syntax", ws + ["--grid", "q1_x=0:1"], r"--grid")
    add("workspace unknown coordinate", ws + ["--grid", "wrist=0:1:3"], r"grid: unknown coordinate 'wrist'")
    add("workspace grid of 0", ws + ["--grid", "q1_x=0:1:0"], r"grid q1_x: expected a positive whole number")
    add("workspace grid nan", ws + ["--grid", "q1_x=nan:1:3"], r"--grid")
    add("workspace random 0", ws + ["--random", "0"], r"random: expected a positive number of poses")
    add("workspace random huge", ws + ["--random", "100000000000"], r"random: expected at most \d+ poses")
    add("workspace grid huge", ws + ["--grid", "q1_x=0:1:100000", "--grid", "q4_x=0:1:100000"], r"grid q4_x: the grid would have")
    add("workspace poses missing", ws + ["--poses", "nope.csv"], r"nope\.csv", "nope.csv")
    add("workspace poses bad header", ws + ["--poses", "wave.csv"], r"wave\.csv", "wave.csv")
    add("workspace chunk 0", ws + ["--random", "5", "--chunk", "0"], r"--chunk")
    add("workspace workers 0", ws + ["--random", "5", "--workers", "0"], r"--workers")
    add("workspace scheduler url", ["workspace", "robot.yaml", "--out", "ws.zarr", "--random", "5", "--scheduler", "udp:/x"],
        r"scheduler: expected local, inline or tcp://HOST:PORT")
    add("workspace out not zarr", ["workspace", "robot.yaml", "--out", "ws.txt", "--random", "5"], r"--out")
    add("workspace out missing folder", ["workspace", "robot.yaml", "--out", "no/ws.zarr", "--random", "5"], r"--out")
    add("workspace cone on case 1", ws + ["--random", "5", "--cone", "shoulder=20"], r"--cone")
    add("workspace at unknown", ws + ["--grid", "q1_x=0:1:3", "--at", "knee=1"], r"at: unknown coordinate 'knee'")
    add("export suffix", ["export-opensim", "robot.yaml", "arm.txt"], r"\.osim")
    add("export missing folder", ["export-opensim", "robot.yaml", "no/arm.osim"], r"OUT no/arm\.osim: the folder no does not exist")
    add("export the urdf", ["export-opensim", "arm.urdf", "arm.osim"], r"arm\.urdf is a URDF", "arm.urdf")
    add("export over the sidecar", ["export-opensim", "robot.yaml", "robot.yaml"], r"\.osim|robot\.yaml")
    add("export force negative", ["export-opensim", "robot.yaml", "arm.osim", "--optimal-force", "-1"], r"--optimal-force")
    return cases


def results_cases() -> list[Case]:
    import numpy as np

    cases = []

    def npz(**arrays) -> bytes:
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        return buf.getvalue()

    def add(name, content, field, argv=None):
        files = _base(**{"run.npz": content})
        cases.append(Case("results", name, files, argv or ["plot", "run.npz", "--out", "figs"], field, "run.npz"))

    add("not a zip", b"hello", r"not a results file")
    add("empty npz", npz(), r"not an mcdm-pin results file \(missing")
    add("missing f", npz(t=np.zeros(3)), r"missing .*f")
    add("pickled object", npz(t=np.array([object()], dtype=object)), r"cannot read the results|not an mcdm-pin results file")
    add("text file", "t,f\n1,2\n", r"not a results file")
    add("view with wrong robot", npz(t=np.zeros(3)), r"run\.npz", argv=["view", "robot.yaml", "--results", "run.npz", "--html", "v.html"])
    return cases


def all_cases() -> list[Case]:
    from .hostile_caspr import caspr_cases

    return (sidecar_cases() + urdf_cases() + csv_cases() + cli_cases() + command_cases() + results_cases()
            + caspr_cases())


if __name__ == "__main__":
    from collections import Counter

    counts = Counter(c.klass for c in all_cases())
    for k, n in counts.items():
        print(f"{k:10s} {n}")
    print(f"{'all':10s} {sum(counts.values())}")
    names = [f"{c.klass}: {c.name}" for c in all_cases()]
    assert len(set(names)) == len(names), "case names must be unique"
    for c in all_cases():
        re.compile(c.field)
