"""Finite differences shared by the tests."""

from __future__ import annotations

import numpy as np


def lengths_jacobian(lengths_at, q, h: float = 1e-6) -> np.ndarray:
    """Central differences of the cable lengths, ``(m, nv)``: ``lengths_at(q)`` returns the lengths.

    The error is O(h^2 |l'''|) ~ 1e-12 from truncation plus ~ eps |l| / h ~ 1e-10 from rounding."""
    q = np.asarray(q, dtype=float)
    columns = []
    for i in range(len(q)):
        e = np.zeros(len(q))
        e[i] = h
        columns.append((lengths_at(q + e) - lengths_at(q - e)) / (2 * h))
    return np.stack(columns, axis=1)
