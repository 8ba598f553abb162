"""The solver peers by name (``--peers`` of ``bench_id.py`` and ``scaling.py``), and ``all`` of them.

Each peer is one small module with the interface of :mod:`.base`; a peer whose library is missing is
skipped with the install command.
"""

from __future__ import annotations

from importlib import import_module

# name: (module, class, install command); "all" runs them in this order
SOLVER_PEERS = {
    "daqp": ("daqp_", "DaqpPeer", "pip install daqp"),
    "piqp": ("piqp_", "PiqpPeer", "pip install piqp"),
    "proxqp": ("proxqp_", "ProxqpPeer", "pip install proxsuite"),
    "qoco": ("qoco_", "QocoPeer", "pip install qoco"),
    "clarabel": ("clarabel_", "ClarabelPeer", "pip install clarabel"),
}
ALL = tuple(SOLVER_PEERS)


def peer_class(name: str):
    module, cls, _ = SOLVER_PEERS[name]
    return getattr(import_module(f"{__package__}.{module}"), cls)


def make_solver_peers(names) -> tuple[list, list[str]]:
    """(peers, notes): one instance per installed peer; a note with the install command per missing one."""
    peers, notes = [], []
    for name in names:
        try:
            peers.append(peer_class(name)())
        except ImportError as e:
            notes.append(f"{name}: skipped, not installed ({e.name or e}); install with: "
                         f"{SOLVER_PEERS[name][2]}")
    return peers, notes


def expand(names) -> list[str]:
    """``all`` -> every solver peer (in :data:`ALL`'s order); other names kept, duplicates dropped."""
    out = []
    for n in names:
        for m in (ALL if n == "all" else (n,)):
            if m not in out:
                out.append(m)
    return out
