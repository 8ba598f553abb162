r"""One execution path: the library's numba kernels run compiled when an explicit compile has cached
them, and as the very same Python functions (their ``py_func``) until then.

numba compiles a kernel on its first call with given argument types (about 160 s of CPU for all
of this library's kernels, docs/speed.md "First run") and caches it on disk (``__pycache__`` beside the module, or under
``NUMBA_CACHE_DIR``). Nothing here compiles behind the user's back:

- every module with kernels registers the calls that use them (:func:`register`: a function
  returning ``(kernel, example_args)`` pairs with the argument types the library passes);
- :func:`compile_now` (the ``mcdm-pin compile`` command, or ``MCDM_PIN_JIT=compile``) compiles every
  registered kernel, with a note on stderr, and then writes a *stamp*. The entry points are split
  between :func:`compile_workers` processes (:func:`compile_plan`: the calling one and workers started
  for the compile alone), which share numba's on-disk cache (one file per kernel and specialisation,
  each written whole by a rename); the calling process then calls every entry point once more, which
  loads what the workers cached (and compiles anything they did not);
- :func:`prepare` (called when an :class:`~mcdm_pin.inverse_dynamics.InverseDynamics` is created)
  loads the compiled kernels from numba's cache when the stamp is current (1.5 s here), and
  otherwise leaves them uncompiled, with one note on stderr saying how to compile them.

Either way :func:`kernels` hands out the same functions: the numba dispatchers once compiled, else
copies of their Python functions whose globals name the other kernels' Python functions (so an
uncompiled kernel never triggers a compile of the kernels it calls). The answers are those of the
same code, to rounding (``fastmath`` reassociation in two modules, docs/speed.md).

The stamp (:data:`STAMP`, in the cache folder of the kernels) holds the digest of every kernel
module's source (no kernel reads a setting when compiled: :class:`~mcdm_pin.settings.Settings`' values
are arguments), the ``(mtime, size)`` of each kernel source (numba's own cache key: a touched file would make numba
recompile on load), and the numba and Python versions. It is removed before a compile starts and
written, by an atomic rename, only after every kernel is compiled and cached (every worker ended
well and the final pass loaded every entry point): a compile that is interrupted, or still running,
or whose worker failed, leaves no stamp, and runs meanwhile stay uncompiled. numba
invalidates a cached kernel only when *its own* file changes, not a kernel it calls in another module,
so a compile whose stamp is stale first flushes every kernel's cache (``Dispatcher.recompile`` on
dispatchers without overloads: numba's public flush). Concurrent compiles of one install take a lock
file in that same cache folder (``fcntl``, where the platform has it): another install, with its
own cache folder, never waits on it.

The policy is ``MCDM_PIN_JIT`` (or ``prepare(policy=...)``): ``auto`` (default: load when stamped,
else uncompiled), ``compile`` (``wait`` is a synonym: compile in this process when not stamped;
tests and benchmarks use it), ``off`` (uncompiled, even when stamped).

numba is the ``numba`` extra. The kernel modules take ``njit`` and ``extending`` from here: numba's
when it is installed, else stand-ins that keep each function as its Python code (:class:`PyKernel`),
so that the library loads and answers on the uncompiled path without numba; compiling then raises
:class:`~mcdm_pin.exceptions.MissingPackageError` naming the extra.
"""

from __future__ import annotations

import functools
import hashlib
import importlib
import os
import platform
import re
import sys
import time
import types
from pathlib import Path

from .exceptions import MissingPackageError, SolverError
from .extras import install_hint

try:  # POSIX: the compile lock; elsewhere concurrent compiles each write numba's files atomically
    import fcntl
except ImportError:  # pragma: no cover - Windows
    fcntl = None

try:  # the compiled path (the numba extra); without it the kernels stay Python (module docstring)
    import numba
    from numba import extending, njit
except ImportError:
    numba = None

    class PyKernel:
        """A kernel without numba: its Python function (``py_func``), called as it is."""

        def __init__(self, f):
            self.py_func = f
            functools.update_wrapper(self, f)

        def __call__(self, *args, **kwargs):
            return self.py_func(*args, **kwargs)

        def recompile(self):  # (what _dispatchers' users call on numba's dispatchers)
            pass

        stats = None

    def njit(*args, **options):
        """numba's ``njit`` without numba: the function as a :class:`PyKernel`."""
        if len(args) == 1 and callable(args[0]) and not options:
            return PyKernel(args[0])
        return PyKernel

    extending = types.SimpleNamespace(register_jitable=lambda f=None, **options: f if f is not None
                                      else (lambda g: g))

MODULES = ("mcdm_pin.model.kernels", "mcdm_pin.model.coupling_kernels", "mcdm_pin.model.route_kernels",
           "mcdm_pin.model.scale_kernels", "mcdm_pin.model.muscle_kernels", "mcdm_pin.model.bezier_kernels",
           "mcdm_pin.model.actuated_kernels", "mcdm_pin.osim.loop_kernels",
           "mcdm_pin.solvers.ipm")  # modules that register kernels
POLICIES = ("auto", "compile", "wait", "off")
STAMP = "mcdm_pin_kernels.stamp"  # the stamp's file name, in the kernels' cache folder
LOCK = "mcdm_pin_kernels.lock"  # the compile lock's file name, beside the stamp
WORKERS_ENV = "MCDM_PIN_COMPILE_WORKERS"  # how many processes compile (default: the usable cores)
COMPILE_COST = {"mcdm_pin.solvers._fast.ipm_answer": 115.0, "mcdm_pin.solvers._fast.active_set_answer": 125.0,
                "mcdm_pin.model.route_kernels.osim_route_pass": 34.5, "mcdm_pin.solvers._unique.face_setup": 19.7,
                "mcdm_pin.model.route_kernels.route_pass": 9.3, "mcdm_pin.model.kernels.scale_factors": 8.4,
                "mcdm_pin.solvers._dual_guess.dual_guess": 6.0, "mcdm_pin.model.scale_kernels.scale_instant": 5.8,
                "mcdm_pin.model.kernels.cable_terms": 4.4, "mcdm_pin.solvers._fast.kkt_measures": 4.1,
                "mcdm_pin.model.actuated_kernels.actuated_arrays": 3.3}
"""CPU seconds of each entry point's compile in a two-process compile into an empty cache
(docs/speed.md, "A new machine", gives the runs): :func:`compile_plan` splits the entry points
between the processes by them. ``active_set_answer``'s includes the active-set solver, which the
other process's ``ipm_answer`` then loads from the cache, so ``ipm_answer``'s is its compile without
it. Only their ratios and :data:`COMPILE_LEAD`, in the same seconds, matter."""
COMPILE_ANCHOR = "mcdm_pin.solvers._fast.ipm_answer"
"""The entry point that the calling process compiles after its lead (:func:`compile_plan`): the
interior-point method, whose machine code, and so whose answers, depend on what its process
compiled before it."""
COMPILE_LEAD = 60.0
"""Seconds (of :data:`COMPILE_COST`) of the registry's first entry points that the calling process
compiles before :data:`COMPILE_ANCHOR` (:func:`compile_plan`). ``ipm_answer`` reaches the active-set
solver it shares with ``active_set_answer`` part-way through its compile; with this lead, the
process that compiles ``active_set_answer`` first has usually cached that solver by then, and the
calling process loads it instead of compiling it a second time (docs/speed.md, "A new machine",
gives the timings). It is a race, not a wait:
where the solver is not cached yet, the calling process compiles it too, which costs time but not
bits (a compile in one process, in the same order, gives the same answers; docs/speed.md, "A new
machine")."""
_CHILD_CODE = "import sys; from mcdm_pin import jit; jit._child_main(sys.argv[1:])"  # a worker's program
LAST_COMPILE: dict = {}
"""The last compile of this process (:func:`compile_now`): ``entries`` (name, wall s, CPU s, worker;
worker 0 is this process), ``workers``, ``wall``, ``cpu`` (this process and the workers) and
``load_wall``, ``load_cpu`` (the final pass that loads every entry point here)."""
UNCOMPILED_SLOWDOWN = 1000.0
"""How many times longer the uncompiled kernels may take than the compiled ones: the factor by which
:class:`~mcdm_pin.inverse_dynamics.InverseDynamics` stretches a solver's time budget while they run
(the measured ratios are in docs/speed.md, "Before `mcdm-pin compile`")."""

_REGISTRY: dict[str, object] = {}  # name -> callable returning [(dispatcher, args), ...]
_READY = True  # the kernels answer (tests set it False to reach the numpy references they check against)
_COMPILED = False  # the compiled kernels are loaded in this process
_NOTED = False  # the "uncompiled" note was printed
_PURE: dict[str, types.ModuleType] = {}  # "model.kernels" -> the module's uncompiled twin namespace
_LOADED: dict[str, types.ModuleType] = {}  # "model.kernels" -> the module, once the compiled kernels are loaded


def register(name: str, calls) -> None:
    """Register ``calls()`` -> list of ``(kernel, args)``: each kernel (a numba dispatcher) called with
    example arguments of exactly the types the library passes."""
    _REGISTRY[name] = calls


def ready() -> bool:
    """Whether the kernels answer (compiled or not: :func:`compiled`). Always, except where a test
    switches them off to compare them with the numpy references."""
    return _READY


def compiled() -> bool:
    """Whether the compiled kernels are loaded in this process."""
    return _COMPILED


def kernels(module: str):
    """The kernels of ``mcdm_pin.<module>`` (``"model.kernels"``, ``"solvers._fast"``): the module
    itself when the compiled kernels are loaded, else its uncompiled namespace (the same functions'
    Python code, :func:`_pure_modules`)."""
    if _COMPILED:
        mod = _LOADED.get(module)
        if mod is None:
            mod = _LOADED[module] = importlib.import_module(f"mcdm_pin.{module}")
        return mod
    ns = _PURE.get(module)
    if ns is None:
        _pure_modules()
        ns = _PURE[module]
    return ns


@functools.lru_cache(maxsize=None)
def kernel_sources() -> tuple[Path, ...]:
    """The package's source files that define numba kernels (those that import numba's ``njit``, or
    ``extending`` for functions compiled inline into kernels) or the structures they take and return
    (a module with ``KERNEL_STRUCTURES``). No kernel reads a module constant of
    another file when compiled: the settings (:class:`~mcdm_pin.settings.Settings`) reach them as
    arguments, so a changed setting needs no recompile."""
    root = Path(__file__).resolve().parent
    # njit kernels, and register_jitable functions compiled inline into them (numba.extending)
    # (or that decorate with them, imported from another kernel module: wrapping_osim_ellipsoid.py),
    # and the named structures the kernels take and return (KERNEL_STRUCTURES: solvers/_structs.py)
    pattern = re.compile(r"^(from (numba(\.\w+)?|\.+jit) import .*\b(njit|extending|register_jitable)\b"
                         r"|@(njit|register_jitable|extending\.register_jitable)\b|KERNEL_STRUCTURES = )", re.M)
    found = {p for p in root.rglob("*.py") if pattern.search(p.read_text(encoding="utf-8"))}
    return tuple(sorted(found))


def sources_digest(paths=None) -> str:
    """sha256 over the names and bytes of ``paths`` (default: :func:`kernel_sources`)."""
    h = hashlib.sha256()
    for p in (kernel_sources() if paths is None else paths):
        h.update(Path(p).name.encode() + b"\0" + Path(p).read_bytes() + b"\0")
    return h.hexdigest()


def _kernel_modules() -> dict[str, types.ModuleType]:
    """The imported modules that define kernels, by name (importing the registering ones first)."""
    for mod in MODULES:
        importlib.import_module(mod)
    sources = set(kernel_sources())
    return {name: mod for name, mod in list(sys.modules.items())
            if name.startswith("mcdm_pin.") and getattr(mod, "__file__", None)
            and Path(mod.__file__).resolve() in sources}


def _is_kernel(v) -> bool:
    return hasattr(v, "py_func") and hasattr(v, "recompile") and hasattr(v, "stats")


def _dispatchers() -> list:
    """Every numba dispatcher defined in the kernel modules."""
    return [v for name, mod in _kernel_modules().items() for v in vars(mod).values()
            if _is_kernel(v) and v.py_func.__module__ == name]


def _pure_modules() -> None:
    """Fill :data:`_PURE`: for each kernel module, a namespace where every kernel is a copy of its
    Python function (``py_func``) whose globals name the other kernels' copies (and the other kernel
    modules' namespaces): the uncompiled path calls no dispatcher, so it compiles nothing."""
    mods = _kernel_modules()
    globs = {name: dict(vars(mod)) for name, mod in mods.items()}
    copies = {}
    for name, mod in mods.items():
        for v in vars(mod).values():
            if _is_kernel(v) and v.py_func.__module__ == name:
                f = v.py_func
                copies[id(v)] = types.FunctionType(f.__code__, globs[name], f.__name__, f.__defaults__,
                                                   f.__closure__)
    for g in globs.values():
        for key, v in list(g.items()):
            if _is_kernel(v) and id(v) in copies:
                g[key] = copies[id(v)]
    spaces = {}
    for name, g in globs.items():
        spaces[name] = types.ModuleType(name, f"uncompiled kernels of {name}")
        vars(spaces[name]).update(g)
    for name, g in globs.items():
        for key, v in list(g.items()):
            if isinstance(v, types.ModuleType) and v.__name__ in spaces:
                g[key] = spaces[v.__name__]
                setattr(spaces[name], key, spaces[v.__name__])
    quiet = {id(f): _quiet(f) for f in copies.values()}
    for name, ns in spaces.items():
        public = types.ModuleType(name, f"uncompiled kernels of {name}")
        vars(public).update({k: quiet.get(id(v), v) for k, v in vars(ns).items()})
        _PURE[name[len("mcdm_pin."):]] = public


def _quiet(f):
    """``f`` called under ``np.errstate(all="ignore")``: the compiled kernels use numba's
    ``error_model="numpy"`` (a division by zero gives inf or nan, silently), and so do their
    uncompiled copies (the calls between kernels stay direct)."""
    import numpy as np

    @functools.wraps(f)
    def call(*args):
        with np.errstate(all="ignore"):
            return f(*args)

    return call


def _all_calls():
    _kernel_modules()
    return [call for name in sorted(_REGISTRY) for call in _REGISTRY[name]()]


def entry_points() -> list[str]:
    """The registered kernels' names (``module.function``), one per compiled specialisation."""
    return [f"{d.py_func.__module__}.{d.py_func.__name__}" for d, _ in _all_calls()]


def cache_dir() -> Path | None:
    """The folder of numba's cache of this install's kernels (``Dispatcher.stats.cache_path``), where
    the stamp and the lock live; ``None`` when numba has no writable cache for them."""
    for d in _dispatchers():
        try:
            path = d.stats.cache_path
        except Exception:  # noqa: BLE001 - a dispatcher without a cache: try the next
            continue
        if path:
            return Path(path)
    return None


def stamp_text() -> str:
    """What the stamp of a complete compile of the current sources holds (see the module docstring)."""
    lines = [f"digest {sources_digest()}", f"numba {numba.__version__}",
             f"python {sys.version_info[0]}.{sys.version_info[1]} {platform.machine()}"]
    for p in kernel_sources():
        st = p.stat()
        lines.append(f"source {p.name} {st.st_mtime!r} {st.st_size}")
    return "\n".join(lines) + "\n"


def stamp_current() -> bool:
    """Whether the cache holds a complete compile of the current sources (its stamp equals
    :func:`stamp_text`)."""
    folder = cache_dir()
    try:
        return folder is not None and (folder / STAMP).read_text() == stamp_text()
    except OSError:
        return False


def _write_stamp(folder: Path) -> None:
    tmp = folder / f"{STAMP}.{os.getpid()}.tmp"
    try:
        tmp.write_text(stamp_text())
        os.replace(tmp, folder / STAMP)  # atomic: a reader sees no stamp or the whole one
    except OSError:
        pass  # an unwritable cache folder: numba caches nothing there either


def load() -> bool:
    """Load the compiled kernels from the cache when the stamp is current (each registered kernel
    called once on its example arguments: numba's cache then serves it); whether they are loaded."""
    global _COMPILED
    if _COMPILED:
        return True
    if numba is None or not stamp_current():
        return False
    for disp, args in _all_calls():
        disp(*args)
    _COMPILED = True
    return True


class _Lock:
    """An exclusive lock on ``folder / LOCK`` (none where ``fcntl`` is missing); says so when it
    waits."""

    def __init__(self, folder: Path | None, quiet: bool):
        self.path = None if folder is None or fcntl is None else folder / LOCK
        self.quiet = quiet
        self.fh = None

    def __enter__(self):
        if self.path is None:
            return self
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.fh = open(self.path, "a")
        except OSError:  # an unwritable cache folder: numba compiles in memory there, nothing to guard
            return self
        try:
            fcntl.flock(self.fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            if not self.quiet:
                print(f"mcdm-pin: another process compiles this install's kernels; waiting for it "
                      f"(lock: {self.path})", file=sys.stderr, flush=True)
            fcntl.flock(self.fh, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc):
        if self.fh is not None:
            fcntl.flock(self.fh, fcntl.LOCK_UN)
            self.fh.close()


def compile_workers() -> int:
    """How many processes :func:`compile_now` compiles in: ``MCDM_PIN_COMPILE_WORKERS`` when set (a
    positive integer), else the cores this process may run on."""
    text = os.environ.get(WORKERS_ENV, "").strip()
    if text:
        if not text.isdigit() or int(text) < 1:
            raise SolverError(f"{WORKERS_ENV}={text!r}: expected a positive integer (processes that "
                              f"compile the kernels)")
        return int(text)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - no sched_getaffinity (macOS, Windows)
        return max(1, os.cpu_count() or 1)


def compile_plan(names: list[str], workers: int) -> list[list[int]]:
    """The entry points' indices (``names`` in the registry's order) split into at most ``workers``
    groups, one per process. The first group, the calling process's, starts as a one-process compile
    does: the registry's first entry points in its order (the first module's whole, then more up to
    :data:`COMPILE_LEAD` seconds of :data:`COMPILE_COST`, 1 s for a name it lacks), then
    :data:`COMPILE_ANCHOR` (or, without it, the heaviest entry point). numba's code
    for a kernel depends on what its process compiled before it (a callee compiled earlier is linked
    as it was made then), and this order gives the interior-point method the machine code, and so
    the answers, bit for bit, of a compile in one process; the lead lets another process cache the
    active-set solver the two share first. The others go longest first, each to the least loaded
    group."""
    cost = [COMPILE_COST.get(n, 1.0) for n in names]
    if not names:
        return []
    anchor = names.index(COMPILE_ANCHOR) if COMPILE_ANCHOR in names else max(range(len(names)), key=cost.__getitem__)
    module = names[0].rsplit(".", 1)[0]
    first, lead = [], 0.0
    for i in range(anchor):
        if names[i].rsplit(".", 1)[0] != module and lead >= COMPILE_LEAD:
            break
        first.append(i)
        lead += cost[i]
    first.append(anchor)
    groups: list[list[int]] = [first] + [[] for _ in range(max(1, min(workers, len(names))) - 1)]
    load = [sum(cost[i] for i in first)] + [0.0] * (len(groups) - 1)
    for i in sorted(set(range(len(names))) - set(first), key=lambda i: (-cost[i], i)):
        k = min(range(len(groups)), key=load.__getitem__)
        groups[k].append(i)
        load[k] += cost[i]
    return [g for g in groups if g]


def _compile_group(calls, group) -> list[tuple[str, float, float]]:
    """Call (compile, and cache) the entry points ``group`` of ``calls``: ``(name, wall s, CPU s)``."""
    out = []
    for i in group:
        disp, args = calls[i]
        w, c = time.perf_counter(), time.process_time()
        disp(*args)
        out.append((_name(disp), time.perf_counter() - w, time.process_time() - c))
    return out


def _name(disp) -> str:
    f = getattr(disp, "py_func", disp)
    return f"{getattr(f, '__module__', '?')}.{getattr(f, '__name__', repr(f))}"


def _child_main(argv: list[str]) -> None:
    """A compile worker (:func:`_start_children`): compiles the entry points whose indices ``argv``
    names into numba's cache and prints one line per entry point, ``name wall cpu``, then
    ``total cpu``."""
    calls = _all_calls()
    for name, wall, cpu in _compile_group(calls, [int(a) for a in argv]):
        print(f"{name} {wall:.3f} {cpu:.3f}", flush=True)
    print(f"total {time.process_time():.3f}", flush=True)


def _start_children(groups, names):
    """One Python process per group (``_child_main``), importing this very package (its folder first on
    ``PYTHONPATH``), with numba's settings of this process (the same ``NUMBA_CACHE_DIR``)."""
    import subprocess  # the explicit compile step only: no library constructor starts a process

    root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, MCDM_PIN_JIT="off",
               PYTHONPATH=os.pathsep.join([root, *filter(None, [os.environ.get("PYTHONPATH")])]))
    return [(subprocess.Popen([sys.executable, "-c", _CHILD_CODE, *map(str, g)], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True), [names[i] for i in g]) for g in groups]


def _join_children(children) -> tuple[list, float]:
    """Wait for the workers: their per-entry ``(name, wall, cpu, worker)`` (workers from 1) and their
    total CPU seconds."""
    rows, cpu = [], 0.0
    for k, (proc, want) in enumerate(children, start=1):
        out, err = proc.communicate()
        if proc.returncode != 0:
            raise SolverError(f"compiling the kernels {', '.join(want)} failed in a worker process (exit "
                              f"status {proc.returncode}): {err.strip()[-2000:]}")
        for line in out.splitlines():
            parts = line.split()
            if parts[:1] == ["total"]:
                cpu += float(parts[1])
            elif len(parts) == 3:
                rows.append((parts[0], float(parts[1]), float(parts[2]), k))
    return rows, cpu


def _compile_all(calls, workers: int) -> None:
    """Compile every entry point into numba's cache: the first group of :func:`compile_plan` here, the
    others in worker processes at the same time; then each entry point is called here once more (the
    others' kernels load from the cache; anything a worker did not cache compiles here)."""
    names = [_name(d) for d, _ in calls]
    groups = compile_plan(names, workers)
    t0, c0 = time.perf_counter(), time.process_time()
    children = _start_children(groups[1:], names) if len(groups) > 1 else []
    try:
        rows = [(*r, 0) for r in _compile_group(calls, groups[0])]
        done, child_cpu = _join_children(children)
    finally:
        for proc, _ in children:  # interrupted: stop the workers (their files are whole or absent)
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    rows += done
    w, c = time.perf_counter(), time.process_time()
    for disp, args in calls:
        disp(*args)
    LAST_COMPILE.clear()
    LAST_COMPILE.update(entries=rows, workers=len(groups), load_wall=time.perf_counter() - w,
                        load_cpu=time.process_time() - c, wall=time.perf_counter() - t0,
                        cpu=time.process_time() - c0 + child_cpu)


def compile_now(quiet: bool = False, workers: int | None = None) -> float:
    """Compile every registered kernel (blocking; in :func:`compile_workers` processes at once: this
    one and workers) and stamp the cache; loads them instead when a complete compile is stamped
    already. Returns the seconds it took; :data:`LAST_COMPILE` holds the details of a compile."""
    global _COMPILED
    if numba is None:
        raise MissingPackageError(f"compiling the kernels needs the optional package 'numba', which is "
                                  f"not installed: {install_hint('numba')}")
    t0 = time.perf_counter()
    folder = cache_dir()
    with _Lock(folder, quiet):
        if load():
            return time.perf_counter() - t0
        if folder is not None:
            try:
                (folder / STAMP).unlink(missing_ok=True)
            except OSError:
                folder = None  # an unwritable cache: numba compiles in memory, nothing to stamp
        workers = (workers or compile_workers()) if folder is not None else 1  # workers share the cache
        if not quiet:
            print(f"mcdm-pin: compiling the numba kernels (once per install, in {workers} process"
                  f"{'es' if workers > 1 else ''}; about two minutes on two quiet cores)...", file=sys.stderr,
                  flush=True)
        for d in _dispatchers():
            d.recompile()  # flushes the kernel's cache (and recompiles what this process loaded from it)
        _compile_all(_all_calls(), workers)
        if folder is not None:
            _write_stamp(folder)
        _COMPILED = True
    if not quiet:
        print(f"mcdm-pin: kernels compiled in {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return time.perf_counter() - t0


def _compile_command() -> str:
    """The compile command as this run was started: ``python -m mcdm_pin compile`` under ``python -m
    mcdm_pin`` (the script's folder may not be on the shell's path there), else ``mcdm-pin compile``."""
    spec = getattr(sys.modules.get("__main__"), "__spec__", None)
    return "python -m mcdm_pin compile" if spec is not None and spec.name.startswith("mcdm_pin") else "mcdm-pin compile"


def prepare(policy: str | None = None, quiet: bool = False) -> bool:
    """Load the compiled kernels when they are stamped (policy ``auto``), compile them (``compile``,
    ``wait``) or leave them uncompiled (``off``; see the module docstring); returns :func:`compiled`.
    Starts no process and, under ``auto``, compiles nothing."""
    global _NOTED
    if _COMPILED:
        return True
    policy = policy or os.environ.get("MCDM_PIN_JIT", "auto")
    if policy == "off":
        return False
    if policy in ("compile", "wait"):
        compile_now(quiet=quiet)
        return True
    if load():
        return True
    if not (quiet or _NOTED):
        _NOTED = True
        command = _compile_command()
        how = (f"`{command}` compiles them once (a few minutes of CPU, split between the cores)"
               if numba is not None else
               f"installing numba (pip install 'mcdm-pin[numba]') and `{command}` compile them")
        print(f"mcdm-pin: the numba kernels are not compiled on this install: they run as plain Python "
              f"(the same answers, slower); {how}", file=sys.stderr, flush=True)
    return False
