r"""The conditions a control loop runs under inside one Python process, each one separately switchable,
and the per-tick probes that say where a late tick's time went.

**Where a tick's wall time goes.** ``latency = cpu + wait + other``:

- ``cpu``, the time the guest's kernel counts as the tick thread's run time (``time.thread_time``):
  the computation, and what is ours besides -- a garbage collection, page faults (``ru_minflt`` /
  ``ru_majflt`` of ``getrusage(RUSAGE_THREAD)``), a first call's compile or cache load -- but also,
  on a virtual machine, time during which the host held the virtual CPU (steal) and interrupts,
  wherever the kernel does not account them apart: a tick with no involuntary switch, no fault and
  no collection whose ``cpu`` is many times the usual was not computing;
- ``wait``, the time the thread was runnable but waited on the run queue (``run_delay`` of
  ``/proc/thread-self/schedstat``) while another thread ran: the machine's other processes;
- ``other``, the rest: blocked (I/O of a major fault), interrupts accounted apart.

:class:`Probe` reads those counters around each tick (``os.pread`` of the open schedstat file and one
``getrusage``: a few microseconds, outside the timed part of the tick).

**The conditions** (:class:`Conditions`, entered around the loop and undone afterwards):

- ``gc``: ``"on"`` (Python's default thresholds: a generation-0 collection every 700 net container
  allocations, a full one now and then, mid-tick); ``"off"`` (collected once before the loop, then
  disabled); ``"freeze"`` (collected, then every surviving object moved to the permanent generation
  (``gc.freeze``) and the collector disabled; between ticks the young generation is collected when
  the period has at least ``gc_slack_s`` left, so that cyclic garbage made by the ticks does not
  accumulate; a collection then traverses only the objects made since the freeze).
- ``cpu``: pin the loop's thread to that core (``os.sched_setaffinity``): no migration between cores
  (caches stay warm), but the scheduler can no longer move the loop to the other core when this one
  is busy.
- ``fifo_priority``: the real-time scheduling class ``SCHED_FIFO`` (Linux, with the permission): the
  guest's scheduler then preempts the loop only for a higher real-time priority (kernel threads,
  interrupts); the previous class is restored afterwards.
- ``lock_memory``: ``mlockall(MCL_CURRENT | MCL_FUTURE)`` (libc): every mapped page resident and
  locked, future ones too, so that no page fault of the loop waits for the disk; unlocked afterwards.

**Pacing** (:func:`wait_until`): tick ``k`` starts at ``start + k dt``. The thread sleeps until
``spin_s`` before that instant and then polls the clock: a sleep wakes up late by the timer slack
and the scheduler's wake-up latency (tens to hundreds of microseconds), polling spends the CPU it
waits on (in the time-sharing class, the loop's share of it).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import os
import resource
import time

from ..exceptions import ProblemError

GC_MODES = ("on", "off", "freeze")
_MCL_CURRENT, _MCL_FUTURE = 1, 2


class Probe:
    """Per-thread counters read around each tick (module docstring); ``available`` is false where the
    kernel does not expose them (then :meth:`read` returns zeros)."""

    def __init__(self):
        try:
            self._fd = os.open("/proc/thread-self/schedstat", os.O_RDONLY)
        except OSError:
            self._fd = None
        self._thread = getattr(resource, "RUSAGE_THREAD", resource.RUSAGE_SELF)
        self.available = self._fd is not None
        self.collections = 0  # garbage collections started so far (while this probe is open)
        gc.callbacks.append(self._count)

    def _count(self, phase, info) -> None:
        if phase == "start":
            self.collections += 1

    def read(self) -> tuple[int, int, int, int]:
        """``(run-queue wait in ns, involuntary context switches, page faults, garbage collections)``
        of this thread so far."""
        wait = int(os.pread(self._fd, 96, 0).split()[1]) if self._fd is not None else 0
        ru = resource.getrusage(self._thread)
        return wait, ru.ru_nivcsw, ru.ru_minflt + ru.ru_majflt, self.collections

    def close(self) -> None:
        if self._count in gc.callbacks:
            gc.callbacks.remove(self._count)
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def wait_until(target: float, spin_s: float = 0.0) -> None:
    """Return at ``target`` (``time.perf_counter``): sleep until ``spin_s`` before it, then poll."""
    rest = target - time.perf_counter()
    if rest > spin_s:
        time.sleep(rest - spin_s)
    while time.perf_counter() < target:
        pass


class Conditions:
    """The loop's conditions (module docstring) as a context manager: entered before the first tick,
    undone after the last (also on an error).

    Args:
        gc: ``"on"``, ``"off"`` or ``"freeze"``; ``gc_slack_s``: the period's time left at which a
            frozen loop collects its young generation between ticks.
        cpu: the core to pin the thread to (``None``: as it was).
        fifo_priority: ``SCHED_FIFO`` priority 1-99 (``None``: as it was).
        lock_memory: lock every page (``mlockall``).

    Raises:
        ProblemError: an unknown ``gc`` mode, or a condition the system refuses (named, with its reason).
    """

    def __init__(self, gc: str = "freeze", gc_slack_s: float = 3e-4, cpu: int | None = None,
                 fifo_priority: int | None = None, lock_memory: bool = False):
        if gc not in GC_MODES:
            raise ProblemError(f"gc: expected one of {GC_MODES}, got {gc!r}")
        self.gc, self.gc_slack_s = gc, float(gc_slack_s)
        self.cpu, self.fifo_priority, self.lock_memory = cpu, fifo_priority, bool(lock_memory)
        self.collections = 0  # young-generation collections between ticks (gc="freeze")
        self._undo = []

    def __enter__(self) -> "Conditions":
        try:
            self._enter_gc()
            if self.cpu is not None:
                self._enter_affinity()
            if self.lock_memory:
                self._enter_mlock()
            if self.fifo_priority is not None:  # last: the set-up above runs in the normal class
                self._enter_fifo()
        except BaseException:
            self.__exit__(None, None, None)
            raise
        return self

    def __exit__(self, *exc) -> None:
        while self._undo:
            self._undo.pop()()

    def between_ticks(self, slack_s: float) -> None:
        """Collect the young generation when frozen and ``slack_s`` (the period's time left) allows."""
        if self.gc == "freeze" and slack_s >= self.gc_slack_s and gc.get_count()[0] > 0:
            gc.collect(0)
            self.collections += 1

    def _enter_gc(self) -> None:
        was = gc.isenabled()
        gc.collect()
        if self.gc == "on":
            gc.enable()
        else:
            gc.disable()
            if self.gc == "freeze":
                gc.freeze()
                self._undo.append(gc.unfreeze)
        self._undo.append(gc.enable if was else gc.disable)

    def _enter_affinity(self) -> None:
        try:
            previous = os.sched_getaffinity(0)
            os.sched_setaffinity(0, {int(self.cpu)})
        except (AttributeError, OSError, ValueError) as exc:
            raise ProblemError(f"cpu: cannot pin the loop to core {self.cpu!r}: {exc}") from None
        self._undo.append(lambda: os.sched_setaffinity(0, previous))

    def _enter_fifo(self) -> None:
        try:
            previous = (os.sched_getscheduler(0), os.sched_getparam(0))
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(int(self.fifo_priority)))
        except (AttributeError, OSError, ValueError) as exc:
            raise ProblemError(f"fifo_priority: cannot run the ticks in SCHED_FIFO at priority "
                               f"{self.fifo_priority!r}: {exc}") from None
        self._undo.append(lambda: os.sched_setscheduler(0, *previous))

    def _enter_mlock(self) -> None:
        name = ctypes.util.find_library("c")
        libc = ctypes.CDLL(name, use_errno=True) if name else None
        if libc is None or libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) != 0:
            err = os.strerror(ctypes.get_errno()) if libc is not None else "no C library"
            raise ProblemError(f"lock_memory: mlockall refused: {err}")
        self._undo.append(libc.munlockall)
