"""One BLAS thread while solving: each loaded BLAS library's own thread-count setter, set on the way
into a solve and restored on the way out (:class:`BlasLimit`, :meth:`InverseDynamics.blas_limit
<mcdm_pin.inverse_dynamics.InverseDynamics.blas_limit>`).

The matrices of one instant are small, and waking BLAS worker threads costs milliseconds on a loaded
machine (docs/speed.md); the limit applies only inside a solve and is lifted afterwards.
"""

from __future__ import annotations

import scipy.linalg  # noqa: F401  (scipy's BLAS is loaded too, so that it is limited as well)
from threadpoolctl import ThreadpoolController

_CONTROLLER = None  # threadpoolctl's view of the BLAS libraries, made once
_BLAS_SETTERS = None  # blas_setters(), listed once


class BlasLimit:
    """``InverseDynamics.blas_limit``'s context: each BLAS library's own setter, its count restored on
    the way out (also after an exception; entries nest). A class, not a generator: it is entered at
    every ``InverseDynamics.solve``, where threadpoolctl's ``limit()`` asks every library for its
    whole description and a generator around the setters costs more than the setters; this calls the
    libraries' own functions (:func:`blas_setters`)."""

    __slots__ = ("threads", "depth", "changed")

    def __init__(self):
        self.threads = None
        self.depth = 0
        self.changed = []

    def __enter__(self):
        if self.depth == 0 and self.threads is not None:
            try:
                for get, set_ in blas_setters():
                    old = get()
                    if old != self.threads:
                        set_(self.threads)
                        self.changed.append((set_, old))
            except BaseException:
                self._restore()
                raise
        self.depth += 1
        return self

    def __exit__(self, *exc) -> bool:
        self.depth -= 1
        if self.depth == 0:
            self._restore()
        return False

    def _restore(self) -> None:
        changed = self.changed
        while changed:
            set_, old = changed.pop()
            set_(old)



def blas_setters():
    """``(get, set)`` of each loaded BLAS library's thread count (listed once): OpenBLAS's own C
    functions where threadpoolctl names them (``openblas_get_num_threads``, ``..._set_...`` with the
    library's symbol affixes, its pthreads build: one process-wide count), else threadpoolctl's
    methods. The C functions skip threadpoolctl's check of which Python thread controls OpenBLAS;
    the limit is set and restored within one call, so two threads solving at once with the same
    ``blas_threads`` only run each other's BLAS calls at the limit meanwhile and leave the count as
    they found it (with different limits at once, the last to leave restores what it found, which
    may be the other's limit: as before, threadpoolctl's own setters did not order them either). A
    call through ctypes costs a fraction of threadpoolctl's, which took an eighth of a cold instant's
    Python on the neck."""
    global _BLAS_SETTERS
    if _BLAS_SETTERS is None:
        out = []
        for lib in _blas_controller().select(user_api="blas").lib_controllers:
            get = set_ = None
            symbol = getattr(lib, "_get_symbol", None)
            if getattr(lib, "internal_api", "") == "openblas" and getattr(lib, "threading_layer", "") == "pthreads" \
                    and symbol is not None:
                get, set_ = symbol("openblas_get_num_threads"), symbol("openblas_set_num_threads")
            out.append((get, set_) if get is not None and set_ is not None else (lib.get_num_threads,
                                                                                 lib.set_num_threads))
        _BLAS_SETTERS = tuple(out)
    return _BLAS_SETTERS



def _blas_controller():
    """threadpoolctl's view of the loaded BLAS libraries (made once: it scans them, ~1.5 ms)."""
    global _CONTROLLER
    if _CONTROLLER is None:
        _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


__all__ = ["BlasLimit", "blas_setters"]
