"""``mcdm-pin compile``: compile the numba kernels once per install (about 160 s of CPU, one core) and
cache them; until then every run executes the same kernels as plain Python (mcdm_pin/jit.py,
docs/speed.md). A CI caches the kernels' cache folder, printed here (``--where``)."""

from __future__ import annotations


def add(sub):
    p = sub.add_parser("compile", help="compile the numba kernels once per install (the same answers, "
                                       "faster; runs before it execute them as plain Python)")
    p.add_argument("--where", action="store_true",
                   help="print the kernels' cache folder and whether it holds a complete compile; "
                        "compile nothing")
    p.set_defaults(func=run)


def run(args) -> int:
    from .. import jit

    folder = jit.cache_dir()
    if args.where:
        state = "compiled" if jit.stamp_current() else "not compiled (or stale)"
        print(f"{folder if folder is not None else 'no writable numba cache'}: {state}")
        return 0
    seconds = jit.compile_now()  # (says on stderr when it compiles or waits for another compile)
    print(f"kernels ready ({len(jit.entry_points())} entry points) in {seconds:.1f} s; cache: {folder}")
    return 0
