"""What every solver peer of ``bench_id.py`` and ``scaling.py`` shares: the interface and the bounds.

A peer solves one instant's :class:`~mcdm_pin.problem.QPData`
``min 1/2 f^T P f + c^T f  s.t.  A f = b,  lb <= f <= ub,  f in every stability cone`` and returns the
cable forces ``f`` (m,) in N, or ``None`` when it gives no answer (``message`` then says why).

- ``reset()`` forgets the previous instant (cold: every instant alone);
- ``solve(qp)`` solves one instant; between two ``reset()`` calls it may start from the previous
  instant's answer or active set (warm), as far as the library supports it (``warm`` says how);
- ``prepare(qp)`` runs once per case outside the timing (nothing to do for these peers);
- ``cones``: whether the peer takes second-order cones (case 3); a QP-only peer is not asked there.
"""

from __future__ import annotations

import numpy as np

BIG = 1e30  # an infinite bound for libraries that want finite numbers (DAQP's own infinity)


class Peer:
    name = "peer"
    label = "peer"
    cones = False  # takes second-order cones (case 3)
    warm = "none"  # what a warm solve reuses from the previous instant
    message = ""  # why the last failed solve failed

    def reset(self):
        """Forget the previous instant."""

    def prepare(self, qp):
        """Called once per case with a representative problem, outside the timing."""

    def solve(self, qp):
        """Cable forces (m,) or None (no answer)."""
        raise NotImplementedError


def finite_bounds(qp) -> tuple[np.ndarray, np.ndarray]:
    """``(lb, ub)`` with infinite bounds replaced by -+``BIG``."""
    return np.maximum(qp.lb, -BIG), np.minimum(qp.ub, BIG)


def fail(peer, why: str):
    """Record why ``peer`` gave no answer; returns None."""
    peer.message = why
    return None
