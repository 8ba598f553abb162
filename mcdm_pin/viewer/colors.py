"""The viewer's colours: the cable tension scale, its "nice" top, and the muted link colours.

**Cable tension scale.** The *turbo* colour map (matplotlib's) from 0.1 to 1: from a clear blue at 0 N
through cyan, green, yellow and orange to dark red at ``fmax``; forces above ``fmax`` keep the top
colour, instants without a valid answer are grey. Turbo's darkest tenth (near-black violet) is left
out: a cable at its minimum force would vanish against a dark link.

**Links** are drawn in their URDF colours mixed with a light grey (``mute``), so that saturated body
colours (example-robot-data's human is bright red, green and blue) do not compete with the cables.
"""

from __future__ import annotations

import numpy as np

# matplotlib's turbo at 0.1, 0.2, ..., 1.0, linear in between
CABLE_MAP = np.array([
    (0.270, 0.349, 0.796), (0.244, 0.609, 0.997), (0.098, 0.837, 0.803), (0.276, 0.971, 0.517),
    (0.644, 0.990, 0.234), (0.883, 0.866, 0.217), (0.996, 0.643, 0.192), (0.941, 0.356, 0.070),
    (0.765, 0.144, 0.010), (0.480, 0.016, 0.011)])
TURBO = CABLE_MAP  # the name older code imports
NO_ANSWER_RGB = (0.55, 0.55, 0.55)
CONE_OK_RGB = (0.15, 0.75, 0.25)
CONE_OUT_RGB = (1.0, 0.0, 0.0)
ARROW_RGB = (0.8, 0.0, 0.8)
LINK_RGB = (0.55, 0.6, 0.7)
PLATFORM_RGB = (0.35, 0.42, 0.55)  # a cable robot's platform (muted to a mid blue-grey)
ANCHOR_RGB = (0.25, 0.25, 0.25)
MUTE_TOWARD = np.array([0.80, 0.80, 0.82])
MUTE = 0.6  # share of the light grey in a muted link colour
BACKGROUND = ((0.98, 0.98, 0.98), (0.82, 0.85, 0.90))  # top, bottom
GRID_RGB = (0.62, 0.64, 0.68)

# mantissas of the "nice" tops of the colour scale: the peak rounded up by at most a third
NICE = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0)


def tension_rgb(f, fmax: float) -> np.ndarray:
    """Colours (..., 3) of cable forces ``f`` (N) on the fixed scale [0, fmax]; NaN -> grey."""
    f = np.asarray(f, dtype=float)
    x = np.clip(np.nan_to_num(f, nan=0.0) / fmax, 0.0, 1.0) * (len(CABLE_MAP) - 1)
    i = np.minimum(np.floor(x).astype(int), len(CABLE_MAP) - 2)
    w = (x - i)[..., None]
    rgb = CABLE_MAP[i] * (1 - w) + CABLE_MAP[i + 1] * w
    rgb[~np.isfinite(f)] = NO_ANSWER_RGB
    return rgb


def nice_ceil(x: float) -> float:
    """The smallest ``m x 10^k >= x`` with ``m`` in :data:`NICE` (1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8):
    at most a third above ``x`` (53.8 N -> 60 N, 125.2 N -> 150 N); 1 for non-positive ``x``."""
    if not np.isfinite(x) or x <= 0:
        return 1.0
    k = np.floor(np.log10(x))
    for m in NICE:
        top = float(f"{m * 10**k:.12g}")  # 0.3, not 0.30000000000000004
        if top >= x * (1 - 1e-12):
            return top
    return float(f"{10 ** (k + 1):.12g}")


def mute(rgb, share: float | None = None) -> np.ndarray:
    """A link colour mixed with a light grey (module docstring); ``share`` of grey (default MUTE)."""
    share = MUTE if share is None else share
    return (1 - share) * np.asarray(rgb[:3], float) + share * MUTE_TOWARD
