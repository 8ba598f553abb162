"""A workspace store in a few lines: statuses, the wrench-feasible and the stability-aware parts."""

from __future__ import annotations

import numpy as np


def fractions(ds) -> dict:
    """Counts that describe a store: ``poses``, ``status`` ({word: count}) and, when the margins were
    computed and every cable has the same ``f_max``, ``wrench_feasible`` (``needed_f_max <= f_max``)
    and, with cones, ``stable`` (wrench-feasible and ``needed_cone_deg <= cone``) and ``removed``
    (the share of the wrench-feasible poses that the cones remove)."""
    attrs = ds.attrs["workspace"]
    status = ds["status"].values
    words, counts = np.unique(status, return_counts=True)
    out = dict(poses=int(status.size), status={str(w): int(c) for w, c in zip(words, counts)})
    f_max = np.array(attrs["f_max"], dtype=float)
    need_f = ds["needed_f_max"].values
    if not attrs["setup"]["margins"] or not np.all(f_max == f_max[0]):
        return out
    wrench = need_f <= f_max[0]
    out["wrench_feasible"] = int(wrench.sum())
    cones = attrs["cones_deg"]
    if cones:
        cone = max(cones.values())  # needed_cone_deg is reported as the largest cone after the move
        stable = wrench & (ds["needed_cone_deg"].values <= cone)
        out["stable"] = int(stable.sum())
        out["removed"] = float(1.0 - stable.sum() / wrench.sum()) if wrench.any() else float("nan")
        # the margins and the solver answer the same question two ways: count where they differ
        out["status_disagrees"] = int(np.sum(stable != (status == "optimal")))
    return out


def summary(ds) -> str:
    """The text ``mcdm-pin workspace`` prints after a run."""
    a = fractions(ds)
    attrs = ds.attrs["workspace"]
    n = a["poses"]
    lines = [f"{attrs['robot']['name']}: {attrs['problem']}",
             f"{n} poses ({attrs['poses']['kind']}), chunks of {attrs['chunk']}",
             "status: " + ", ".join(f"{w} {c} ({100 * c / n:.1f} %)" for w, c in a["status"].items())]
    if "wrench_feasible" in a:
        w = a["wrench_feasible"]
        lines.append(f"wrench-feasible (needed_f_max <= f_max = {attrs['f_max'][0]:g} N): {w} poses "
                     f"({100 * w / n:.1f} %)")
    if "stable" in a:
        cones = ", ".join(f"{j} {d:g} deg" for j, d in attrs["cones_deg"].items())
        lines.append(f"stability-aware (also needed_cone_deg <= cone; {cones}): {a['stable']} poses "
                     f"({100 * a['stable'] / n:.1f} %); the cones remove {100 * a['removed']:.1f} % of "
                     f"the wrench-feasible workspace")
        if a["status_disagrees"]:
            lines.append(f"note: at {a['status_disagrees']} poses the margins and the solver's status "
                         f"disagree (a margin within its tolerance of the limit, or a solver failure)")
    return "\n".join(lines)
