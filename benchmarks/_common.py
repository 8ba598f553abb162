"""What the benchmark scripts share: the machine description and the CASPR neck with the paper's
settings (the robot converted from CASPR and committed under robots/caspr; ``--caspr DIR`` with CASPR's
XML files converts it afresh into a temporary folder)."""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# benchmarks time the compiled kernels: compile them first when they are not (mcdm_pin/jit.py)
os.environ.setdefault("MCDM_PIN_JIT", "compile")
DEFAULT_CASPR = REPO / "robots" / "caspr"  # the committed conversions; or a folder of CASPR's XML files


_BLAS_LIMIT = []  # the threadpoolctl limit in force (kept alive for the process)


def one_blas_thread() -> None:
    """One BLAS/OpenMP thread for everything in this process (ours and the peers alike): the
    environment for libraries loaded later, threadpoolctl for those already loaded (numpy's BLAS)."""
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    if not _BLAS_LIMIT:
        from threadpoolctl import threadpool_limits
        _BLAS_LIMIT.append(threadpool_limits(limits=1))


def cpu_model() -> str:
    """``lscpu``'s model name (``platform.processor()`` when lscpu is missing)."""
    model = platform.processor() or "unknown CPU"
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=10).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                model = line.split(":", 1)[1].strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return model


def machine() -> dict:
    """CPU, cores, Python, the relevant package versions and the 1-minute load average."""
    versions = {}
    for mod in ("pinocchio", "proxsuite", "numba", "clarabel", "cvxpy", "scipy", "numpy", "cyipopt"):
        try:
            versions[mod] = __import__(mod).__version__
        except Exception:  # noqa: BLE001 - not installed or no version
            pass
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = float("nan")
    return dict(cpu=cpu_model(), nproc=os.cpu_count(), python=platform.python_version(), versions=versions,
                load_avg_1min=round(load, 2))


def machine_line() -> str:
    m = machine()
    return f"{m['cpu']}, {m['nproc']} cores (nproc), Python {m['python']}"


def import_neck(caspr: Path, out: Path, trajectory_ids=None):
    """CASPR's 8S neck: the committed conversion when ``caspr`` holds one (``caspr/8S_neck/8S_neck.yaml``),
    else imported from CASPR's XML in ``caspr/8S_neck`` into ``out``; returns an object with ``.sidecar``."""
    from types import SimpleNamespace

    from mcdm_pin.caspr import import_caspr

    committed = Path(caspr) / "8S_neck" / "8S_neck.yaml"
    if committed.is_file():
        return SimpleNamespace(sidecar=committed)
    d = Path(caspr) / "8S_neck"
    if not (d / "8S_neck_bodies.xml").is_file():
        raise SystemExit(f"CASPR neck model not found in {d} (give the CASPR folder, e.g. --caspr DIR)")
    return import_caspr(d / "8S_neck_bodies.xml", d / "8S_neck_cables.xml", out,
                        trajectories_xml=d / "8S_neck_trajectories.xml", trajectory_ids=trajectory_ids)


def neck_case_options(joint_names) -> dict:
    """The paper's neck settings per case: alpha = 1/8 and beta = 0 on every joint (cases 2 and 3),
    15 deg cones on every joint (case 3)."""
    base = dict(alpha={j: 0.125 for j in joint_names}, beta={j: 0.0 for j in joint_names})
    return {1: {}, 2: dict(base), 3: dict(base, cones={j: 15.0 for j in joint_names})}


def load_robot(robot_path: str, trajectory: str, chain: int | None = None):
    """``(robot, trajectory, {case: for_case options})``: a robot file along ``trajectory`` (the
    neck with the paper's settings, :func:`neck_case_options`), or ``benchmarks/scaling.py``'s chain
    of ``chain`` links (``9 chain`` cables) along its ``sweep``."""
    from mcdm_pin import Robot
    from mcdm_pin.trajectory import load_trajectory

    if chain:
        import tempfile

        import scaling

        robot, tr = scaling.build(Path(tempfile.mkdtemp()), chain, 9 * chain, 11)
        return robot, tr, {c: {} for c in (1, 2, 3)}
    robot = Robot.load(robot_path)
    opts = neck_case_options(robot.joint_names) if "neck" in robot_path else {c: {} for c in (1, 2, 3)}
    return robot, load_trajectory(robot, trajectory), opts


def captured_ipm_arguments(ident, traj, instants: int) -> list:
    """The arguments of ``_fast.ipm_answer`` at ``instants`` cold instants of ``traj`` (shuffled with
    seed 0, each after ``ident.reset()``), captured from ``solvers.ipm.ipm_arguments``: the named
    structures (the kernel takes each as a plain tuple, ``tuple(s)``)."""
    import random

    from mcdm_pin.settings import DEFAULT
    from mcdm_pin.solvers import ipm as ipm_mod

    captured, original = [], ipm_mod.ipm_arguments

    def capture(qp, settings=DEFAULT):
        args = original(qp, settings)
        captured.append(args)
        return args

    ipm_mod.ipm_arguments = capture
    try:
        order = list(range(len(traj.t)))
        random.Random(0).shuffle(order)
        for k in order[:instants]:
            ident.reset()
            ident.solve(traj.q[k], traj.qd[k], traj.qdd[k])
    finally:
        ipm_mod.ipm_arguments = original
    return captured
