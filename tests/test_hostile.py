"""Every hostile input of ``tests/hostile_corpus.py`` ends in one clear error and changes nothing.

Each case runs ``mcdm-pin`` in a forked child (the package is imported once, in the parent) inside a
fresh folder holding its files, with stdout and stderr captured, an address-space limit 2 GiB above the
child's start and a 60 s wall-clock limit. Asserted: exit status 2; stderr is one line
``mcdm-pin: error: ...`` naming the case's file and matching its field; no traceback; no file created,
changed or removed; and the child's peak resident memory grew by less than 1 GiB.
"""

from __future__ import annotations

import hashlib
import os
import re
import resource
import signal
import time
from collections import Counter
from pathlib import Path

import pytest

from .hostile_corpus import Case, Sparse, all_cases

TIMEOUT_S = 60
EXTRA_ADDRESS_SPACE = 2 * 2**30
MAX_RSS_GROWTH_KB = 2**20

CASES = all_cases()
RESULTS: Counter = Counter()


def _snapshot(folder: Path) -> dict[str, str]:
    out = {}
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            out[str(p.relative_to(folder))] = hashlib.sha256(p.read_bytes()).hexdigest()
        else:
            out[str(p.relative_to(folder))] = "dir"
    return out


def _vm_size() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    return 0


def _run(case: Case, folder: Path):
    from mcdm_pin.cli import main

    out, err = folder.parent / f"{folder.name}.out", folder.parent / f"{folder.name}.err"
    pid = os.fork()
    if pid == 0:  # child
        code = 98
        try:
            os.chdir(folder)
            start_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
            limit = _vm_size() + EXTRA_ADDRESS_SPACE
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
            import sys

            fo, fe = os.open(out, os.O_WRONLY | os.O_CREAT), os.open(err, os.O_WRONLY | os.O_CREAT)
            os.dup2(fo, 1)
            os.dup2(fe, 2)
            # pytest replaced sys.stdout/sys.stderr with its own capture objects: write to the files
            sys.stdout = open(1, "w", closefd=False)
            sys.stderr = open(2, "w", closefd=False)
            code = main(case.argv)
            sys.stdout.flush()
            sys.stderr.flush()
            grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - start_rss
            if grown > MAX_RSS_GROWTH_KB:
                os.write(2, f"\nMEMORY: grew by {grown} kB\n".encode())
        except BaseException:  # noqa: BLE001 (the child reports everything through its stderr)
            import traceback

            os.write(2, traceback.format_exc().encode())
            code = 99
        finally:
            os._exit(int(code) if isinstance(code, int) else 97)
    deadline = time.monotonic() + TIMEOUT_S
    while True:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            return None, "", ""
        time.sleep(0.01)
    code = os.waitstatus_to_exitcode(status)
    return code, out.read_text(errors="replace"), err.read_text(errors="replace")


@pytest.mark.parametrize("case", CASES, ids=[f"{c.klass}-{c.name}" for c in CASES])
def test_hostile_input(case: Case, tmp_path):
    folder = tmp_path / "case"
    folder.mkdir()
    for name, content in case.files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, Sparse):
            path.write_bytes(content.head)
            os.truncate(path, content.size)
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
    before = _snapshot(folder)
    code, out, err = _run(case, folder)
    kind = "clear"
    try:
        assert code is not None, f"hang: no answer in {TIMEOUT_S} s"
        assert "Traceback" not in err, f"traceback:\n{err}"
        assert "MEMORY:" not in err, err
        assert code == 2, f"exit status {code}; stderr: {err!r}"
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("mcdm-pin: error: "), f"not one line: {err!r}"
        for name in filter(None, (case.file, case.extra.get("also"))):
            assert name in lines[0], f"the message does not name {name}: {lines[0]}"
        assert re.search(case.field, lines[0]), f"the message does not match {case.field!r}: {lines[0]}"
        assert _snapshot(folder) == before, "files were created or changed"
    except AssertionError as exc:
        text = str(exc)
        kind = ("hang" if text.startswith("hang") else "traceback" if text.startswith("traceback") else
                "changed" if "created or changed" in text else "vague")
        raise
    finally:
        RESULTS[(case.klass, kind)] += 1


def test_corpus_is_large_and_covers_every_input():
    classes = Counter(c.klass for c in CASES)
    assert sum(classes.values()) >= 150
    assert set(classes) >= {"sidecar", "urdf", "csv", "cli", "results", "caspr"}
