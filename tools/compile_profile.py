"""Where the kernels' compile goes: every registered entry point compiled in this one process into
an empty numba cache, each specialisation's compile timed through numba's compile events
(``numba.core.event``, ``numba:compile``), inclusive and exclusive of the kernels it compiles on
the way.

    NUMBA_CACHE_DIR=$(mktemp -d) python tools/compile_profile.py [--top 25] [--json out.json]

Prints each entry point's wall seconds, the total, the specialisations with the largest exclusive
share, and every kernel of the package compiled in more than one specialisation (a literal or
``A``-ordered argument at a call site compiles a specialisation of its own). The cache must be
empty (a fresh ``NUMBA_CACHE_DIR``): what loads from a cache is not compiled and not timed.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import time

os.environ["MCDM_PIN_JIT"] = "off"  # the registry's calls compile here, not through jit.compile_now

from numba.core import event  # noqa: E402

from mcdm_pin import jit  # noqa: E402


class _Recorder(event.Listener):
    """Each compile's ``(kernel, signature, inclusive s, exclusive s)``."""

    def __init__(self):
        self.stack, self.rows = [], []

    def on_start(self, ev):
        self.stack.append([ev.data["dispatcher"], ev.data["args"], time.perf_counter(), 0.0])

    def on_end(self, ev):
        disp, args, t0, inner = self.stack.pop()
        dt = time.perf_counter() - t0
        if self.stack:
            self.stack[-1][3] += dt
        f = disp.py_func
        self.rows.append((f"{f.__module__}.{f.__name__}", str(args), dt, dt - inner))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--top", type=int, default=25, help="specialisations listed by exclusive time")
    ap.add_argument("--json", help="write every specialisation's row to this file")
    args = ap.parse_args(argv)
    if not os.environ.get("NUMBA_CACHE_DIR"):
        print("set NUMBA_CACHE_DIR to an empty folder (what loads from a cache is not timed)", file=sys.stderr)
        return 2
    rec = _Recorder()
    event.register("numba:compile", rec)
    t0 = time.perf_counter()
    for disp, call_args in jit._all_calls():
        t1 = time.perf_counter()
        disp(*call_args)
        print(f"entry {jit._name(disp)}: {time.perf_counter() - t1:.1f} s", flush=True)
    total = time.perf_counter() - t0
    rows = rec.rows
    print(f"\ntotal {total:.1f} s wall, {len(rows)} specialisations, "
          f"{sum(r[3] for r in rows):.1f} s exclusive in all\n")
    print("| exclusive, s | inclusive, s | kernel |\n|---|---|---|")
    for name, _, inc, exc in sorted(rows, key=lambda r: -r[3])[:args.top]:
        print(f"| {exc:.2f} | {inc:.2f} | `{name}` |")
    count = collections.Counter(r[0] for r in rows if r[0].startswith("mcdm_pin."))
    several = {n: k for n, k in count.items() if k > 1}
    print(f"\nkernels of the package in more than one specialisation: {several or 'none'}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
