r"""OpenSim as a peer: Static Optimization (SO) for the cable forces of case 1 and Joint Reaction
Analysis (JRA) for the joint reactions, on our robot exported by :mod:`mcdm_pin.export.opensim`.

**The same problem.** SO minimises :math:`\sum_i a_i^p` over the controls :math:`a_i` (tension
:math:`a_i F_{0,i}`) subject to "the model's accelerations equal the target accelerations" and
:math:`a_{min} \le a \le a_{max}`. With one optimal force :math:`F_0` for every cable, :math:`p = 2` and
bounds :math:`f_{min}/F_0 .. f_{max}/F_0` it is our case 1 (:math:`\min f^T f` s.t.
:math:`L^T f = -(M \ddot q + h)`, bounds), scaled by :math:`1/F_0^2`. No reserve actuators: the export
has the cables only, so SO cannot buy acceleration anywhere else.

**Exact states.** SO reads ``q`` and ``u`` from the state it is handed and takes its target
accelerations from the derivative of a quintic interpolating spline (``GCVSplineSet(5, states)``, error
variance 0) of the *speeds* in its states storage, evaluated at the storage's times. A spline of the
sampled trajectory is not exact (from a coordinates file: 5 % of the largest force at the first and last
frames of the 2-link arm's trajectories, from the natural end conditions, and 0.1 % in between). So
:func:`exact_states` gives each frame its own stretch of (fictitious) time, ``2 J + 1`` knots one
second apart on which every speed is a straight line of slope :math:`\ddot q_k` (the lines joined into
one continuous polyline): a quintic interpolant reproduces a straight line exactly, and the kinks between
the stretches reach the middle knot damped by :math:`0.43^J` (the decay of the natural quintic
spline's cardinal functions): for ``J = 40`` the targets equal ``qdd`` to 7e-13 (rounding of the
polyline's values). The frame's state is set at that middle knot's time.

**Tolerance and optimal force.** SO's optimiser is IPOPT (Simbody's, limited-memory Hessian) with an
absolute convergence criterion (default 1e-4, iterations 100) on the problem in controls, whose
objective :math:`\sum a_i^2` and multipliers scale as :math:`1/F_0^2`: with :math:`F_0` = the largest
``f_max`` (1000 N on the 2-link arm) the objective is ~1e-3 and any tolerance is loose. :data:`TUNED`
takes :math:`F_0 = 1` N (controls are newtons; the optimum does not depend on :math:`F_0`), a
criterion of 1e-10 and 1000 iterations; 1e-11 and below stall at the iteration limit on traj2.
Simbody's own constraint tolerance (1e-4, not reachable from SO) is then never the binding one.

**Joint reactions.** JRA's reaction of each joint on its child, expressed in the child body frame, at
the child frame's origin: with the export's frames (body frame = Pinocchio's joint frame, child offset
frame at its origin) this is our interaction wrench :math:`p = u + R^T f` as it stands. The SO forces
are applied as the actuators' override forces (what JRA does itself with a ``forces_file``).

Run ``python benchmarks/peers/opensim_so.py --help``; :mod:`bench_id` runs it as the peer ``opensim``
(case 1) with ``--peers opensim``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[2]
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from mcdm_pin.export.opensim import INSTALL_HINT, require_opensim  # noqa: E402
from mcdm_pin.export.opensim_eval import OpenSimModel  # noqa: E402

TUNED = dict(optimal_force=1.0, tolerance=1e-10, max_iterations=1000)
DEFAULTS = dict(optimal_force=None, tolerance=1e-4, max_iterations=100)  # SO's own defaults; F0 the export's
KNOTS = 40  # J: knots on each side of a frame in the exact states storage


@dataclass
class SORun:
    """Static Optimization on some frames: ``forces`` (N, m) newtons, ``seconds`` (N,) wall time per
    frame (``StaticOptimization.step``, or ``nan`` when the frame was recorded inside ``begin``),
    ``cpu_seconds`` the same in this thread's CPU time (what a busy shared machine inflates less),
    ``setup_s`` (``begin``: working copy of the model, splines, the first frame)."""

    forces: np.ndarray
    seconds: np.ndarray
    setup_s: float = float("nan")
    cpu_seconds: np.ndarray | None = None


def _storage(osim, labels, times, rows):
    sto = osim.Storage()
    sto.setColumnLabels(_labels(osim, ["time", *labels]))
    for t, row in zip(times, rows):
        sto.append(float(t), osim.Vector(row.tolist()))
    return sto


def _labels(osim, labels):
    arr = osim.ArrayStr()
    for name in labels:
        arr.append(name)
    return arr


def state_labels(om: OpenSimModel) -> tuple[list[str], list[str]]:
    """The full state-variable paths of the coordinates' values and speeds, in our coordinate order."""
    values, speeds = [], []
    for c in om.coordinates:
        path = c.getAbsolutePathString()
        values.append(f"{path}/value")
        speeds.append(f"{path}/speed")
    return values, speeds


def exact_states(om: OpenSimModel, x, xd, xdd, knots: int = KNOTS):
    """(states storage, frame times): a storage whose spline-derived accelerations at the frame times are
    ``xdd`` (module docstring). ``x``, ``xd``, ``xdd``: (N, nv) in our coordinate order."""
    osim = om.osim
    x, xd, xdd = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (x, xd, xdd))
    n, nv = xd.shape
    j = np.arange(-knots, knots + 1, dtype=float)
    width = 2 * knots + 1
    times, rows, centres = [], [], []
    level = xd[0] - xdd[0] * knots  # the polyline's value at the first knot
    for k in range(n):
        if k:  # one knot spacing between stretches, crossed at the mean of the two slopes
            level = level + 0.5 * (xdd[k - 1] + xdd[k])
        speeds = level[None, :] + xdd[k][None, :] * (j + knots)[:, None]
        level = speeds[-1]
        t0 = k * width + knots
        centres.append(float(t0))
        times.extend(t0 + j)
        rows.extend(np.hstack([np.repeat(x[k][None, :], width, axis=0), speeds]))
    values, speeds_l = state_labels(om)
    return _storage(osim, values + speeds_l, times, rows), np.array(centres)


def static_optimization(om: OpenSimModel, x, xd, xdd, tolerance: float, max_iterations: int,
                        knots: int = KNOTS) -> SORun:
    """OpenSim's Static Optimization on frames ``(x, xd, xdd)`` (N, nv each, our order) with the exact
    states of :func:`exact_states`; returns the forces ``a F0`` (our cable order) and the times."""
    osim = om.osim
    store, times = exact_states(om, x, xd, xdd, knots)
    so = osim.StaticOptimization()
    so.setModel(om.model)
    so.setStatesStore(store)
    so.setUseModelForceSet(True)
    so.setActivationExponent(2.0)
    so.setUseMusclePhysiology(False)
    so.setConvergenceCriterion(float(tolerance))
    so.setMaxIterations(int(max_iterations))
    s = om.state
    n = len(times)
    seconds, cpu = np.full(n, np.nan), np.full(n, np.nan)
    om.set_state(x[0], xd[0], s, time=times[0])
    t0 = time.perf_counter()
    so.begin(s)
    setup = time.perf_counter() - t0
    for k in range(1, n):
        om.set_state(x[k], xd[k], s, time=times[k])
        t0, c0 = time.perf_counter(), time.thread_time()
        so.step(s, k)
        seconds[k], cpu[k] = time.perf_counter() - t0, time.thread_time() - c0
    controls = _storage_rows(so.getActivationStorage(), n)
    return SORun(controls * om.optimal_force, seconds, setup, cpu)


def _storage_rows(sto, n: int) -> np.ndarray:
    if sto.getSize() != n:
        raise RuntimeError(f"OpenSim recorded {sto.getSize()} frames, expected {n}")
    return np.array([np.array(sto.getStateVector(i).getData().getAsVector().to_numpy()) for i in range(n)])


def joint_reactions(om: OpenSimModel, x, xd, forces) -> tuple[np.ndarray, np.ndarray]:
    """OpenSim's Joint Reaction Analysis with the cable ``forces`` (N, m) applied: (N, J, 6) the reaction
    of each joint (our joint order) on its child, child body frame, at the joint point, ``[F; M]``, and
    (N,) seconds per frame (``begin``/``step``)."""
    osim = om.osim
    jr = osim.JointReaction()
    jr.setName("JointReaction")
    names = [j.name for j in om.spec.joints]
    jr.setJointNames(_labels(osim, names))
    jr.setOnBody(_labels(osim, ["child"]))
    jr.setInFrame(_labels(osim, ["child"]))
    jr.setModel(om.model)
    s = om.state
    for a in om.actuators:
        a.overrideActuation(s, True)
    n = len(forces)
    seconds = np.empty(n)
    for k in range(n):
        om.set_state(x[k], xd[k], s, time=float(k))
        for a, f in zip(om.actuators, forces[k]):
            a.setOverrideActuation(s, float(f))
        t0 = time.perf_counter()
        if k == 0:
            jr.begin(s)
        else:
            jr.step(s, k)
        seconds[k] = time.perf_counter() - t0
    for a in om.actuators:
        a.overrideActuation(s, False)
    with tempfile.TemporaryDirectory() as tmp:  # JRA keeps its loads to itself: read its results file
        jr.printResults("jra", tmp, -1.0, ".sto")
        loads = _storage_rows(osim.Storage(str(Path(tmp) / "jra_JointReaction_ReactionLoads.sto")), n)
    return loads.reshape(n, len(names), 9)[:, :, :6], seconds


# --------------------------------------------------------------------------- OpenSim's own workflow
def static_optimization_tool(om: OpenSimModel, t, x, tolerance: float = 1e-4, max_iterations: int = 100) -> SORun:
    """SO as a user runs it: an ``AnalyzeTool`` on a coordinates file (our ``x`` (N, nv) at times ``t``,
    radians), speeds and accelerations from OpenSim's splines of the coordinates, SO with the given
    criterion and iterations (SO's defaults: 1e-4, 100). ``seconds``: the tool's wall time / frames."""
    osim = om.osim
    names = [c.getName() for c in om.coordinates]
    motion = _storage(osim, names, t, np.asarray(x, dtype=float))
    motion.setInDegrees(False)
    motion.setName("coordinates")
    so = osim.StaticOptimization()
    so.setConvergenceCriterion(float(tolerance))
    so.setMaxIterations(int(max_iterations))
    with tempfile.TemporaryDirectory() as tmp:
        mot = Path(tmp) / "coordinates.mot"
        motion.printToFile(str(mot), "w")
        tool = osim.AnalyzeTool()
        tool.setModel(om.model)
        tool.setCoordinatesFileName(str(mot))
        tool.setInitialTime(float(t[0]))
        tool.setFinalTime(float(t[-1]))
        tool.setResultsDir(tmp)
        tool.setLoadModelAndInput(True)
        tool.updAnalysisSet().cloneAndAppend(so)
        tool.addAnalysisSetToModel()
        try:
            t0 = time.perf_counter()
            tool.run()
            wall = time.perf_counter() - t0
            sto = osim.StaticOptimization.safeDownCast(om.model.getAnalysisSet().get(0)).getActivationStorage()
            controls = _storage_rows(sto, len(t))
        finally:
            tool.removeAnalysisSetFromModel()
    return SORun(controls * om.optimal_force, np.full(len(t), wall / len(t)))


# ------------------------------------------------------------------------------ against mcdm-pin
def force_errors(forces, ours) -> dict:
    """``|f_OpenSim - f_ours|_inf`` per frame, relative to the trajectory's largest force (``traj``)
    and to the frame's own (``frame``): max and median over the frames ours answered."""
    ok = np.all(np.isfinite(ours), axis=1)
    err = np.abs(forces[ok] - ours[ok]).max(axis=1)
    traj = err / np.abs(ours[ok]).max()
    frame = err / np.abs(ours[ok]).max(axis=1)
    return dict(traj_max=float(traj.max()), traj_median=float(np.median(traj)), frame_max=float(frame.max()),
                frame_median=float(np.median(frame)), frames=int(ok.sum()))


def compare(robot, traj, settings: dict = TUNED, reactions: bool = True) -> dict:
    """Our case 1 and OpenSim's SO (exact states, ``settings``) + JRA on every frame of ``traj``:
    times per frame, force errors (:func:`force_errors`), the EoM residual of SO's forces in our model,
    and JRA against our interaction wrenches at SO's forces and at ours (relative to each frame's largest
    wrench component)."""
    from mcdm_pin import InverseDynamics

    ident = InverseDynamics.for_case(robot, 1)
    ident.solve_trajectory(traj, progress=False)  # warm-up (imports, compiled kernels)
    t0 = time.perf_counter()
    res = ident.solve_trajectory(traj, progress=False)
    ours_ms = (time.perf_counter() - t0) / len(traj) * 1e3
    ours = np.where(res.found[:, None], res.f, np.nan)
    om = OpenSimModel(robot, settings["optimal_force"])
    run = static_optimization(om, traj.q, traj.qd, traj.qdd, settings["tolerance"], settings["max_iterations"])
    terms = [ident.evaluate(traj.q[k], traj.qd[k], traj.qdd[k]) for k in range(len(traj))]
    eom = np.array([t.eom_residual(f) for t, f in zip(terms, run.forces)])
    out = dict(frames=len(traj), answered=int(res.found.sum()), ours_ms=ours_ms, so_ms=_ms(run.seconds),
               so_cpu_ms=_ms(run.cpu_seconds),
               so_seconds=run.seconds[1:].tolist(),
               so_setup_ms=run.setup_s * 1e3, forces=force_errors(run.forces, ours),
               so_eom_max=float(eom[res.found].max()), so_eom_fail=int(((eom > 1e-6) & res.found).sum()),
               optimal_force=om.optimal_force, **{k: v for k, v in settings.items() if k != "optimal_force"})
    if reactions:
        R, seconds = joint_reactions(om, traj.q, traj.qd, run.forces)
        ok = np.flatnonzero(res.found)
        at_so = [_rel(R[k], terms[k].wrenches(run.forces[k])) for k in ok]
        at_ours = [_rel(R[k], terms[k].wrenches(res.f[k])) for k in ok]
        out.update(jra_ms=_ms(seconds), jra_vs_ours_at_so_forces=float(max(at_so)),
                   jra_vs_ours_at_our_forces=float(max(at_ours)),
                   so_jra_seconds=(run.seconds + seconds)[1:].tolist())  # per frame (frame 0 is in begin)
    return out


def _rel(a, b) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


def _ms(seconds) -> dict:
    x = np.asarray(seconds, dtype=float)
    x = x[np.isfinite(x)] * 1e3
    p10, p50, p90 = np.percentile(x, [10, 50, 90])
    return dict(median=float(p50), p10=float(p10), p90=float(p90), max=float(x.max()), n=int(x.size))


def settings_study(robot, traj) -> list[dict]:
    """What each setting costs: SO with OpenSim's defaults (AnalyzeTool on the coordinates, criterion
    1e-4, F0 = the export's largest f_max) and with one setting changed at a time, against our case 1."""
    from mcdm_pin import InverseDynamics

    res = InverseDynamics.for_case(robot, 1).solve_trajectory(traj, progress=False)
    ours = np.where(res.found[:, None], res.f, np.nan)
    default_f0 = max(c.f_max for c in robot.cables)
    rows = []
    for label, states, f0, tol, its in (
            ("OpenSim defaults: coordinates file, criterion 1e-4, F0 = max f_max", "tool", default_f0, 1e-4, 100),
            ("defaults + exact velocities and accelerations", "exact", default_f0, 1e-4, 100),
            ("defaults + F0 = 1 N", "tool", 1.0, 1e-4, 100),
            ("defaults + criterion 1e-10 (1000 iterations)", "tool", default_f0, 1e-10, 1000),
            ("coordinates file, F0 = 1 N, criterion 1e-10", "tool", 1.0, 1e-10, 1000),
            ("exact states, F0 = max f_max, criterion 1e-10", "exact", default_f0, 1e-10, 1000),
            ("exact states, F0 = 1 N, criterion 1e-10 (TUNED)", "exact", 1.0, 1e-10, 1000)):
        om = OpenSimModel(robot, f0)
        run = (static_optimization_tool(om, traj.t, traj.q, tol, its) if states == "tool" else
               static_optimization(om, traj.q, traj.qd, traj.qdd, tol, its))
        rows.append(dict(label=label, ms=_ms(run.seconds)["median"], **force_errors(run.forces, ours)))
    return rows


# ----------------------------------------------------------------------------- bench_id's hook
def bench_rows(robot, traj, case: int, ours_row: dict, stats_ms) -> list[dict]:
    """Rows of ``benchmarks/bench_id.py``'s table for OpenSim (case 1 only; SO has no interaction
    objective): SO per frame (solve), SO + JRA per frame (total), the check against our forces
    (1e-6 of the trajectory's largest force) and our wrenches (1e-6 of each frame's largest)."""
    if case != 1:
        return []
    label = "OpenSim 4.6 Static Optimization + JRA (F0 1 N, tol 1e-10)"
    try:
        require_opensim()
    except ImportError:
        return [dict(case=case, backend="opensim", label=label, model_ms=stats_ms([]), solve_ms=stats_ms([]),
                     total_ms=stats_ms([]), no_answer=0, check=f"skipped: not installed ({INSTALL_HINT})",
                     ratio=float("nan"))]
    c = compare(robot, traj)
    ok = (c["forces"]["traj_max"] <= 1e-6 and c["jra_vs_ours_at_so_forces"] <= 1e-6)
    check = ("ok" if ok else "FAIL") + (f" (forces {c['forces']['traj_max']:.0e}, JRA "
                                        f"{c['jra_vs_ours_at_so_forces']:.0e})")
    so = np.array(c["so_seconds"])
    total = np.array(c["so_jra_seconds"])
    return [dict(case=case, backend="opensim", label=label,
                 model_ms=stats_ms([]), solve_ms=stats_ms(so), total_ms=stats_ms(total),
                 no_answer=c["so_eom_fail"], check=check,
                 ratio=stats_ms(total)["median"] / ours_row["total_ms"]["median"])]


# -------------------------------------------------------------------------------------- command
def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--robot", default=str(REPO / "robots" / "two_link_sr.yaml"), help="sidecar (YAML)")
    p.add_argument("--trajectory", nargs="+", default=["traj1", "traj2"])
    p.add_argument("--samples", type=int, help="N frames spread over each trajectory (default: all)")
    p.add_argument("--no-study", action="store_true", help="skip the settings study")
    p.add_argument("--json", help="write the results as JSON")
    args = p.parse_args(argv)
    try:
        require_opensim()
    except ImportError as exc:
        print(f"opensim_so: {exc}")
        return 2
    from mcdm_pin import Robot, load_trajectory

    robot = Robot.load(args.robot)
    out = {}
    for name in args.trajectory:
        traj = load_trajectory(robot, name)
        if args.samples:
            traj = traj.subsample(args.samples)
        c = compare(robot, traj)
        f = c["forces"]
        print(f"\n{robot.name} {name}: {c['frames']} frames, ours answered {c['answered']}; OpenSim SO with "
              f"exact states, F0 {c['optimal_force']:g} N, criterion {c['tolerance']:g}")
        print(f"  ms per frame: ours (case 1, solve_trajectory wall / frames) {c['ours_ms']:.3f}; SO "
              f"{c['so_ms']['median']:.1f} (p10-p90 {c['so_ms']['p10']:.1f}-{c['so_ms']['p90']:.1f}, max "
              f"{c['so_ms']['max']:.1f}; CPU {c['so_cpu_ms']['median']:.1f}; begin {c['so_setup_ms']:.0f}); JRA "
              f"{c['jra_ms']['median']:.2f}")
        print(f"  SO forces vs ours: max {f['traj_max']:.1e} of the largest force (median {f['traj_median']:.1e});"
              f" per frame max {f['frame_max']:.1e} (median {f['frame_median']:.1e}); SO's EoM residual in our "
              f"model {c['so_eom_max']:.1e}; frames we answered and SO did not (EoM > 1e-6): {c['so_eom_fail']}")
        print(f"  JRA vs our interaction wrenches: at SO's forces {c['jra_vs_ours_at_so_forces']:.1e}, at ours "
              f"{c['jra_vs_ours_at_our_forces']:.1e} (of each frame's largest component)")
        out[name] = c
        if not args.no_study:
            rows = settings_study(robot, traj)
            print("  | settings | ms per frame | max error (of largest force) | median | per frame max |")
            print("  |---|---|---|---|---|")
            for r in rows:
                print(f"  | {r['label']} | {r['ms']:.1f} | {r['traj_max']:.1e} | {r['traj_median']:.1e} | "
                      f"{r['frame_max']:.1e} |")
            out[name + "_study"] = rows
    if args.json:
        import json

        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
