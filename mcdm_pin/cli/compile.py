"""``mcdm-pin compile``: compile the numba kernels once per install (about 160 s of CPU, split between
the cores: docs/speed.md, "First run") and cache them; until then every run executes the same kernels
as plain Python (mcdm_pin/jit.py). A CI caches the kernels' cache folder, printed here (``--where``).
It also writes the bytecode of the modules a run imports where it is missing (mcdm_pin/bytecode.py):
where ``PYTHONDONTWRITEBYTECODE`` is set, Python itself never does."""

from __future__ import annotations

import time


def add(sub):
    p = sub.add_parser("compile", help="compile the numba kernels once per install (the same answers, "
                                       "faster; runs before it execute them as plain Python)")
    p.add_argument("--where", action="store_true",
                   help="print the kernels' cache folder and whether it holds a complete compile; "
                        "compile nothing")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes that compile at once (default: MCDM_PIN_COMPILE_WORKERS, else the "
                        "usable cores)")
    p.add_argument("--timings", action="store_true",
                   help="after a compile, print each entry point's wall and CPU seconds and its process")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import bytecode, jit
    from ..exceptions import SolverError

    folder = jit.cache_dir()
    if args.where:
        state = "compiled" if jit.stamp_current() else "not compiled (or stale)"
        print(f"{folder if folder is not None else 'no writable numba cache'}: {state}")
        return 0
    if args.workers is not None and args.workers < 1:
        raise SolverError(f"--workers {args.workers}: expected a positive number of processes")
    seconds = jit.compile_now(workers=args.workers)  # (says on stderr when it compiles or waits)
    print(f"kernels ready ({len(jit.entry_points())} entry points) in {seconds:.1f} s; cache: {folder}")
    t0 = time.perf_counter()
    done = bytecode.write_bytecode(bytecode.module_sources())
    unwritable = (f", {len(done.unwritable)} not writable (e.g. {done.unwritable[0]}: they compile at every "
                  f"import)" if done.unwritable else "")
    print(f"bytecode of the modules a run imports: {done.written} written, {done.current} current{unwritable} "
          f"({time.perf_counter() - t0:.1f} s)")
    info = jit.LAST_COMPILE
    if args.timings and info:
        print(f"compiled in {info['workers']} process(es): wall {info['wall']:.1f} s, CPU {info['cpu']:.1f} s "
              f"(all processes); final load pass {info['load_wall']:.1f} s")
        print("| entry point | process | wall, s | CPU, s |\n|---|---|---|---|")
        for name, wall, cpu, worker in info["entries"]:
            print(f"| `{name}` | {worker} | {wall:.1f} | {cpu:.1f} |")
    return 0
