r"""No silent wait for numba: the compiled kernels are loaded from numba's cache, or compiled in a
detached background process while this run uses the uncompiled path.

numba compiles a kernel on its first call with given argument types (about a minute for all of this
library's kernels on 2 cores) and caches it on disk (``__pycache__`` beside the module, or
``NUMBA_CACHE_DIR``). So that nobody waits for that without being told:

- every module with kernels registers the calls that use them (:func:`register`: a function
  returning ``(kernel, example_args)`` pairs with the argument types the library passes);
- :func:`prepare` (called when an :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` is created)
  loads every registered kernel from the cache when all are there (about a second: docs/speed.md, "First run") and reports
  :func:`ready`; when one is missing, it starts **one** detached background process
  (``python -m mcdm_pin.jit``, a lock file makes a second one wait and then find the cache filled)
  that compiles and caches them, prints one line on stderr saying so, and this run uses the
  uncompiled path: the numpy cable terms and the ProxQP/Clarabel stages (the compiled stages skip
  themselves while :func:`ready` is false). Later runs load the cache.

numba invalidates a cached kernel when *its own* source file changes, not when a kernel it calls
in another module does (``_fast.py``'s kernels call ``_kkt.py``'s): after such an edit (a ``git
pull``, an upgrade in place) the cache would serve the old code. So the cache carries a stamp, the
digest of every kernel module's source and of ``tolerances.py``, whose constants some kernels read
when compiled (:func:`sources_digest`); a cache whose stamp differs is flushed (numba's own ``flush``
of every kernel's index) and compiled again.

The policy is ``MCDM_PIN_JIT`` (or ``prepare(policy=...)``): ``background`` (default), ``wait``
(compile in this process, with a note: tests and benchmarks use it), ``off`` (never compile here:
uncompiled path only, the cache is used when complete).
"""

from __future__ import annotations

import hashlib
import importlib
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

MODULES = ("mcdm_pin.model.kernels", "mcdm_pin.model.route_kernels", "mcdm_pin.solvers.ipm")  # modules that register kernels
POLICIES = ("background", "wait", "off")

_REGISTRY: dict[str, object] = {}  # name -> callable returning [(dispatcher, args), ...]
_READY = False
_STARTED = False


def register(name: str, calls) -> None:
    """Register ``calls()`` -> list of ``(kernel, args)``: each kernel (a numba dispatcher) called with
    example arguments of exactly the types the library passes."""
    _REGISTRY[name] = calls


def ready() -> bool:
    """Whether the compiled kernels are available in this process."""
    return _READY


_KERNEL_MODULES: dict = {}


def kernels(module: str):
    """The kernels' module ``mcdm_pin.<module>`` (``"model.kernels"``, ``"solvers._fast"``), imported
    on first use (they import numba, which ``import mcdm_pin`` does not) and then looked up: an
    ``import`` inside a function costs ~1 us on every call, and the per-instant hot path calls
    several."""
    mod = _KERNEL_MODULES.get(module)
    if mod is None:
        mod = _KERNEL_MODULES[module] = importlib.import_module(f"mcdm_pin.{module}")
    return mod


def _lock_path() -> Path:
    return Path(tempfile.gettempdir()) / f"mcdm_pin_jit_{os.getuid() if hasattr(os, 'getuid') else 0}.lock"


def _all_calls():
    for mod in MODULES:
        importlib.import_module(mod)
    return [call for name in sorted(_REGISTRY) for call in _REGISTRY[name]()]


def _load_cached(disp, args) -> bool:
    """Load ``disp``'s specialisation for ``args`` from numba's cache without compiling; whether it
    is available (numba's own ``Dispatcher.compile`` cache branch)."""
    argtypes = tuple(disp.typeof_pyval(a) for a in args)
    if argtypes in disp.overloads:
        return True
    cres = disp._cache.load_overload(argtypes, disp.targetctx)
    if cres is None:
        return False
    disp._cache_hits[argtypes] += 1
    if not cres.objectmode:
        disp.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
    disp.add_overload(cres)
    return True


def kernel_sources() -> list[Path]:
    """The package's source files that define numba kernels (those that import numba's ``njit``),
    and ``tolerances.py``: kernels read some of its constants when they are compiled
    (``UNIQUE_PENALTY``, ``IPM_START_BOX_WEIGHT``), so a changed constant must recompile them too."""
    root = Path(__file__).resolve().parent
    pattern = re.compile(r"^from numba import .*\bnjit\b", re.M)
    found = {p for p in root.rglob("*.py") if pattern.search(p.read_text(encoding="utf-8"))}
    return sorted(found | {root / "tolerances.py"})


def sources_digest(paths=None) -> str:
    """sha256 over the names and bytes of ``paths`` (default: :func:`kernel_sources`)."""
    h = hashlib.sha256()
    for p in (kernel_sources() if paths is None else paths):
        h.update(Path(p).name.encode() + b"\0" + Path(p).read_bytes() + b"\0")
    return h.hexdigest()


STAMP = "mcdm_pin_kernels.sha256"  # the stamp's file name, in the kernels' cache folder


def _dispatchers():
    """Every numba dispatcher of the kernel modules (registered or called by registered ones)."""
    _all_calls()
    sources = set(kernel_sources())  # (reads the package's files: once, not per module)
    out = []
    for name, mod in list(sys.modules.items()):
        path = getattr(mod, "__file__", None)
        if not (name.startswith("mcdm_pin.") and path and Path(path).resolve() in sources):
            continue
        out += [v for v in vars(mod).values() if getattr(v, "_cache", None) is not None
                and hasattr(v, "py_func") and v.py_func.__module__ == name]
    return out


def _stamp_path(disps) -> Path | None:
    for d in disps:
        try:
            return Path(d._cache.cache_path) / STAMP
        except Exception:  # noqa: BLE001 - no cache folder for this kernel: try the next
            continue
    return None


def stamp_current() -> bool:
    """Whether the cache's stamp equals the sources' digest; if not, flush every kernel's cache
    index (the next load finds nothing and the kernels are compiled again)."""
    disps = _dispatchers()
    path = _stamp_path(disps)
    if path is None:
        return True  # no cache at all: numba compiles in memory, nothing can be stale
    try:
        if path.is_file() and path.read_text().strip() == sources_digest():
            return True
    except OSError:
        pass
    for d in disps:
        try:
            d._cache.flush()
        except Exception:  # noqa: BLE001 - an unwritable cache: numba then compiles in memory
            pass
    return False


def _write_stamp() -> None:
    path = _stamp_path(_dispatchers())
    if path is None:
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(sources_digest() + "\n")
    except OSError:
        pass  # an unwritable cache folder: nothing is cached there either


def cached() -> bool:
    """Whether every registered kernel can be loaded from the cache (loads those that can); a cache
    stamped for other kernel sources is flushed first and is not."""
    try:
        calls = _all_calls()
        if not stamp_current():
            return False
        return bool(calls) and all([_load_cached(disp, args) for disp, args in calls])
    except Exception:  # noqa: BLE001 - numba internals changed: treat as not cached
        return False


def compile_now() -> None:
    """Compile (or load) every registered kernel in this process, blocking, and stamp the cache."""
    global _READY
    for disp, args in _all_calls():
        disp(*args)
    _write_stamp()
    _READY = True


def _background_running() -> bool:
    import fcntl

    path = _lock_path()
    try:
        with open(path, "a") as fh:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                return True
            fcntl.flock(fh, fcntl.LOCK_UN)
    except OSError:
        return False
    return False


def _start_background() -> bool:
    """Start the detached compiling process unless one runs already; whether one runs now."""
    global _STARTED
    if _STARTED or _background_running():
        return True
    log = Path(tempfile.gettempdir()) / "mcdm_pin_jit.log"
    try:
        with open(log, "a") as out:
            subprocess.Popen([sys.executable, "-c", "import sys; from mcdm_pin import jit; sys.exit(jit._main())"],
                             stdin=subprocess.DEVNULL, stdout=out,
                             stderr=out, start_new_session=True, env=dict(os.environ), close_fds=True)
    except OSError:
        return False
    _STARTED = True
    return True


def prepare(policy: str | None = None, quiet: bool = False) -> bool:
    """Make the compiled kernels available if they can be without waiting (see the module
    docstring); returns :func:`ready`."""
    global _READY
    if _READY:
        return True
    policy = policy or os.environ.get("MCDM_PIN_JIT", "background")
    if policy not in POLICIES:
        policy = "background"
    if cached():
        _READY = True
        return True
    if policy == "wait":
        if not quiet:
            print("mcdm-pin: compiling the numba kernels (once per machine, about a minute)...",
                  file=sys.stderr, flush=True)
        compile_now()
        return True
    if policy == "background" and _start_background() and not quiet:
        print("mcdm-pin: compiling the numba kernels in the background (once per machine, about a "
              "minute; log: " + str(Path(tempfile.gettempdir()) / "mcdm_pin_jit.log") + "); this run "
              "uses the uncompiled path", file=sys.stderr, flush=True)
    return False


def _main(argv=None) -> int:
    """The background process: compile under the lock, then exit (``--list``: print how many kernel
    specialisations are registered and whether the cache holds them all, compile nothing)."""
    import fcntl

    if "--list" in (sys.argv[1:] if argv is None else argv):
        print(f"{len(_all_calls())} kernel specialisations registered; cached: {cached()}", flush=True)
        return 0

    with open(_lock_path(), "a") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        t0 = time.perf_counter()
        if not cached():
            compile_now()
        print(f"mcdm-pin: kernels ready in {time.perf_counter() - t0:.1f} s (pid {os.getpid()})", flush=True)
        fcntl.flock(fh, fcntl.LOCK_UN)
    return 0


if __name__ == "__main__":
    # run the package's module, not this __main__ copy: the kernel modules register into
    # mcdm_pin.jit's registry, which this copy does not see (with its own empty registry the
    # background process found "everything cached" and compiled nothing: every later run on a new
    # machine stayed on the uncompiled path)
    from mcdm_pin import jit as _jit

    sys.exit(_jit._main())
