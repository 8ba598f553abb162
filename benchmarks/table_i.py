"""Timing table like the source paper's Table I: time per instant (mean and standard deviation) and
solver iterations, for the 2-link arm (trajectories 1 and 2) and the neck (roll), cases 1-3, with
ProxQP (default back-end) and Clarabel (exact conic reference).

The models are the conversions committed under robots/caspr (or, with --caspr DIR, CASPR's XML files imported into a temporary
folder. Case 2 and 3 settings are the paper's: 2-link, alpha = 1 on the shoulder, 30 deg cone; neck,
alpha = 1/8, beta = 0 on every joint, 15 deg cones.

Time per instant = model (kinematics, RNEA, cable maps, QP assembly) + solve, wall clock, over the
instants that have an answer (infeasible instants also run a diagnosis and are left out; their count
is shown). Iterations are the back-end's (ProxQP: summed over cone rounds).

    python benchmarks/table_i.py [--repeat 3] [--json out.json] [--caspr DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import DEFAULT_CASPR, import_neck, machine_line, neck_case_options  # noqa: E402


def examples(caspr: Path, out: Path):
    from mcdm_pin import Robot, load_trajectory
    from mcdm_pin.caspr import import_caspr

    sr_dir = caspr / "SR_model"
    if (sr_dir / "SR_model.yaml").is_file():  # the committed conversion
        sr = Robot.load(sr_dir / "SR_model.yaml")
    else:
        sr = Robot.load(import_caspr(sr_dir / "SR_model_bodies.xml", sr_dir / "SR_model_cables.xml", out / "sr",
                                     trajectories_xml=sr_dir / "SR_model_trajectories.xml", name="sr").sidecar)
    neck = Robot.load(import_neck(caspr, out / "neck", ["roll"]).sidecar)
    neck_kw = neck_case_options(neck.joint_names)[3]
    return [("2-link, trajectory 1", sr, load_trajectory(sr, "SR_trajectory"), {"cones": {"Link_1": 30.0}}),
            ("2-link, trajectory 2", sr, load_trajectory(sr, "SR_trajectory2"), {"cones": {"Link_1": 30.0}}),
            ("neck (8S), roll", neck, load_trajectory(neck, "roll"), neck_kw)]


def run(caspr: Path, repeat: int, solvers=("proxqp", "clarabel")):
    from mcdm_pin import InverseDynamics

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, robot, traj, kw in examples(caspr, Path(tmp)):
            for case in (1, 2, 3):
                for solver in solvers:
                    times, iters, solves = [], [], []
                    # warm-up: one untimed run (imports, numba's compiled kernels loaded from its cache)
                    InverseDynamics.for_case(robot, case, solver=solver, **kw).solve_trajectory(traj, progress=False)
                    for _ in range(repeat):
                        ident = InverseDynamics.for_case(robot, case, solver=solver, **kw)
                        res = ident.solve_trajectory(traj, progress=False)
                        ok = res.found
                        times.append((res.time_model_s + res.time_solve_s)[ok])
                        solves.append(res.time_solve_s[ok])
                        iters.append(res.iterations[ok])
                    t = np.concatenate(times) * 1e3
                    it = np.concatenate(iters)
                    solve = np.concatenate(solves) * 1e3
                    rows.append(dict(example=label, case=case, solver=solver, instants=len(traj),
                                     no_answer=int((~res.found).sum()), mean_ms=float(t.mean()),
                                     std_ms=float(t.std()), solve_mean_ms=float(solve.mean()),
                                     iterations_mean=float(it.mean()), iterations_max=int(it.max())))
    return rows


def markdown(rows) -> str:
    lines = ["| example | case | back-end | time per instant, ms (mean ± std) | of which solve, ms | "
             "iterations (mean / max) | instants without answer |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['example']} | {r['case']} | {r['solver']} | {r['mean_ms']:.2f} ± {r['std_ms']:.2f} | "
                     f"{r['solve_mean_ms']:.2f} | {r['iterations_mean']:.1f} / {r['iterations_max']} | "
                     f"{r['no_answer']} of {r['instants']} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3, help="runs per cell (default 3)")
    p.add_argument("--json", help="also write the rows as JSON")
    p.add_argument("--caspr", default=str(DEFAULT_CASPR), help="the CASPR reference folder")
    p.add_argument("--solver", action="append", help="only this back-end (repeatable)")
    args = p.parse_args(argv)
    caspr = Path(args.caspr)
    if not ((caspr / "8S_neck" / "8S_neck_bodies.xml").is_file() or (caspr / "8S_neck" / "8S_neck.yaml").is_file()):
        print(f"table_i: CASPR reference models not found in {caspr}", file=sys.stderr)
        return 2
    rows = run(caspr, args.repeat, tuple(args.solver or ("proxqp", "clarabel")))
    print(f"Machine: {machine_line()}; {args.repeat} run(s) per cell.\n")
    print(markdown(rows))
    if args.json:
        Path(args.json).write_text(json.dumps({"machine": machine_line(), "repeat": args.repeat, "rows": rows},
                                              indent=2))
        print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
