"""The per-instant model part on an OpenSim model (default: the thoracoscapular shoulder): the route
pass (OpenSim's paths and wraps), the cable terms (route pass, ``L``, ``M``, ``h``, wrench maps) and
the muscles' force range, at random states on the model's loops, compiled or not.

    python benchmarks/osim_instant.py [--model robots/opensim/TSM_subject_noWeight.osim] [--states 60]
    MCDM_PIN_JIT=off python benchmarks/osim_instant.py      # the uncompiled path

Times are wall times per instant (p50, p99) on whatever else the machine runs.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from mcdm_pin import jit
from mcdm_pin.model import CableSet, TermsEvaluator
from mcdm_pin.model import routes as route_module
from mcdm_pin.model.joints import physical_joints
from mcdm_pin.model.muscles import force_range
from mcdm_pin.osim.load import osim_skeleton
from mcdm_pin.osim.paths import read_paths

ROOT = Path(__file__).resolve().parents[1]


def _states(om, src, n, rng):
    """Random states on the loops: unlocked coordinates uniform in [-0.5, 0.9], speeds normal."""
    cv = {name: int(v) for name, v in zip(om.coordinates, om.coordinate_v)}
    free = [name for name in om.coordinates if not name.startswith("ground_")]
    out = []
    for _ in range(n):
        q = src.configuration({name: rng.uniform(-0.5, 0.9) for name in free})
        if src.loops is not None:
            q = src.loops.project(q, [cv[name] for name in free if name.startswith(("clav", "scapula"))])
        out.append((q, 0.5 * rng.normal(size=om.model.nv)))
    return out


def _stats(ms):
    ms = 1e3 * np.asarray(ms)
    return f"p50 {np.median(ms):.3f} ms, p99 {np.percentile(ms, 99):.3f} ms"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default=str(ROOT / "robots" / "opensim" / "TSM_subject_noWeight.osim"))
    ap.add_argument("--states", type=int, default=60)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    jit.prepare()
    om, _, src, doc = osim_skeleton(args.model)
    model = om.model
    coords = {n: (int(om.q_index[v]), int(v)) for n, v in zip(om.coordinates, om.coordinate_v)}
    cables, muscles, _ = read_paths(doc.root, args.model, model, coords)
    states = _states(om, src, args.states, np.random.default_rng(0))
    joints = physical_joints(model)
    ev = TermsEvaluator(model, CableSet(model, cables), joints)
    ev_m = TermsEvaluator(model, CableSet(model, cables, muscles=muscles, muscle_cables=muscles.names), joints)
    for q, v in states[:2]:  # warm
        ev(q, v, v)
        ev_m(q, v, v)
    route, terms, fr, full = [], [], [], []
    original = route_module.RoutePaths.__call__

    def timed(self, *a, **k):
        t0 = time.perf_counter()
        out = original(self, *a, **k)
        route.append(time.perf_counter() - t0)
        return out

    route_module.RoutePaths.__call__ = timed
    try:
        for _ in range(args.repeat):
            for q, v in states:
                t0 = time.perf_counter()
                t = ev(q, v, v)
                t1 = time.perf_counter()
                force_range(muscles, t.lengths, t.L @ v)
                t2 = time.perf_counter()
                ev_m(q, v, v)
                t3 = time.perf_counter()
                terms.append(t1 - t0)
                fr.append(t2 - t1)
                full.append(t3 - t2)
    finally:
        route_module.RoutePaths.__call__ = original
    print(f"{Path(args.model).name}: {len(cables)} cables, {muscles.size} muscles, {model.nv} dofs; "
          f"MCDM_PIN_JIT={os.environ.get('MCDM_PIN_JIT', 'auto')}, {len(terms)} instants")
    print(f"  route pass                                  {_stats(route[1::2])}")
    print(f"  terms (route pass, L, M, h, wrench maps)    {_stats(terms)}")
    print(f"  muscles' force range (one Bezier kernel)   {_stats(fr)}")
    print(f"  terms with the force range (one call)       {_stats(full)}")


if __name__ == "__main__":
    main()
