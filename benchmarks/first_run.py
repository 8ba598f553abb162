"""What the first run on a machine costs: numba compiling the kernels (then cached).

    python benchmarks/first_run.py

Runs, in a fresh process with an empty numba cache (``NUMBA_CACHE_DIR`` pointed at a new temporary
folder), then again in a second process with that cache filled: import, loading the bundled 2-link
robot, and 5 instants of cases 1 and 3. Prints the wall times of both.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PROBE = """
import time
t0 = time.perf_counter()
from mcdm_pin import InverseDynamics, Robot, load_trajectory
robot = Robot.load({sidecar!r})
traj = load_trajectory(robot, "traj1").subsample(5)
t1 = time.perf_counter()
for case in (1, 3):
    InverseDynamics.for_case(robot, case).solve_trajectory(traj, progress=False)
t2 = time.perf_counter()
print(f"{{t1 - t0:.2f}} {{t2 - t1:.2f}}")
"""


def main() -> int:
    code = PROBE.format(sidecar=str(REPO / "robots" / "two_link_sr.yaml"))
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        print("| run | import + robot, s | 5 instants of cases 1 and 3, s |")
        print("|---|---|---|")
        for label in ("first (empty numba cache: compiles)", "second (cache filled)"):
            out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                 check=True).stdout.split()
            print(f"| {label} | {out[0]} | {out[1]} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
