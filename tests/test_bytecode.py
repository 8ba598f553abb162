"""``mcdm-pin compile`` writes the bytecode of the modules a run imports (mcdm_pin/bytecode.py): the
``.pyc`` Python's import would write, only where it is missing or stale, and says what it could not
write."""

from __future__ import annotations

import importlib.util
import marshal
import os
from pathlib import Path

import numpy

import mcdm_pin
from mcdm_pin import bytecode


def _module(tmp_path: Path, text: str) -> Path:
    source = tmp_path / "someone.py"
    source.write_text(text)
    return source


def test_writes_the_pyc_import_reads_and_only_where_it_is_missing_or_stale(tmp_path):
    source = _module(tmp_path, "ANSWER = 41 + 1\n")
    pyc = Path(importlib.util.cache_from_source(str(source)))
    assert bytecode.write_bytecode([source]) == bytecode.BytecodeReport(1, 0, ())
    data = pyc.read_bytes()
    assert data[:4] == importlib.util.MAGIC_NUMBER and int.from_bytes(data[4:8], "little") == 0  # timestamp-checked
    space = {}
    exec(marshal.loads(data[16:]), space)
    assert space["ANSWER"] == 42
    assert bytecode.write_bytecode([source]) == bytecode.BytecodeReport(0, 1, ())  # current: untouched
    source.write_text("ANSWER = 43\n")  # another size: import would find the .pyc stale
    os.utime(source, (1_700_000_000, 1_700_000_000))
    assert bytecode.write_bytecode([source]) == bytecode.BytecodeReport(1, 0, ())
    space = {}
    exec(marshal.loads(pyc.read_bytes()[16:]), space)
    assert space["ANSWER"] == 43


def test_a_pyc_that_cannot_be_written_is_reported_not_hidden(tmp_path):
    source = _module(tmp_path, "X = 1\n")
    (tmp_path / "__pycache__").write_text("a file where the folder would go")  # unwritable, even for root
    report = bytecode.write_bytecode([source])
    assert report.written == 0 and report.current == 0 and report.unwritable == (str(source),)


def test_the_sources_are_what_this_process_imported_and_every_module_of_the_package():
    sources = bytecode.module_sources()
    assert Path(numpy.__file__) in sources and Path(bytecode.__file__) in sources
    package = Path(mcdm_pin.__file__).parent
    assert set(package.rglob("*.py")) <= set(sources)
    assert len(sources) == len(set(sources)) and all(s.suffix == ".py" for s in sources)


def test_the_compile_command_says_what_it_wrote(monkeypatch, capsys, tmp_path):
    from mcdm_pin import jit
    from mcdm_pin.cli import main

    source = _module(tmp_path, "Y = 2\n")
    monkeypatch.setattr(jit, "compile_now", lambda **kw: 0.0)  # the kernels' compile: tests/test_compile.py
    monkeypatch.setattr(bytecode, "module_sources", lambda: [source])
    assert main(["compile"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-1].startswith("bytecode of the modules a run imports: 1 written, 0 current (")
    assert Path(importlib.util.cache_from_source(str(source))).is_file()
    blocked = tmp_path / "ro"
    blocked.mkdir()
    other = _module(blocked, "Z = 3\n")
    (blocked / "__pycache__").write_text("a file where the folder would go")
    monkeypatch.setattr(bytecode, "module_sources", lambda: [source, other])
    assert main(["compile"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith(
        f"bytecode of the modules a run imports: 0 written, 1 current, 1 not writable (e.g. {other}: ")
