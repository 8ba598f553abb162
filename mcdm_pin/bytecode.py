"""The bytecode of the modules a run imports, written once by ``mcdm-pin compile``.

Python compiles a module's source to bytecode on every import that finds no current ``.pyc`` for
it, and writes that ``.pyc`` only where it may: where ``PYTHONDONTWRITEBYTECODE`` is set (as many
container images set it) it writes none, so every run compiles numpy's, scipy's, numba's and this
package's sources again (0.7-0.9 s of an uncompiled 2-link solve's 1.6 s on a quiet 2-core machine:
docs/speed.md, "The first command without uv's bytecode pass"). Installers write the bytecode of
what they install (pip always, uv with ``--compile-bytecode``), about 6,800 files for the ``all``
extra, most of them never imported by a run; and an editable install's own package gets none.

:func:`write_bytecode` writes the ``.pyc`` of the given modules where it is missing or stale, as
Python's import would (timestamp-checked ``.pyc`` in ``__pycache__``, the interpreter's optimisation
level), and nothing else: ``mcdm-pin compile`` calls it on the modules its process imported while
loading the command line, the solvers and every kernel (the modules a run imports) and on every
module of this package.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import py_compile
import struct
import sys
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class BytecodeReport:
    """What :func:`write_bytecode` did: ``.pyc`` files written, found current, and not writable
    (a read-only installation: those modules keep compiling at import)."""

    written: int
    current: int
    unwritable: tuple[str, ...]


def _current(source: Path, pyc: str) -> bool:
    """Whether ``pyc`` holds a timestamp-checked header that matches ``source`` (what import checks),
    or is hash-based (checked against the source by import itself)."""
    try:
        with open(pyc, "rb") as f:
            header = f.read(16)
        stat = source.stat()
    except OSError:
        return False
    if len(header) < 16 or header[:4] != importlib.util.MAGIC_NUMBER:
        return False
    flags, mtime, size = struct.unpack("<III", header[4:16])
    if flags & 1:
        return True
    return mtime == int(stat.st_mtime) & 0xFFFFFFFF and size == stat.st_size & 0xFFFFFFFF


# what a run imports besides what the compile command's process has loaded (the command line and
# every kernel): the back-ends a chain may reach, and the codec of the sidecar reader
RUN_IMPORTS = ("clarabel", "proxsuite", "encodings.utf_8_sig")


def module_sources() -> list[Path]:
    """The ``.py`` sources of every module loaded in this process, :data:`RUN_IMPORTS` imported first,
    and of every module of this package, each once."""
    for name in RUN_IMPORTS:
        importlib.import_module(name)
    files = {Path(getattr(m, "__file__", "") or "") for m in list(sys.modules.values()) if m is not None}
    files |= set(Path(__file__).parent.rglob("*.py"))
    return sorted(f for f in files if f.suffix == ".py" and f.is_file())


def write_bytecode(sources: list[Path]) -> BytecodeReport:
    """Write the ``.pyc`` of each source whose ``.pyc`` is missing or stale."""
    written, current, unwritable = 0, 0, []
    optimization = sys.flags.optimize or ""
    for source in sources:
        pyc = importlib.util.cache_from_source(os.fspath(source), optimization=optimization)
        if _current(source, pyc):
            current += 1
            continue
        try:
            py_compile.compile(os.fspath(source), cfile=pyc, doraise=True,
                               invalidation_mode=py_compile.PycInvalidationMode.TIMESTAMP)
            written += 1
        except OSError:
            unwritable.append(os.fspath(source))
    return BytecodeReport(written, current, tuple(unwritable))
