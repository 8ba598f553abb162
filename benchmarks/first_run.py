"""What the first run on a new machine costs, and what the user sees meanwhile.

    python benchmarks/first_run.py

Runs the README's first command, ``mcdm-pin solve robots/two_link_sr.yaml --trajectory traj1 --case 3``
(as ``python -m mcdm_pin``), with an empty numba cache (``NUMBA_CACHE_DIR`` pointed at a new temporary
folder), as on a machine where mcdm-pin was just installed:

1. the first run: the kernels are not compiled; the run says so in one line on stderr and runs them
   as their Python code (the same kernels, the same chain of stages);
2. ``mcdm-pin compile --timings`` (the explicit compile, as a user or a CI runs it; its wall and CPU
   time, the CPU of its worker processes included, and each entry point's);
3. the second run, on the compiled kernels.

Prints a table of wall times and the stderr lines of each run. The answers of both runs are the same
(compared line by line, but for the timing line and the time of a tied peak).
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
COMMAND = ["solve", "robots/two_link_sr.yaml", "--trajectory", "traj1", "--case", "3", "-q"]


def _run(env) -> tuple[float, str, str]:
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "mcdm_pin", *COMMAND], cwd=REPO, env=env, capture_output=True,
                         text=True, timeout=600)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise SystemExit(f"first_run: the command failed ({out.returncode}): {out.stderr}")
    return wall, out.stdout, out.stderr


def _children_cpu() -> float:
    """CPU seconds (user + system) of the finished child processes and their own children."""
    use = resource.getrusage(resource.RUSAGE_CHILDREN)
    return use.ru_utime + use.ru_stime


def _peaks(text: str) -> list[str]:
    """The answer's lines with the peak values only (ties at a bound or a cone may be reported at
    another instant of the tie)."""
    rows = []
    for line in text.splitlines():
        parts = line.split()
        if line.startswith("time per instant") or not parts:
            continue
        rows.append(" ".join(p for k, p in enumerate(parts) if k not in (2, 4)) if len(parts) >= 4 else line)
    return rows


def main() -> int:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, MCDM_PIN_JIT="auto")
        load0 = os.getloadavg()[0]
        wall1, out1, err1 = _run(env)
        t0, cpu0, load_c = time.perf_counter(), _children_cpu(), os.getloadavg()[0]
        done = subprocess.run([sys.executable, "-m", "mcdm_pin", "compile", "--timings"], cwd=REPO, env=env,
                              capture_output=True, text=True, timeout=1800)
        compile_wall, compile_cpu = time.perf_counter() - t0, _children_cpu() - cpu0
        if done.returncode != 0:
            raise SystemExit(f"first_run: mcdm-pin compile failed: {done.stderr}")
        wall2, out2, err2 = _run(env)
        load1 = os.getloadavg()[0]
    same = _peaks(out1) == _peaks(out2)
    print(f"`mcdm-pin {' '.join(COMMAND)}` with an empty numba cache; 1-min load average {load0:.2f} before, "
          f"{load1:.2f} after\n")
    print("| run | wall, s | stderr |")
    print("|---|---|---|")
    print(f"| first (kernels not compiled: they run as Python) | {wall1:.2f} | {err1.strip() or '-'} |")
    lines = done.stdout.strip().splitlines()
    print(f"| `mcdm-pin compile` | {compile_wall:.1f} | {lines[0] if lines else '-'} |")
    print(f"| second (compiled kernels) | {wall2:.2f} | {err2.strip() or '-'} |")
    print(f"\n`mcdm-pin compile`: wall {compile_wall:.1f} s, CPU {compile_cpu:.1f} s (the command and its "
          f"workers), 1-min load average {load_c:.2f} when it started\n")
    print("\n".join(lines[1:]))
    print(f"\nthe two runs' answers are {'the same' if same else 'DIFFERENT'}")
    print("\nfirst run's last line:  " + out1.strip().splitlines()[-1])
    print("second run's last line: " + out2.strip().splitlines()[-1])
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
