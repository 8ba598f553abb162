"""Every MyoSuite model through mcdm-pin's MJCF loader: the table of docs/musculoskeletal.md.

For each model of ``myo_sim`` (the file models of ``myo_sim.REGISTRY``, the other MJCF files of its
``models/legacy`` folder that are whole models, the models ``myo_sim.load_spec`` composes in code and
the left hand of ``myo_sim.FRAGMENT_SPEC_BUILDERS``), MuJoCo compiles it (a composed model through
``MjSpec.compile``, as ``myo_sim.load_model`` does: MuJoCo 4.0 cannot compile again the ``to_xml`` of the
mirrored ones, "repeated default class name"), :meth:`mcdm_pin.robot.Robot.from_mujoco`
reads it, and, when it loads, ``mcdm-pin info``'s validation report runs at MuJoCo's reference pose
``qpos0`` (Pinocchio's ``q = 0``). A refusal prints the loader's message.

Run from the repository root, MuJoCo working in a temporary folder (it writes ``MUJOCO_LOG.TXT``)::

    MCDM_PIN_JIT=off PYTHONPATH=. python tools/myosuite_table.py            # every model
    MCDM_PIN_JIT=off PYTHONPATH=. python tools/myosuite_table.py myoelbow   # some models
    MCDM_PIN_JIT=off PYTHONPATH=. python tools/myosuite_table.py --errors   # the loaded models against MuJoCo

``--errors`` compares, at random states (joint values uniform in their ranges, or in [-1, 1] where
unlimited, with the couplings kept; speeds normal(0, 1); activations uniform in [0, 1]), what mcdm-pin
computes with what MuJoCo computes: tendon lengths with ``ten_length``; ``L`` (the length's gradient,
mapped to MuJoCo's velocity coordinates) with ``ten_J``; the muscle tensions ``passive + gain * a`` with
``-gear * actuator_force``; the interaction wrenches ``u + R^T f`` at MuJoCo's forward-dynamics
acceleration, with the muscles' tensions, with ``cfrc_int`` moved to the joint point and turned into
the child frame. Each is the largest relative error over the states (lengths: per tendon; ``L``: per
the largest ``|ten_J|``; tensions and wrenches: per the largest value, at least 1 N or N m).

Needs ``mujoco`` and ``myo_sim`` (MyoSuite's models). A tool, not a test: it prints a Markdown table.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from contextlib import contextmanager

import numpy as np

# file models of myo_sim.REGISTRY without its aliases (elbow = myoelbow, finger = myofinger, osl = myolegs_osl)
FILE_MODELS = ("myoelbow", "myoelbow_2dof", "myoelbow_exo", "myofinger", "myolegs_osl")
# other whole models in myo_sim/models/legacy (myo_sim.get_path), not in the registry
OTHER_FILES = ("legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_Ideal.xml",
               "legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_sim2.xml",
               "legacy/finger/finger_v0.xml", "legacy/finger/motorfinger_v0.xml")
# myo_sim.build.compose.MODEL_REGISTRY (aliases hand/myohand -> myohand_r, myoarm -> myoarm_r)
COMPOSED = ("myoarm_r", "myoarms", "myohand_r", "myohands", "myolegs", "myolegs26", "myolegs_abdomen",
            "myotorso", "myotorso_abdomen", "myotorso_arm_r", "myotorso_arms", "myofullbody")
# myo_sim.FRAGMENT_SPEC_BUILDERS without a torso scaffold (myohand_l has no load_spec name)
FRAGMENTS = ("myohand_l",)
# the models that load (the table's "loaded" rows)
LOADED = ("myoelbow", "myoelbow_2dof", "myofinger", "legacy/finger/motorfinger_v0.xml", "myolegs_osl", "myoarm_r",
          "myohand_r", "myohand_l", "myolegs", "myolegs26", "myolegs_abdomen", "myotorso", "myotorso_abdomen",
          "myotorso_arm_r", "myoarms", "myohands", "myotorso_arms", "myofullbody", "myoelbow_exo",
          "legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_Ideal.xml",
          "legacy/elbow/myoelbow_1dof6muscles_1dofSoftexo_sim2.xml")


@contextmanager
def _in(folder):
    here = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(here)


def compile_model(name: str):
    """MuJoCo's compiled model of a MyoSuite model name (or ``legacy/...xml`` path)."""
    import mujoco
    import myo_sim

    if name.endswith(".xml"):
        return mujoco.MjModel.from_xml_path(str(myo_sim.get_path(name)))
    if name in FILE_MODELS:
        return mujoco.MjModel.from_xml_path(str(myo_sim.get_xml_path(name)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        spec = myo_sim.FRAGMENT_SPEC_BUILDERS[name]() if name in FRAGMENTS else myo_sim.load_spec(name)
    return spec.compile()


def _counts(robot) -> dict:
    from mcdm_pin.model.cables import Pulley

    return dict(dof=robot.nv, indep=robot.nv if robot.couplings is None else robot.couplings.n,
                cables=robot.m, muscles=0 if robot.cables.muscles is None else robot.cables.muscles.size,
                wraps=len(robot.cables.wraps),
                pulleys=sum(isinstance(e, Pulley) for c in robot.cables for e in c.route))


def _direction(robot, y) -> str:
    """``y`` (a direction of the independent coordinates) as its three largest named components."""
    names = robot.couplings.independent_names if robot.couplings is not None else robot.coordinate_names
    top = [i for i in np.argsort(-np.abs(y))[:3] if abs(y[i]) > 1e-6]
    return ", ".join(f"{y[i]:+.2g} {names[i]}" for i in top)


def _short(level: str, text: str) -> str:
    """One warning or failure of ``mcdm-pin info``'s report, shortened for the table."""
    import re

    if text.startswith(("cannot hold the zero pose", "cannot hold the reference pose")):
        found = re.search(r"below f_min: ([^)]*)\)", text)
        why = f" (would need {found.group(1)} below their passive force)" if found else ""
        return "**case 1 infeasible**" + why
    return f"{level}: {text}"


def _validation(robot) -> str:
    """``mcdm-pin info``'s report at the reference pose (``qpos0``, coupled coordinates following their
    couplings), shortened: ``passes`` or its warnings; the rank, the wrench closure and the count of
    cables over the independent coordinates."""
    from mcdm_pin.conditioning import wrench_closure
    from mcdm_pin.validation import validation_report

    report = validation_report(robot)
    if any(level == "fail" for level, _ in report):
        return "; ".join(_short(level, text) for level, text in report if level == "fail")
    bad = []
    closure = wrench_closure(robot, robot.reference_coordinates())
    n = robot.nv if robot.couplings is None else robot.couplings.n
    if not closure.closed:
        bad.append(f"rank L = {closure.rank} of {n}" if closure.rank < n else "rank L full")
        bad.append(f"no wrench closure along ({_direction(robot, closure.direction)})")
    if robot.m <= n:
        bad.append(f"{robot.m} cables for {n} independent DoF")
    for level, text in report:
        if level != "ok" and not text.startswith(("cables span only", "at the reference pose: wrench closure")) \
                and not text.endswith("to keep every cable in tension"):
            bad.append(_short(level, text))
    return "passes, case 1 feasible" if not bad else "; ".join(bad)


def survey(name: str) -> dict:
    """One row: MuJoCo's sizes, then the loader's counts and the validation, or its refusal."""
    import mujoco

    from mcdm_pin.exceptions import McdmError
    from mcdm_pin.robot import Robot

    row = dict(model=name)
    t0 = time.perf_counter()
    try:
        mj = compile_model(name)
    except Exception as exc:  # a model MuJoCo itself cannot compile
        row["result"] = f"MuJoCo cannot compile it: {str(exc).strip()}"
        return row
    free = " (a free root)" if np.any(mj.jnt_type == 0) else ""
    row["mujoco"] = (f"{mj.nbody - 1} bodies, {mj.njnt} joints{free}, nv {mj.nv}, {mj.ntendon} tendons, "
                     f"{mj.nu} actuators, {mj.neq} equalities")
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    try:
        robot = Robot.from_mujoco(mj, name, name)
    except McdmError as exc:
        row["result"] = f"refused: {exc}"
        return row
    row.update(_counts(robot))
    row["result"] = "loaded"
    row["notes"] = len(robot.notes)
    row["validation"] = ""
    try:
        row["validation"] = _validation(robot)
    except McdmError as exc:
        row["validation"] += f"; error: {exc}"
    row["seconds"] = time.perf_counter() - t0
    return row


def _tendon_J(mj, d) -> np.ndarray:
    """MuJoCo's ``ten_J`` dense (ntendon, nv) (MuJoCo stores it sparse for large models)."""
    if not mj.ten_J_rownnz.size:
        return np.array(d.ten_J).reshape(mj.ntendon, mj.nv)
    J = np.zeros((mj.ntendon, mj.nv))
    for t in range(mj.ntendon):
        a, n = mj.ten_J_rowadr[t], mj.ten_J_rownnz[t]
        J[t, mj.ten_J_colind[a:a + n]] = d.ten_J[a:a + n]
    return J


def _states(mj, robot, rng, count):
    """``count`` random MuJoCo states ``(qpos, qvel, act)`` that keep the couplings (see ``--errors``)."""
    maps = robot.source.maps
    for _ in range(count):
        qpos = mj.qpos0.copy()
        for j in range(mj.njnt):
            if int(mj.jnt_type[j]) in (2, 3):  # slide, hinge (free and ball joints stay at qpos0)
                lo, hi = mj.jnt_range[j] if mj.jnt_limited[j] else (-1.0, 1.0)
                qpos[mj.jnt_qposadr[j]] = rng.uniform(lo, hi)
        q = maps.to_pin_q(qpos)
        v = rng.normal(0.0, 1.0, mj.nv)
        if robot.couplings is not None:
            q, v, _ = robot.couplings.fill(q, v)
        yield maps.to_mj_qpos(q), maps.to_mj_qvel(v, q), rng.uniform(0.0, 1.0, mj.nu)


def errors(name: str, count: int = 50) -> dict:
    """Largest relative errors against MuJoCo of one model (``--errors`` in the module docstring)."""
    import mujoco

    from mcdm_pin.robot import Robot
    from mcdm_pin.model.terms import TermsEvaluator

    mj = compile_model(name)
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    robot = Robot.from_mujoco(mj, name, name)
    maps, ev, d = robot.source.maps, TermsEvaluator(robot), mujoco.MjData(mj)
    acts = np.array([mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_ACTUATOR, n) for n in robot.cable_names])
    tendons = mj.actuator_trnid[acts, 0]
    gear = mj.actuator_gear[acts, 0]
    body_of = {int(maps.body_joint[b]): b for b in range(1, mj.nbody) if mj.body_jntnum[b]}
    err = dict(model=name, states=count, lengths=0.0, L=0.0, tensions=0.0, wrenches=0.0)
    for qpos, qvel, act in _states(mj, robot, np.random.default_rng(1), count):
        d.qpos[:], d.qvel[:] = qpos, qvel
        for i in range(mj.nu):  # muscles: the activation; motors: that share of the control range
            if mj.actuator_actadr[i] >= 0:
                d.act[mj.actuator_actadr[i]] = act[i]
            elif mj.actuator_ctrllimited[i]:
                d.ctrl[i] = mj.actuator_ctrlrange[i, 0] + act[i] * np.diff(mj.actuator_ctrlrange[i])[0]
            else:  # (no control range: a control in [-1, 1])
                d.ctrl[i] = 2.0 * act[i] - 1.0
        mujoco.mj_forward(mj, d)
        mujoco.mj_rnePostConstraint(mj, d)
        q = maps.to_pin_q(qpos)
        t = ev(q, maps.to_pin_v(qvel, qpos), maps.to_pin_a(d.qacc, qpos, qvel), checked=True)
        J = _tendon_J(mj, d)[tendons]
        L_mj = t.L_full @ np.column_stack([maps.to_pin_v(e, qpos) for e in np.eye(mj.nv)])
        f_mj = -d.actuator_force[acts] * gear
        k = robot.cables.muscle_index  # the muscles' tensions from our model; a motor's is its control
        f = f_mj.copy()
        if t.muscles is not None:
            f[k] = t.muscles.passive + t.muscles.gain * act[acts[k]]
        p = t.wrenches(f_mj)
        worst_p = 0.0
        for k, joint in enumerate(robot.joints):
            b, oMi = body_of[joint.child_id], ev.data.oMi[joint.child_id]
            F = d.cfrc_int[b, 3:]
            M = d.cfrc_int[b, :3] + np.cross(d.subtree_com[mj.body_rootid[b]] - oMi.translation, F)
            ref = np.concatenate([oMi.rotation.T @ F, oMi.rotation.T @ M])
            worst_p = max(worst_p, np.abs(p[k] - ref).max() / max(1.0, np.abs(ref).max()))
        ell = d.ten_length[tendons]
        err["lengths"] = max(err["lengths"], np.max(np.abs(t.lengths - ell) / ell))
        err["L"] = max(err["L"], np.abs(L_mj - J).max() / np.abs(J).max())
        err["tensions"] = max(err["tensions"], np.abs(f - f_mj).max() / max(1.0, np.abs(f_mj).max()))
        err["wrenches"] = max(err["wrenches"], worst_p)
    return err


def markdown(rows) -> str:
    head = ("| model | MuJoCo | result | DoF (indep.) | cables (muscles) | wraps | pulleys | "
            "`info` at `qpos0` |\n|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        if r["result"] == "loaded":
            lines.append(f"| `{r['model']}` | {r['mujoco']} | loaded | {r['dof']} ({r['indep']}) | "
                         f"{r['cables']} ({r['muscles']}) | {r['wraps']} | {r['pulleys']} | {r['validation']} |")
        else:
            lines.append(f"| `{r['model']}` | {r.get('mujoco', '-')} | {r['result']} | | | | | |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("models", nargs="*", help="model names (default: every model; with --errors: every "
                                             "model that loads)")
    p.add_argument("--errors", action="store_true", help="compare with MuJoCo instead (module docstring)")
    p.add_argument("--states", type=int, default=50, help="random states per model for --errors (default 50)")
    args = p.parse_args(argv)
    names = args.models or list(FILE_MODELS + OTHER_FILES + COMPOSED + FRAGMENTS)
    rows = []
    with tempfile.TemporaryDirectory() as tmp, _in(tmp):
        if args.errors:
            return _print_errors(args.models or LOADED, args.states)
        for name in names:
            row = survey(name)
            print(f"{name}: {row['result'][:200]} {row.get('validation', '')[:300]} "
                  f"({row.get('seconds', 0):.1f} s)", file=sys.stderr, flush=True)
            rows.append(row)
    print(markdown(rows))
    return 0


def _print_errors(names, count) -> int:
    print(f"largest relative error over {count} random states (see --help)")
    print(f"{'model':18s} {'lengths':>9s} {'L/ten_J':>9s} {'tensions':>9s} {'wrenches':>9s}")
    for name in names:
        e = errors(name, count)
        print(f"{name:18s} " + " ".join(f"{e[k]:9.1e}" for k in ("lengths", "L", "tensions", "wrenches")),
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
