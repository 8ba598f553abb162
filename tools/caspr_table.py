"""The table of CASPR's library in docs/caspr.md, measured on the committed robots (a plain clone is
enough), and the provenance file of robots/caspr (``python tools/caspr_library.py table``)."""

from __future__ import annotations

import json
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DOC = REPO / "docs" / "caspr.md"
START, END = "<!-- library-table:start -->", "<!-- library-table:end -->"
CLARABEL_INSTANTS = 51  # instants of each trajectory solved by both back-ends


def _md(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def measure(entry, ref) -> dict:
    """The checks of one imported model: worst relative error against the reference, case 1."""
    from mcdm_pin import load_trajectory
    from tests.caspr_library_check import (TOL, agrees, case1_states, clarabel_alone, compare, reference_states,
                                           robot_of, state_of, worst)

    robot = robot_of(entry)
    tid = entry["table_trajectory"]
    traj = load_trajectory(robot, tid) if tid else None
    errors = [compare(robot, entry["links"], st, *state_of(robot, entry, st, traj))
              for st in reference_states(ref, entry["model"])]
    w = worst(errors)
    out = dict(terms=max(w.values()), terms_ok=max(w.values()) <= TOL, worst=w)
    traj = case1_states(robot, entry, ref)
    t0 = time.perf_counter()
    solved, errors_ = _solve_all(robot, traj)
    alone = clarabel_alone(robot, traj.subsample(CLARABEL_INSTANTS))
    out.update(solved=solved, samples=len(traj), errors=errors_, alone=alone, clarabel_ok=agrees(alone),
               seconds=time.perf_counter() - t0)
    return out


def _solve_all(robot, traj) -> tuple[int, list]:
    """Case 1 at every sample (ProxQP): instants answered, and the instants where the state itself is
    refused (e.g. a cable of zero length), with the reason."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.exceptions import McdmError

    ID = InverseDynamics.for_case(robot, 1, diagnose=False)
    try:
        return int(ID.solve_trajectory(traj, progress=False).found.sum()), []
    except McdmError:
        solved, errors = 0, []
        for k in range(len(traj)):
            try:
                solved += bool(ID.solve(traj.q[k], traj.qd[k], traj.qdd[k]).found)
            except McdmError as exc:
                errors.append((float(traj.t[k]), str(exc)))
        return solved, errors


def rows(lib, ref) -> tuple[list[str], dict]:
    counts = dict(models=0, imported=0, solved_all=0, solved_some=0, terms=0, clarabel=0)
    lines = ["| model | family | CASPR joints | import | trajectory (case 1 solved) | terms vs independent "
             "Newton-Euler (worst rel.) | case 1 vs Clarabel alone: objective; forces (worst rel.) |",
             "|---|---|---|---|---|---|---|"]
    for entry in lib["models"]:
        library = entry["model"] != "SR_model"
        counts["models"] += library
        if entry["status"] != "imported":
            lines.append(f"| {entry['model']} | {entry['family']} | | **refused**: {_md(entry['reason'])} | | | |")
            continue
        m = measure(entry, ref)
        print(f"{entry['model']}: {m}", flush=True)
        counts["imported"] += library
        counts["terms"] += library and m["terms_ok"]
        sets = entry["cable_sets"]
        others = [f"`{s}` refused ({_md(r.split(': ')[-1])})" for s, r in sets.items() if r != "imported"]
        imp = f"imported, cable set `{entry['cable_set']}`" + "".join(f"; {_md(b)}" for b in entry.get("became", []))
        imp += f"; {'; '.join(others)}" if others else ""
        refused_t = [t for t, s in entry["trajectories"].items() if s.startswith("refused")]
        if refused_t:
            imp += "; trajectories refused: " + "; ".join(f"`{t}`: {_md(entry['trajectories'][t][9:])}"
                                                           for t in refused_t)
        name = f"`{entry['table_trajectory']}`" if entry["table_trajectory"] else "at rest at `q_initial` (no joint trajectory)"
        traj = f"{name}: {m['solved']}/{m['samples']}" + "".join(
            f"; at t = {t:g} s: {_md(msg)}" for t, msg in m["errors"][:1])
        if entry["actuated"]:
            traj += " (hybrid: joint motors join the cables)"
        counts["solved_all"] += library and m["solved"] == m["samples"]
        counts["solved_some"] += library and m["solved"] > 0
        counts["clarabel"] += library and m["clarabel_ok"]
        a = m["alone"]
        clar = f"{a['objective']:.1e}; {a['x']:.1e} on {a['optimal']} of {a['instants']} instant(s)"
        if a["mismatch"]:
            times = ", ".join(f"{t:g}" for t in a["mismatch"][:4]) + (", ..." if len(a["mismatch"]) > 4 else "")
            clar += f"; **{len(a['mismatch'])} instant(s) where only one found an optimum** (t = {times} s)"
        joints = ", ".join(entry["joint_types"])
        lines.append(f"| {entry['model']} | {entry['family']} | {joints} | {imp} | {traj} | {m['terms']:.1e} | {clar} |")
    return lines, counts


def write_table() -> int:
    from tests.caspr_library_check import load_library, load_reference

    lib, ref = load_library(), load_reference()
    lines, c = rows(lib, ref)
    summary = (f"Of the {c['models']} models of CASPR's model list, **{c['imported']} import**; "
               f"{c['models'] - c['imported']} {'is' if c['models'] - c['imported'] == 1 else 'are'} refused (the element and the reason are in the table). Of "
               f"the imported models, the terms of **{c['terms']}** agree with the independent Newton-Euler "
               f"implementation to 1e-9 (relative); case 1 is solved at every instant of the model's trajectory "
               f"(or at rest at `q_initial`) for **{c['solved_all']}** and at some instants for "
               f"{c['solved_some']}; case 1 agrees with Clarabel alone (no stage of our solver chain shared) "
               f"for **{c['clarabel']}**: an optimum at the same instants, objectives to 1e-6 and forces to 1e-5 relative (`X_TOL` "
               f"in `tests/caspr_library_check.py`), on "
               f"{CLARABEL_INSTANTS} instants of each trajectory. The SR arm (the "
               f"paper's, not in CASPR's model list) is the last row.")
    text = DOC.read_text(encoding="utf-8")
    if START not in text or END not in text:
        raise SystemExit(f"{DOC}: markers {START} / {END} not found")
    head, rest = text.split(START, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(head + START + "\n" + summary + "\n\n" + "\n".join(lines) + "\n" + END + tail, encoding="utf-8")
    print(summary)
    return 0


def provenance_text() -> str:
    lib = json.loads((REPO / "robots" / "caspr" / "library.json").read_text())
    c = lib["caspr"]
    out = ["# Robots converted from CASPR", "",
           f"Every robot here was converted by `mcdm-pin import-caspr` (through `{lib['regenerate']}`) from the",
           f"model files of CASPR, <{c['repository']}>, commit `{c['commit']}`. CASPR is",
           f"distributed under the {c['licence']}: the licence text is `LICENSE_CASPR.txt` at the top of",
           "this repository. The SR arm comes from CASPR's 2014 CSV files (commit `59451b6`), written as CASPR XML",
           "for mcdm-pin (see `docs/paper.md`). The 8S neck's model asks users to cite Vasavada, Li and Delp,",
           "*Spine* 23(4):412-422, 1998; CASPR asks users to cite Lau, Eden, Tan and Oetomo, IROS 2016.", "",
           "The XML files are the source: `python tools/caspr_library.py convert` (with CASPR's files in",
           "`../shared/reference/caspr`, or `--caspr DIR`) regenerates every file here and in `urdf/caspr/` byte",
           "for byte (`--check` compares). `library.json` records, per model, the CASPR files, what the import did",
           "(cable sets and trajectories imported or refused, with the reason) and which trajectory the library",
           "table of `docs/caspr.md` solves along.", "", "| model | CASPR files (under CASPR's repository) | cable set |",
           "|---|---|---|"]
    for m in lib["models"]:
        files = ", ".join(f"`{v}`" for k, v in m["source"].items() if k != "operational_spaces")
        out.append(f"| {m['model']} | {files} | {m.get('cable_set', '(refused)')} |")
    return "\n".join(out) + "\n"

