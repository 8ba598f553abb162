"""What a newcomer meets first: the README's Python example runs and prints what the README says
(no ``nan``, a short summary instead of arrays), the outputs the docs make are ignored by git, and
``--version`` / ``python -m mcdm_pin`` work."""

from __future__ import annotations

import contextlib
import io
import re
import shutil
import subprocess
import sys

import pytest

from .conftest import REPO

README = REPO / "README.md"


def _python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_readme_python_example_prints_what_the_readme_shows(tmp_path, monkeypatch):
    text = README.read_text()
    block = _python_blocks(text)[0]
    shown = re.search(r"\nprints\n\n```\n(.*?)```", text, flags=re.S).group(1)
    code = block.replace('"robots/', f'"{REPO}/robots/')
    monkeypatch.chdir(tmp_path)  # run.save(...) writes here, not into the repository
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    printed = out.getvalue()
    assert "nan" not in printed.lower()
    assert (tmp_path / "traj2_case3.npz").is_file()
    lines = printed.splitlines()
    expected = shown.splitlines()
    cut = expected.index("...")
    assert lines[:cut] == expected[:cut]  # the README's sample output is this run's, line for line
    assert len(lines) < 20  # print(run) is a summary, not ~900 lines of arrays


def test_readme_composable_example_runs(tmp_path, monkeypatch):
    blocks = _python_blocks(README.read_text())
    code = (blocks[0] + blocks[1]).replace('"robots/', f'"{REPO}/robots/')
    monkeypatch.chdir(tmp_path)
    ns: dict = {}
    with contextlib.redirect_stdout(io.StringIO()):
        exec(compile(code, "README.md", "exec"), ns)
    assert len(ns["run"]) == 101 and ns["run"].found.sum() >= 75  # measured 81: a 25 deg cone is tighter


@pytest.mark.skipif(shutil.which("git") is None or not (REPO / ".git").exists(), reason="not a git checkout")
def test_outputs_the_docs_make_are_ignored_by_git():
    outputs = ["run.npz", "run.csv", "run.html", "traj2_case3.npz", "out/viewer.html", "out/traj1_case1.npz",
               "notebooks/out/neck_case3.npz", "notebooks/out/summary.png", "out/neck/8S_neck.yaml",
               "out.json", "out.md"]
    proc = subprocess.run(["git", "check-ignore", "--no-index", *outputs], cwd=REPO, capture_output=True,
                          text=True)
    assert sorted(proc.stdout.split()) == sorted(outputs)


def test_version_and_python_dash_m():
    from mcdm_pin import __version__

    for args in (["-m", "mcdm_pin", "--version"], ["-m", "mcdm_pin.cli", "--version"]):
        proc = subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0 and proc.stdout.strip() == f"mcdm-pin {__version__}"


# import names whose distribution importlib.metadata cannot map (cmeel wheels install them under
# cmeel.prefix), or cannot map where the extra that brings it is not installed (pink: the ik extra)
_DISTRIBUTION_OF = {"pinocchio": "pin", "proxsuite": "proxsuite", "mujoco": "mujoco", "pink": "pin-pink"}
# declared but never imported, on purpose
_DATA_ONLY = {"example-robot-data": "robot models read through package:// paths"}


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def test_every_imported_package_is_declared_and_every_declared_one_is_used():
    import ast
    import tomllib
    from importlib.metadata import packages_distributions

    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    deps = project["dependencies"]
    declared = {_canonical(re.split(r"[<>=!~ \[;]", d, maxsplit=1)[0]) for d in deps}
    # optional features import their package lazily and say how to install it (MissingPackageError,
    # mcdm_pin.extras.optional): the extras' packages
    extras = ("opensim", "mjcf", "ik", "numba", "viewer", "plots", "workspace", "examples")
    optional = {_canonical(re.split(r"[<>=!~ \[;]", d, maxsplit=1)[0])
                for name in extras for d in project["optional-dependencies"][name]}
    known = packages_distributions()
    used = {}
    for path in (REPO / "mcdm_pin").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else [])
            if (isinstance(node, ast.Call) and getattr(node.func, "id", None) == "optional" and node.args
                    and isinstance(node.args[0], ast.Constant)):  # extras.optional("module", ...)
                names = [node.args[0].value]
            for name in names:
                top = name.split(".")[0]
                if top in sys.stdlib_module_names or top == "mcdm_pin":
                    continue
                dist = _DISTRIBUTION_OF.get(top) or (known.get(top) or [top])[0]
                used.setdefault(_canonical(dist), path.relative_to(REPO))
    undeclared = {d: str(p) for d, p in used.items() if d not in declared | optional}
    assert not undeclared, f"imported but not in pyproject's dependencies: {undeclared}"
    unused = declared - set(used) - {_canonical(d) for d in _DATA_ONLY}
    assert not unused, f"declared but imported nowhere in mcdm_pin: {sorted(unused)}"


def _table_rows(lines):
    return {ln.split()[0]: ln.split()[1:] for ln in lines if re.match(r"^(cable\d|shoulder|elbow)\s", ln)}


def test_readme_worked_example_output_is_a_fresh_runs(capsys):
    """The README's sample output of `mcdm-pin solve ... traj1 --case 3`: the same lines, the same
    peaks to 1e-3 (the time of a peak is compared only where the peak is not a tie at the lower bound
    or at the cone, and the timing line not at all: it is this machine's)."""
    from mcdm_pin.cli import main

    text = README.read_text()
    shown = re.search(r"A worked example.*?```\n(.*?)```", text, flags=re.S).group(1).splitlines()
    assert main(["solve", str(REPO / "robots" / "two_link_sr.yaml"), "--trajectory", "traj1", "--case", "3",
                 "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == shown[:2]  # the problem and the trajectory
    assert [ln for ln in out if not re.match(r"^(cable\d|shoulder|elbow|time per|answered by)", ln)] == \
           [ln for ln in shown if not re.match(r"^(cable\d|shoulder|elbow|time per|answered by)", ln)]
    got, want = _table_rows(out), _table_rows(shown)
    assert sorted(got) == sorted(want)
    for name, row in want.items():
        for k, (a, b) in enumerate(zip(got[name], row)):
            if b == "-":
                assert a == "-"
            elif name.startswith("cable") and k == 1 and row[0] == row[2]:
                continue  # at its lower bound all along: any instant is "the" peak
            elif k == 3 and row[4] != "-" and abs(float(row[2]) - float(row[4])) < 1e-3:
                continue  # the angle held at the cone over a span: any instant of it is "the" maximum
            else:
                assert float(a) == pytest.approx(float(b), abs=1e-3), (name, k, a, b)
    assert re.match(r"time per instant: model [\d.]+ ms, solve [\d.]+ ms", shown[-2])
    counts = r"\w+ at \d+( instants)? \(median \d+ [\w /-]+\)"
    assert re.match(rf"answered by {counts}(, {counts})*$", shown[-1]), shown[-1]
    assert re.match(rf"answered by {counts}(, {counts})*$", out[-1]), out[-1]


def test_links_in_the_readme_and_the_docs_lead_somewhere():
    pages = [README, *sorted((REPO / "docs").glob("*.md")), *sorted((REPO / "docs" / "api").glob("*.md"))]
    broken = []
    for page in pages:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" in target or target.startswith("mailto:"):
                continue
            if not (page.parent / target).exists():
                broken.append(f"{page.relative_to(REPO)} -> {target}")
    assert not broken, broken


def test_ci_runs_the_readmes_test_command_and_both_commands_install_alike():
    """``.ci/run`` runs exactly the README's second command, and both commands install the same way
    (uv's ``pip`` interface)."""
    first, second = (block.strip() for block in re.findall(r"```bash\n(.*?)```", README.read_text(), flags=re.S)[:2])
    ci_lines = [line.strip() for line in (REPO / ".ci" / "run").read_text().splitlines()]
    assert second in ci_lines
    install = "python -m pip install -q uv && python -m uv pip install"
    assert first.startswith(install) and second.startswith(install)
    # the tests' install writes every package's bytecode where Python will not (its workers and
    # subprocesses import far more than a run); the first command leaves that to `mcdm-pin compile`,
    # which writes the bytecode of what a run imports
    assert "${PYTHONDONTWRITEBYTECODE:+--compile-bytecode}" in second and "--compile-bytecode" not in first
    # the first command runs the package as a module: an installer that writes the `mcdm-pin` script
    # where the shell does not look (pyenv's shims before a rehash, a --user install) cannot break it
    assert " && python -m mcdm_pin solve " in first, first
