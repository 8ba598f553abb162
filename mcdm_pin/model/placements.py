"""Strided numpy views of a Pinocchio ``Data`` vector (``data.oMi``, ``data.oMf``, ``data.f``): every
element's array at once, so that an instant gathers the rows it needs in one indexing operation
instead of asking each element for its array.

The vectors are ``std::vector``'s of fixed-size Eigen objects: their elements sit at one fixed stride
in memory, and a ``pin.Data`` never resizes them. The view's layout is read from the element views
eigenpy gives (their addresses and strides) and checked against their values when it is made; the
view is valid while the ``Data`` lives (keep a reference to it next to the view).
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..exceptions import ModelError


def stacked_view(vector, n: int, part) -> np.ndarray:
    """``(n, *shape)`` read-only view of ``part(vector[j])`` for ``j < n`` (``part``: the element's
    numpy view, e.g. ``lambda M: M.rotation``), following every update of ``vector``'s elements.

    Raises ModelError when the elements' views do not lie at one stride (not a contiguous vector)."""
    views = [part(vector[j]) for j in range(n)]
    addr = np.array([v.__array_interface__["data"][0] for v in views], dtype=np.int64)
    first = views[0]
    stride = int(addr[1] - addr[0]) if n > 1 else first.nbytes
    span = stride * (n - 1) + max(s * (k - 1) for s, k in zip(first.strides, first.shape)) + first.itemsize
    if n < 1 or stride <= 0 or not np.array_equal(addr, addr[0] + stride * np.arange(n)) \
            or any(v.strides != first.strides or v.dtype != np.float64 for v in views):
        raise ModelError("Pinocchio's data vector does not lie at one stride in memory")
    base = np.frombuffer((ctypes.c_double * (span // 8)).from_address(int(addr[0])), dtype=float)
    out = np.lib.stride_tricks.as_strided(base, shape=(n, *first.shape), strides=(stride, *first.strides),
                                          writeable=False)
    if not all(np.array_equal(out[j], views[j]) for j in range(n)):
        raise ModelError("Pinocchio's data vector does not lie at one stride in memory")
    return out
