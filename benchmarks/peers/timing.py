"""Timing the solver peers on a list of already assembled problems (``scaling.py``).

Each peer solves the instants in order (warm: its state carried from one instant to the next, as
its module's ``warm`` says) or each alone (cold: ``reset()`` before every instant). Only the solve is
timed here; the caller adds the model time of the instant (the same terms and assembly every
back-end needs). Every answer is checked against a reference objective per instant (ours):
within ``OBJ_RTOL`` relative (plus ``OBJ_ATOL`` absolute), else a mismatch.
"""

from __future__ import annotations

import time

import numpy as np

OBJ_RTOL, OBJ_ATOL = 1e-6, 1e-8


def time_peer(peer, qps, ref_obj, repeat: int, cold: bool) -> dict:
    """``solve_s`` (list per answered instant and run), ``failed`` (no answer, per run, summed over
    runs), ``mismatch`` (answers off the reference objective), ``worst_rel`` and the last message."""
    out = dict(solve_s=[], instant=[], failed=0, mismatch=0, worst_rel=0.0, message="")
    for _ in range(repeat):
        peer.reset()
        for k, qp in enumerate(qps):
            if cold:
                peer.reset()
            t0 = time.perf_counter()
            try:
                f = peer.solve(qp)
            except Exception as e:  # noqa: BLE001 - a peer failing is a result
                f, peer.message = None, f"error: {e}"
            dt = time.perf_counter() - t0
            if f is None or not np.all(np.isfinite(f)):
                out["failed"] += 1
                out["message"] = peer.message
                continue
            if ref_obj[k] is not None:
                err = abs(qp.objective(f) - ref_obj[k])
                rel = err / max(abs(ref_obj[k]), 1e-300)
                out["worst_rel"] = max(out["worst_rel"], rel)
                if err > OBJ_RTOL * abs(ref_obj[k]) + OBJ_ATOL:
                    out["mismatch"] += 1
            out["solve_s"].append(dt)
            out["instant"].append(k)
    return out
