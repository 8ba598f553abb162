"""Scaling study: time per instant against the number of links (degrees of freedom) and of cables.

Generated robots: a vertical chain of N links (spine-like), each attached to the one below by a
unilateral ball joint (spherical: three revolute URDF joints x, y, z, socket axis +z, cone on every
joint in case 3). Links are 0.1 m long, 0.5 kg uniform cylinders of radius 0.03 m (inertia
m(3r^2 + l^2)/12 across, m r^2/2 along), the joint at the top of the link below. Cables run from the
lower part of one link to the middle of a link one (2/3 of the cables) or two (1/3) joints higher, at
5 cm from the axis, evenly spread around it, with a +-0.5 rad twist (alternating) so that they can
also turn the joints about their axes; 0.1 N <= f <= 2000 N. The motion is a rest-to-rest quintic
of every joint (about x, y and z, total bend independent of N), 1 s, ``--instants`` samples.

Two sweeps (each point one generated robot, written as URDF + sidecar into a temporary folder):

- **links**: N = 2, 4, 8, 16, 32 links (6 to 96 DoF) with 9 cables per link (18 to 288 cables);
- **cables**: N = 2 links (6 DoF) with 8 to 300 cables.

For each robot and for cases 1 (min f^T f), 2 (min interaction forces) and 3 (case 2 + 15 deg cones on
every joint) (``--case``), ``InverseDynamics.solve_trajectory`` runs ``--repeat`` times (after one
warm-up run) and the medians over instants and runs of the model time (kinematics, RNEA, cable maps, QP
assembly) and the solve time are kept; ``--cold`` runs every instant alone (``reset()`` then ``solve``,
shuffled; the total is the wall time of ``solve``), ``--warm-and-cold`` both. Instants without an answer
(infeasible, inaccurate) are counted and reported. Growth laws are least-squares fits of log(time)
against log(DoF) (links sweep), log(cables) (cables sweep) and jointly ``t = C nv^a m^b`` over both
sweeps (first mode only).

``--peers all`` (or some of daqp, piqp, proxqp, qoco, clarabel: ``benchmarks/peers``) times the solver
peers on the same instants' problems, warm or cold like ours, one BLAS thread: a peer's total is the
instant's model time plus its solve, and its answer is checked against our objective (1e-6 relative).
For each case and size the table gives the best peer (among those that answered every instant at our
objective) and its total over ours (below 1: the peer is faster).

    python benchmarks/scaling.py [--instants 11] [--repeat 3] [--quick] [--case 1 2 3]
        [--peers all] [--cold | --warm-and-cold] [--json FILE] [--plot docs/img/scaling.png]
        [--markdown docs/scaling.md]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

REPO = Path(__file__).resolve().parents[1]
LINK_LENGTH, LINK_MASS, LINK_RADIUS, CABLE_RADIUS = 0.1, 0.5, 0.03, 0.05
CONE_DEG = 15.0
LINKS_SWEEP = [(n, 9 * n) for n in (2, 4, 8, 16, 32)]
CABLES_SWEEP = [(2, m) for m in (8, 16, 32, 64, 128, 200, 300)]
QUICK_LINKS = [(n, 9 * n) for n in (2, 4, 8)]
QUICK_CABLES = [(2, m) for m in (8, 32, 128)]


def chain_files(n_links: int, n_cables: int, instants: int) -> tuple[str, dict]:
    """URDF text and sidecar mapping of an ``n_links`` chain with ``n_cables`` cables."""
    L, mass, r = LINK_LENGTH, LINK_MASS, LINK_RADIUS
    ixx = mass * (3 * r * r + L * L) / 12
    izz = mass * r * r / 2
    name = lambda k: "base" if k == 0 else f"link{k}"  # noqa: E731
    urdf = ['<?xml version="1.0"?>', f'<robot name="chain_{n_links}_{n_cables}">', '  <link name="base"/>']
    joints = {}
    for k in range(1, n_links + 1):
        chain = [name(k - 1), f"{name(k)}_sx", f"{name(k)}_sy", name(k)]
        urdf += [f'  <link name="{chain[1]}"/>', f'  <link name="{chain[2]}"/>']
        for a, (axis, tag) in enumerate((("1 0 0", "x"), ("0 1 0", "y"), ("0 0 1", "z"))):
            z = L if a == 0 else 0.0
            urdf.append(f'  <joint name="{name(k)}_q{tag}" type="revolute"><parent link="{chain[a]}"/>'
                        f'<child link="{chain[a + 1]}"/><origin xyz="0 0 {z!r}" rpy="0 0 0"/>'
                        f'<axis xyz="{axis}"/><limit lower="-3.2" upper="3.2" effort="0" velocity="0"/></joint>')
        urdf.append(f'  <link name="{name(k)}"><inertial><origin xyz="0 0 {L / 2!r}" rpy="0 0 0"/>'
                    f'<mass value="{mass!r}"/><inertia ixx="{ixx!r}" ixy="0" ixz="0" iyy="{ixx!r}" iyz="0" '
                    f'izz="{izz!r}"/></inertial></link>')
        joints[f"j{k}"] = {"type": "spherical", "urdf_joints": [f"{name(k)}_q{t}" for t in "xyz"],
                           "socket_axis": [0.0, 0.0, 1.0], "alpha": 1.0, "beta": 0.0, "cone_deg": CONE_DEG}
    urdf.append("</robot>")
    # cables: round-robin over the links they end on; every third spans two joints
    per_link = [[] for _ in range(n_links + 1)]
    for c in range(n_cables):
        per_link[1 + c % n_links].append(c)
    cables = [None] * n_cables
    for k in range(1, n_links + 1):
        own = per_link[k]
        for i, c in enumerate(own):
            span = 2 if (i % 3 == 2 and k >= 2) else 1
            phi = 2 * np.pi * i / len(own) + 0.37 * k
            twist = 0.5 if i % 2 == 0 else -0.5
            lower = [CABLE_RADIUS * np.cos(phi), CABLE_RADIUS * np.sin(phi), 0.25 * L]
            upper = [CABLE_RADIUS * np.cos(phi + twist), CABLE_RADIUS * np.sin(phi + twist), 0.5 * L]
            cables[c] = {"name": f"c{c}", "f_min": 0.1, "f_max": 2000.0,
                         "route": [{"link": name(k - span), "point": [round(float(x), 9) for x in lower]},
                                   {"link": name(k), "point": [round(float(x), 9) for x in upper]}]}
    amp = 0.6 / n_links  # total bend of the chain ~0.6 rad about x whatever N
    start = {f"j{k}": [-amp, -0.5 * amp, -0.5 * amp] for k in range(1, n_links + 1)}
    end = {f"j{k}": [amp, 0.5 * amp, 0.5 * amp] for k in range(1, n_links + 1)}
    sidecar = {"version": 1, "name": f"chain_{n_links}_{n_cables}", "urdf": "chain.urdf",
               "gravity": [0.0, 0.0, -9.81], "joints": joints, "cables": cables,
               "trajectories": {"sweep": {"type": "quintic", "q_start": start, "q_end": end,
                                          "duration": 1.0, "dt": 1.0 / max(instants - 1, 1)}}}
    return "\n".join(urdf) + "\n", sidecar


def build(folder: Path, n_links: int, n_cables: int, instants: int):
    from mcdm_pin import Robot, load_trajectory

    folder.mkdir(parents=True, exist_ok=True)
    urdf, sidecar = chain_files(n_links, n_cables, instants)
    (folder / "chain.urdf").write_text(urdf)
    (folder / "chain.yaml").write_text(yaml.safe_dump(sidecar, sort_keys=False))
    robot = Robot.load(folder / "chain.yaml")
    return robot, load_trajectory(robot, "sweep")


def _ours_runs(ident, traj, repeat: int, cold: bool, rng):
    """``repeat`` runs of ours: warm ``solve_trajectory`` (its timed model and solve per instant), or
    cold (``reset()`` then ``solve`` per instant, shuffled; the wall time of each call as the total).
    Yields ``(found, model_s, solve_s, total_s, status, message)`` arrays per run."""
    for _ in range(repeat):
        if not cold:
            res = ident.solve_trajectory(traj, progress=False)
            yield (res.found, res.time_model_s, res.time_solve_s, res.time_model_s + res.time_solve_s,
                   res.status, res.message)
            continue
        n = len(traj)
        found, model, solve, total = (np.zeros(n, bool), np.zeros(n), np.zeros(n), np.zeros(n))
        status, message = np.empty(n, object), np.empty(n, object)
        for k in rng.permutation(n):
            ident.reset()
            t0 = time.perf_counter()
            r = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
            total[k] = time.perf_counter() - t0
            found[k], model[k], solve[k], status[k], message[k] = (r.found, r.time_model_s, r.time_solve_s,
                                                                   r.status, r.message)
        yield found, model, solve, total, status, message


def measure(robot, traj, case: int, repeat: int, cold: bool = False) -> dict:
    """Ours on one robot and case: medians of the model, solve and total times per answered instant."""
    from mcdm_pin import InverseDynamics

    ident = InverseDynamics.for_case(robot, case)
    ident.solve_trajectory(traj, progress=False)  # warm-up
    model, solve, total, bad, statuses = [], [], [], 0, {}
    for found, m_, s_, t_, status, message in _ours_runs(ident, traj, repeat, cold, np.random.default_rng(0)):
        bad = int((~found).sum())
        model.append(m_[found])
        solve.append(s_[found])
        total.append(t_[found])
        for st in status:
            statuses[str(st)] = statuses.get(str(st), 0) + 1
    # instants without an answer: does Clarabel (exact SOCP) find one? (back-end failure vs infeasible)
    missing = []
    for k in np.flatnonzero(~found):
        entry = dict(instant=int(k), status=str(status[k]), message=str(message[k])[:160])
        try:
            ref = InverseDynamics.for_case(robot, case, solver="clarabel").solve(
                traj.q[k], traj.qd[k], traj.qdd[k])
            entry["clarabel"] = str(ref.status)
        except Exception as e:  # noqa: BLE001 - clarabel not installed
            entry["clarabel"] = f"not checked ({e})"
        missing.append(entry)
    model, solve, total = (np.concatenate(x) * 1e3 for x in (model, solve, total))
    med = lambda x: float(np.median(x)) if x.size else float("nan")  # noqa: E731
    return dict(model_ms=med(model), solve_ms=med(solve), total_ms=med(total),
                no_answer=bad, statuses=statuses, missing=missing)


def measure_peers(robot, traj, case: int, peers, repeat: int, cold: bool) -> dict:
    """Each solver peer on the instants' problems (assembled once; the model time of each instant,
    timed here, is added to the peer's solve time), checked against our objective per instant."""
    from mcdm_pin import InverseDynamics
    from mcdm_pin.problem import Context

    from peers.timing import time_peer

    ident = InverseDynamics.for_case(robot, case)
    qps, model_s, ref_obj = [], [], []
    for k in range(len(traj)):
        t0 = time.perf_counter()
        qp = ident.problem.assemble(ident.evaluate(traj.q[k], traj.qd[k], traj.qdd[k]), Context(robot))
        model_s.append(time.perf_counter() - t0)
        qps.append(qp)
        ident.reset()
        r = ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
        ref_obj.append(qp.objective(r.f) if r.found else None)
    out = {}
    for p in peers:
        if qps[0].cones and not p.cones:
            continue  # a QP solver: no second-order cones
        t = time_peer(p, qps, ref_obj, repeat, cold)
        total = np.array([model_s[k] + dt for k, dt in zip(t["instant"], t["solve_s"])]) * 1e3
        out[p.name] = dict(total_ms=float(np.median(total)) if total.size else float("nan"),
                           solve_ms=float(np.median(t["solve_s"]) * 1e3) if t["solve_s"] else float("nan"),
                           failed=t["failed"], mismatch=t["mismatch"], worst_rel=t["worst_rel"],
                           message=str(t["message"])[:160])
    return out


def best_peer(row: dict):
    """(name, best peer total / ours) over the peers that answered every instant at our objective."""
    good = {n: r for n, r in row.get("peers", {}).items()
            if not r["failed"] and not r["mismatch"] and np.isfinite(r["total_ms"])}
    if not good:
        return None, float("nan")
    name = min(good, key=lambda n: good[n]["total_ms"])
    return name, good[name]["total_ms"] / row["total_ms"]


def fit(x, y) -> tuple[float, float]:
    """Least-squares ``log y = log C + a log x``: (a, C)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = np.isfinite(y) & (y > 0)
    a, logc = np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)
    return float(a), float(np.exp(logc))


def joint_fit(nv, m, y) -> tuple[float, float, float]:
    """``log y = log C + a log nv + b log m``: (a, b, C)."""
    nv, m, y = (np.asarray(v, float) for v in (nv, m, y))
    ok = np.isfinite(y) & (y > 0)
    X = np.column_stack([np.ones(ok.sum()), np.log(nv[ok]), np.log(m[ok])])
    coef = np.linalg.lstsq(X, np.log(y[ok]), rcond=None)[0]
    return float(coef[1]), float(coef[2]), float(np.exp(coef[0]))


def run(links_sweep, cables_sweep, instants: int, repeat: int, log=print, cases=(1, 2, 3),
        modes=("warm",), peers=()) -> dict:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for sweep, points in (("links", links_sweep), ("cables", cables_sweep)):
            for n_links, n_cables in points:
                robot, traj = build(Path(tmp) / f"{sweep}_{n_links}_{n_cables}", n_links, n_cables, instants)
                for case in cases:
                    for mode in modes:
                        t0 = time.perf_counter()
                        r = measure(robot, traj, case, repeat, cold=mode == "cold")
                        if peers:
                            r["peers"] = measure_peers(robot, traj, case, peers, repeat, cold=mode == "cold")
                        row = dict(sweep=sweep, links=n_links, nv=robot.nv, cables=robot.m, case=case,
                                   mode=mode, instants=len(traj), **r)
                        rows.append(row)
                        best, ratio = best_peer(row)
                        log(f"{sweep:6s} links {n_links:2d} dof {robot.nv:3d} cables {robot.m:3d} case {case} "
                            f"{mode}: model {r['model_ms']:8.3f} ms, solve {r['solve_ms']:8.3f} ms, "
                            f"no answer {r['no_answer']}/{len(traj)}"
                            + (f"; best peer {best} {ratio:.2f}x ours" if best else "")
                            + f" ({time.perf_counter() - t0:.1f} s)")
    fits = {}
    for case in cases:
        for part in ("model_ms", "solve_ms", "total_ms"):
            sel = [r for r in rows if r["case"] == case and r["mode"] == modes[0]]
            a = [r for r in sel if r["sweep"] == "links"]
            b = [r for r in sel if r["sweep"] == "cables"]
            key = f"case{case}_{part[:-3]}"
            fits[key] = dict(
                vs_dof=fit([r["nv"] for r in a], [r[part] for r in a]) if len(a) > 1 else None,
                vs_cables=fit([r["cables"] for r in b], [r[part] for r in b]) if len(b) > 1 else None,
                joint=joint_fit([r["nv"] for r in sel], [r["cables"] for r in sel], [r[part] for r in sel])
                if len(sel) > 2 else None)
    return dict(rows=rows, fits=fits, instants=instants, repeat=repeat, modes=list(modes),
                peers=[p.name for p in peers])


def plot(result: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows, fits = result["rows"], result["fits"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    styles = {("model_ms", 1): ("tab:blue", "o", "--"), ("solve_ms", 1): ("tab:blue", "s", ":"),
              ("total_ms", 1): ("tab:blue", "D", "-"), ("model_ms", 3): ("tab:red", "o", "--"),
              ("solve_ms", 3): ("tab:red", "s", ":"), ("total_ms", 3): ("tab:red", "D", "-")}
    for ax, sweep, xkey, fkey, xlabel in ((axes[0], "links", "nv", "vs_dof", "degrees of freedom (3 per link)"),
                                          (axes[1], "cables", "cables", "vs_cables", "cables (2 links, 6 DoF)")):
        for (part, case), (color, marker, ls) in styles.items():
            sel = [r for r in rows if r["sweep"] == sweep and r["case"] == case
                   and r.get("mode", "warm") == result.get("modes", ["warm"])[0]]
            if not sel:
                continue
            x = np.array([r[xkey] for r in sel], float)
            y = np.array([r[part] for r in sel], float)
            f = fits[f"case{case}_{part[:-3]}"][fkey]
            label = f"case {case} {part[:-3]}" + (f" ~ x^{f[0]:.2f}" if f else "")
            ax.loglog(x, y, marker=marker, ls=ls, color=color, label=label, alpha=0.9 if part == "total_ms" else 0.6)
        from matplotlib.ticker import NullFormatter
        ticks = sorted({r[xkey] for r in rows if r["sweep"] == sweep})
        ax.set_xticks(ticks)
        ax.set_xticklabels([str(t) for t in ticks])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(xlabel)
        ax.set_ylabel("time per instant, ms (median)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_title("links sweep: 2-32 links, 9 cables per link")
    axes[1].set_title("cables sweep: 2 links, 8-300 cables")
    fig.suptitle("mcdm-pin time per instant (default chain; case 1 blue, case 3 red with 15 deg cones)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(result: dict) -> str:
    lines = ["| sweep | links | DoF | cables | case | mode | model, ms | solve, ms | total, ms | no answer |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in result["rows"]:
        lines.append(f"| {r['sweep']} | {r['links']} | {r['nv']} | {r['cables']} | {r['case']} | {r['mode']} | "
                     f"{r['model_ms']:.3f} | {r['solve_ms']:.3f} | {r['total_ms']:.3f} | "
                     f"{r['no_answer']} of {r['instants']} |")
    if result.get("peers"):
        lines += ["", peers_markdown(result)]
    lines += ["", "| quantity | vs DoF (links sweep, cables = 3 DoF) | vs cables (6 DoF) | joint fit t = C nv^a m^b |",
              "|---|---|---|---|"]
    for key, f in result["fits"].items():
        def one(v):
            return f"t ~ {v[1]:.3g} x^{v[0]:.2f}" if v else "-"
        j = f["joint"]
        jt = f"a = {j[0]:.2f}, b = {j[1]:.2f}, C = {j[2]:.3g} ms" if j else "-"
        lines.append(f"| {key.replace('_', ' ')} | {one(f['vs_dof'])} | {one(f['vs_cables'])} | {jt} |")
    return "\n".join(lines)


def peers_markdown(result: dict) -> str:
    """Ours and every peer's total per instant (ms, median), and the best peer / ours (below 1: the
    peer is faster). A peer's cell carries ``F`` (instants without an answer, over all runs) and ``M``
    (answers off our objective by more than 1e-6 relative); such a peer is not the best peer."""
    names = result["peers"]
    lines = ["| sweep | DoF | cables | case | mode | ours, ms | " + " | ".join(f"{n}, ms" for n in names)
             + " | best peer | best peer / ours |",
             "|---|---|---|---|---|---|" + "---|" * len(names) + "---|---|"]
    for r in result["rows"]:
        cells = []
        for n in names:
            p = r["peers"].get(n)
            if p is None:
                cells.append("n/a (no cones)")
                continue
            flags = "".join(f" {k[0].upper()}{p[k]}" for k in ("failed", "mismatch") if p[k])
            cells.append(f"{p['total_ms']:.3f}{flags}")
        best, ratio = best_peer(r)
        lines.append(f"| {r['sweep']} | {r['nv']} | {r['cables']} | {r['case']} | {r['mode']} | "
                     f"{r['total_ms']:.3f} | " + " | ".join(cells) + f" | {best or '-'} | "
                     + (f"{ratio:.2f}" if best else "-") + " |")
    return "\n".join(lines)


def document(result: dict, plot_path: str | None) -> str:
    """docs/scaling.md: the command, the machine, the plot, the tables and the growth laws."""
    m = result["machine"]
    f = result["fits"]
    c1, c3 = f["case1_total"], f["case3_total"]
    bad = [r for r in result["rows"] if r["no_answer"]]

    def share(case):
        big = max((r for r in result["rows"] if r["case"] == case), key=lambda r: (r["nv"], r["cables"]))
        return 100.0 * big["model_ms"] / (big["model_ms"] + big["solve_ms"])

    out = ["# Scaling: time per instant against links and cables", "",
           f"Generated by `{result['command']}`"
           f" ({result['wall_s']:.0f} s here). The robots, the motion and the method are described in the "
           "script's docstring: vertical chains of 0.5 kg, 0.1 m links joined by ball joints (3 DoF each, "
           "socket axis +z), cables spanning one or two joints at 5 cm from the axis with a +-0.5 rad twist, "
           f"a rest-to-rest quintic sampled at {result['instants']} instants; case 1 = min f^T f, case 3 = "
           f"min interaction forces with {CONE_DEG:g} deg cones on every joint; mcdm-pin's default chain "
           "(warm instants: the compiled active set from the previous instant's; cold ones: in case 1 the "
           "active set read off the dual's optimum (Newton's method from zero multipliers), verified, "
           "elsewhere the compiled interior-point method with its crossover).",
           "",
           f"Machine: {m['cpu']}, {m['nproc']} cores (`nproc`), Python {m['python']}, "
           + ", ".join(f"{k} {v}" for k, v in m["versions"].items())
           + f". The machine was shared with other jobs (1-min load average {m['load_avg_1min']} at the end): "
           f"each cell is the median over instants and {result['repeat']} runs (after a warm-up run).", ""]
    if plot_path:
        out += [f"![time per instant against DoF and cables]({Path(plot_path).relative_to('docs') if plot_path.startswith('docs/') else plot_path})", ""]
    out += ["## Growth law", "",
            "Least-squares power laws `t = C x^a` (log-log slopes; the links sweep grows cables with the DoF, "
            "m = 3 nv, so its slope is the combined growth):", "",
            f"- **case 1** total: ~ nv^{c1['vs_dof'][0]:.2f} along the links sweep, ~ m^{c1['vs_cables'][0]:.2f} "
            f"along the cables sweep; joint fit t = {c1['joint'][2]:.3g} ms nv^{c1['joint'][0]:.2f} m^{c1['joint'][1]:.2f}.",
            f"- **case 3** total: ~ nv^{c3['vs_dof'][0]:.2f} along the links sweep, ~ m^{c3['vs_cables'][0]:.2f} "
            f"along the cables sweep; joint fit t = {c3['joint'][2]:.3g} ms nv^{c3['joint'][0]:.2f} m^{c3['joint'][1]:.2f}.",
            f"- The model evaluation (Pinocchio + compiled cable maps + QP assembly) grows as "
            f"~ nv^{f['case1_model']['vs_dof'][0]:.2f} (case 1) and ~ nv^{f['case3_model']['vs_dof'][0]:.2f} "
            f"(case 3) along the links sweep; at the largest robot it is {share(1):.0f}% (case 1) and "
            f"{share(3):.0f}% (case 3) of the time per instant.",
            "- Small problems are dominated by fixed per-instant costs (the Python around the compiled "
            "kernels: scaling, the chain's stages, the check), so a single "
            "power law fits the small end poorly: read the slopes as the large-size growth, and the table "
            "for the actual times.", ""]
    out += ["## Tables", "", markdown(result), ""]
    out += ["## Instants without an answer", ""]
    if not bad:
        out += ["None: every generated robot is feasible along its motion and every instant was solved.", ""]
    else:
        for r in bad:
            out.append(f"- {r['sweep']} sweep, {r['links']} links, {r['cables']} cables, case {r['case']}: "
                       f"{r['no_answer']} of {r['instants']} instants per run ({r['statuses']} over all runs).")
            for e in r["missing"]:
                out.append(f"  - instant {e['instant']}: `{e['status']}` ({e['message']}); Clarabel on the "
                           f"same instant: `{e['clarabel']}`.")
        out.append("")
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--instants", type=int, default=11, help="instants of the quintic (default 11)")
    p.add_argument("--repeat", type=int, default=3, help="timed runs per robot and case (default 3)")
    p.add_argument("--quick", action="store_true", help="small sweeps only (up to 24 DoF, 128 cables)")
    p.add_argument("--case", type=int, nargs="+", default=[1, 2, 3], choices=[1, 2, 3])
    p.add_argument("--peers", default="", help="comma-separated solver peers (daqp,piqp,proxqp,qoco,clarabel "
                                               "or all; default none)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--cold", action="store_true", help="every instant alone (reset before each)")
    mode.add_argument("--warm-and-cold", action="store_true", help="both, warm then cold")
    p.add_argument("--json", help="write rows and fits as JSON")
    p.add_argument("--plot", help="write the plot (PNG), e.g. docs/img/scaling.png")
    p.add_argument("--markdown", help="write the study as Markdown (e.g. docs/scaling.md)")
    args = p.parse_args(argv)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _common import machine, one_blas_thread
    from peers.solvers import SOLVER_PEERS, expand, make_solver_peers

    one_blas_thread()
    names = expand([n.strip() for n in args.peers.split(",") if n.strip()])
    unknown = [n for n in names if n not in SOLVER_PEERS]
    if unknown:
        raise SystemExit(f"scaling: unknown peer(s) {unknown}; expected some of {','.join(SOLVER_PEERS)} or all")
    peers, notes = make_solver_peers(names)
    for note in notes:
        print(f"note: {note}")
    modes = ("warm", "cold") if args.warm_and_cold else ("cold",) if args.cold else ("warm",)
    t0 = time.perf_counter()
    result = run(QUICK_LINKS if args.quick else LINKS_SWEEP, QUICK_CABLES if args.quick else CABLES_SWEEP,
                 args.instants, args.repeat, cases=tuple(args.case), modes=modes, peers=peers)
    result["wall_s"] = time.perf_counter() - t0
    result["command"] = " ".join(["python benchmarks/scaling.py", *(sys.argv[1:] if argv is None else argv)])
    result["machine"] = machine()
    print()
    print(markdown(result))
    bad = [r for r in result["rows"] if r["no_answer"]]
    if bad:
        print("\ninstants without an answer:")
        for r in bad:
            print(f"  {r['sweep']} {r['links']} links {r['cables']} cables case {r['case']} {r['mode']}: "
                  f"{r['no_answer']} of {r['instants']} ({r['statuses']})")
            for e in r["missing"]:
                print(f"    instant {e['instant']}: {e['status']}, Clarabel: {e['clarabel']}; {e['message']}")
    peer_trouble = [(r, n, q) for r in result["rows"] for n, q in r.get("peers", {}).items()
                    if q["failed"] or q["mismatch"]]
    if peer_trouble:
        print("\npeers without an answer (F) or off our objective (M, worst relative error):")
        for r, n, q in peer_trouble:
            print(f"  {n}: {r['sweep']} {r['nv']} DoF {r['cables']} cables case {r['case']} {r['mode']}: "
                  f"F {q['failed']}, M {q['mismatch']} (worst {q['worst_rel']:.1e}) {q['message']}")
    m = result["machine"]
    print(f"\n{result['wall_s']:.0f} s in all; 1-min load average at the end {m['load_avg_1min']}")
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2, default=str))
    if args.plot:
        plot(result, Path(args.plot))
        print(f"wrote {args.plot}")
    if args.markdown:
        Path(args.markdown).write_text(document(result, args.plot))
        print(f"wrote {args.markdown}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
