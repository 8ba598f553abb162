"""The CASPR XML class of the hostile corpus (``tests/hostile_corpus.py``): the committed SR arm fixtures
(``tests/data/caspr/SR_model``), broken one way each, for ``mcdm-pin import-caspr``."""

from __future__ import annotations

import re

from mcdm_pin.limits import MAX_XML_BYTES

from .hostile_corpus import REPO, Case, Sparse, _sub

CASPR_DIR = REPO / "tests" / "data" / "caspr" / "SR_model"


def caspr_cases() -> list[Case]:
    """CASPR XML for ``import-caspr``: the committed SR arm fixtures, broken one way each. The output
    folder must not appear (the snapshot check: nothing created or changed)."""
    bodies = (CASPR_DIR / "SR_model_bodies.xml").read_text()
    cables = (CASPR_DIR / "SR_model_cables.xml").read_text()
    trajs = (CASPR_DIR / "SR_model_trajectories.xml").read_text()
    argv = ["import-caspr", "b.xml", "c.xml", "--trajectories", "t.xml", "--out", "out"]
    cases = []

    def add(name, field, file, b=bodies, c=cables, t=trajs, args=None):
        cases.append(Case("caspr", name, {"b.xml": b, "c.xml": c, "t.xml": t}, list(args or argv), field, file))

    joint = '<joint type="R_X" q_initial="0" q_min="-3.1416" q_max="3.1416"/>'
    add("unknown joint type", r"joint@type|R_W", "b.xml", b=_sub(bodies, 'type="R_X"', 'type="R_W"'))
    add("quaternion joint", r"S_QUATERNION", "b.xml", b=_sub(bodies, 'type="R_X"', 'type="S_QUATERNION"'))
    add("axis norm 1.01", r"axis", "b.xml",
        b=_sub(bodies, joint, '<joint type="R_AXIS" axis="1.01 0 0" q_initial="0" q_min="-3.1416" q_max="3.1416"/>'))
    add("axis zero", r"axis", "b.xml",
        b=_sub(bodies, joint, '<joint type="R_AXIS" axis="0 0 0" q_initial="0" q_min="-3.1416" q_max="3.1416"/>'))
    add("mass text", r"mass", "b.xml", b=_sub(bodies, "<mass>0.1</mass>", "<mass>heavy</mass>"))
    add("mass negative", r"mass", "b.xml", b=_sub(bodies, "<mass>0.1</mass>", "<mass>-0.1</mass>"))
    add("mass 1e400", r"mass", "b.xml", b=_sub(bodies, "<mass>0.1</mass>", "<mass>1e400</mass>"))
    add("com two numbers", r"com_location", "b.xml", b=_sub(bodies, "<com_location>0 0 0.1</com_location>",
                                                           "<com_location>0 0.1</com_location>"))
    add("parent missing link", r"parent|num", "b.xml", b=_sub(bodies, "<num>1</num>", "<num>7</num>"))
    add("q_initial too short", r"q_initial", "b.xml", b=_sub(bodies, 'q_initial="0 0 0"', 'q_initial="0 0"'))
    add("no links", r"link", "b.xml", b=re.sub(r"<link_rigid.*</link_rigid>", "", bodies, flags=re.S))
    add("not xml", r"b\.xml", "b.xml", b="this is not XML <")
    add("entity expansion", r"b\.xml", "b.xml",
        b='<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;'
          '&lol;&lol;&lol;&lol;">]><bodies_system>&lol2;</bodies_system>')
    add("external entity", r"b\.xml", "b.xml",
        b='<?xml version="1.0"?><!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]><bodies_system>&e;</bodies_system>')
    add("deep nesting", r"b\.xml", "b.xml", b="<a>" * 5000 + "</a>" * 5000)
    add("spring cable", r"cable_passive_linear_spring", "c.xml",
        c=_sub(cables, '<cable_ideal name="cable 1"', '<cable_passive_linear_spring name="cable 1"', 1).replace(
            "</cable_ideal>", "</cable_passive_linear_spring>", 1))
    add("pulley attachment", r"pulley", "c.xml", c=_sub(cables, "<attachments>", "<attachments><base_rotating_pulley/>", 1))
    add("unknown cable set", r"cable.set|nope", "c.xml", args=argv + ["--cable-set", "nope"])
    add("cable on missing link", r"link", "c.xml", c=re.sub(r"<link>1</link>", "<link>9</link>", cables, count=1))
    add("trajectory wrong count", r"SR_trajectory|q", "t.xml",
        t=_sub(trajs, "<q>0.523598776 0 0 -0.314159265</q>", "<q>0.523598776 0</q>"),
        args=argv + ["--trajectory", "SR_trajectory"])
    add("time step 1e-9", r"time_step|samples", "t.xml", t=_sub(trajs, 'time_step="0.01"', 'time_step="1e-9"'),
        args=argv + ["--trajectory", "SR_trajectory"])
    add("out is a file", r"--out|out", "out", args=argv[:-1] + ["c.xml"])
    _more_caspr_cases(add, bodies, cables, trajs, argv)
    return cases


def _more_caspr_cases(add, bodies, cables, trajs, argv):
    """Files that are not CASPR's at all, the bodies' numbering and physics, trajectory timing and the
    cables' numbers; a trajectory is asked for by name (``--trajectory``), else it is refused alone and
    the import goes on."""
    by_name = argv + ["--trajectory", "SR_trajectory"]
    laughs = "".join(f'<!ENTITY {chr(98 + i)} "{("&" + chr(97 + i) + ";") * 10}">' for i in range(8))
    add("billion laughs", r"malformed XML", "b.xml",
        b=f'<?xml version="1.0"?><!DOCTYPE l [<!ENTITY a "aaaaaaaaaa">{laughs}]><bodies_system>&i;</bodies_system>')
    add("huge file", r"bytes.*at most", "b.xml", b=Sparse(b"<bodies_system>", MAX_XML_BYTES + 1))
    add("empty file", r"malformed XML", "b.xml", b="")
    add("cables given as bodies", r"root element <bodies_system>", "b.xml", b=cables)
    add("link numbered twice", r"@num: expected num=2", "b.xml", b=_sub(bodies, 'num="2"', 'num="1"'))
    add("inertia not positive", r"inertia.*positive semidefinite", "b.xml", b=_sub(bodies, "<Ixy>0</Ixy>", "<Ixy>5</Ixy>"))
    add("q_min above q_max", r"joint@q_max", "b.xml",
        b=_sub(bodies, 'q_min="-3.1416" q_max="3.1416"/>', 'q_min="3.1416" q_max="-3.1416"/>'))
    add("time step zero", r"time_step: expected a positive", "t.xml", t=_sub(trajs, 'time_step="0.01"', 'time_step="0"'),
        args=by_name)
    add("point time backwards", r"point\[2\]@time", "t.xml", t=_sub(trajs, '<point time="1">', '<point time="-1">'),
        args=by_name)
    add("q_dot wrong count", r"q_dot: expected 4 numbers", "t.xml",
        t=_sub(trajs, "<q_dot>0 0 0 0</q_dot>", "<q_dot>0 0</q_dot>"), args=by_name)
    add("unknown trajectory type", r"unknown trajectory type <foo_trajectory>", "t.xml",
        t=_sub(trajs, 'quintic_spline_trajectory id="SR_trajectory"', 'foo_trajectory id="SR_trajectory"').replace(
            "</quintic_spline_trajectory>", "</foo_trajectory>", 1), args=by_name)
    add("force_min negative", r"force_min", "c.xml",
        c=re.sub(r"<force_min>[^<]*</force_min>", "<force_min>-5</force_min>", cables, count=1))
    add("force_max infinite", r"force_max: expected finite", "c.xml",
        c=re.sub(r"<force_max>[^<]*</force_max>", "<force_max>inf</force_max>", cables, count=1))
    add("one attachment", r"expected at least two <attachment>", "c.xml",
        c=re.sub(r"(<attachments>\s*<attachment>.*?</attachment>).*?(</attachments>)", r"\1\2", cables, count=1,
                 flags=re.S))
    add("attachment link 1.5", r"link: expected an integer", "c.xml",
        c=re.sub(r"<link>1</link>", "<link>1.5</link>", cables, count=1))
