"""Write the API reference (docs/api/*.md) from the package's docstrings and signatures.

    python docs/api/generate.py            # rewrites docs/api/
    python docs/api/generate.py --out DIR  # somewhere else (tests/test_docs.py compares the two)

One page per module of :data:`MODULES`: its docstring, then every public name (``__all__``, or what
the module defines without a leading underscore, in source order) with its signature and docstring;
classes with their public methods and properties. Docstrings are reST-flavoured (Google-style
sections, ``code``, :roles:, ``::`` blocks, simple tables): they are turned into Markdown here, with no
dependency beyond the standard library.
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import importlib
import inspect
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))  # the repository's package, also when not installed

MODULES = [
    ("mcdm_pin", "the package: what `from mcdm_pin import ...` gives"),
    ("mcdm_pin.robot", "Robot: URDF + sidecar (or a pin.Model) -> model, cables, joints"),
    ("mcdm_pin.trajectory", "trajectories: quintic, CSV, plans at any time"),
    ("mcdm_pin.ik", "task-space trajectories -> joint trajectories by inverse kinematics (pink)"),
    ("mcdm_pin.inverse_dynamics", "InverseDynamics: state -> forces, one instant or a trajectory"),
    ("mcdm_pin.settings", "Settings: every tolerance, pivot limit and budget, passed down to the stages"),
    ("mcdm_pin.diagnosis", "what an infeasible instant cannot meet, and what would do"),
    ("mcdm_pin.batch", "batch mode: a trajectory in pieces on Dask"),
    ("mcdm_pin.runtime", "the Dask runtime of workspaces and batches"),
    ("mcdm_pin.extras", "optional dependencies and their extras"),
    ("mcdm_pin.results", "InstantResult, TrajectoryResult and their files"),
    ("mcdm_pin.problem", "Problem: objectives + constraints; the paper's cases"),
    ("mcdm_pin.qp", "QPData and ConeData: the problem every back-end reads"),
    ("mcdm_pin.objectives", "objectives"),
    ("mcdm_pin.constraints", "constraints"),
    ("mcdm_pin.solvers", "solver back-ends"),
    ("mcdm_pin.model", "the layer below Robot, in Pinocchio's idiom"),
    ("mcdm_pin.model.cables", "cables and their routes"),
    ("mcdm_pin.model.joints", "physical joints"),
    ("mcdm_pin.model.charts", "coordinates and configurations"),
    ("mcdm_pin.model.terms", "the cable terms at a state"),
    ("mcdm_pin.model.routes", "configuration-dependent routes: paths over wraps at an instant"),
    ("mcdm_pin.model.wrapping", "MuJoCo's tendon wrapping over spheres and cylinders, and pulleys"),
    ("mcdm_pin.model.pulleys", "rotating and screw pulleys: the exit point at an instant (CASPR's)"),
    ("mcdm_pin.model.springs", "passive springs: known tensions that follow their lengths"),
    ("mcdm_pin.model.muscles", "MuJoCo's muscle model: a cable's tension range and activation"),
    ("mcdm_pin.model.couplings", "coupled coordinates (MuJoCo's equality joint)"),
    ("mcdm_pin.mjcf", "MJCF files (MyoSuite) -> Robot, through MuJoCo's compiler"),
    ("mcdm_pin.mjcf.model", "the pin.Model of a compiled MuJoCo model, and the coordinate maps"),
    ("mcdm_pin.mjcf.tendons", "MuJoCo's tendons, muscles, motors and equalities -> cables, couplings"),
    ("mcdm_pin.osim", "OpenSim .osim files -> Robot, read as XML (the skeleton: bodies, joints, couplings, loops)"),
    ("mcdm_pin.osim.rmr", "RMR's per-frame problem on the thoracoscapular shoulder, and its answers in ours"),
    ("mcdm_pin.verify", "forward-dynamics replay and its verdict"),
    ("mcdm_pin.trajectory_checks", "the trajectory checks of mcdm-pin info"),
    ("mcdm_pin.workspace", "workspaces: poses -> chunks -> Dask -> Zarr"),
    ("mcdm_pin.caspr", "CASPR's XML models -> URDF + sidecar + exact trajectories"),
    ("mcdm_pin.solvers.cascade", "Cascade: a chain of named stages, one signature"),
    ("mcdm_pin.solvers.chains", "the solver chains the library uses, built in one place"),
    ("mcdm_pin.solvers.margins", "margins: the f_max or cone angle that makes an instant feasible"),
    ("mcdm_pin.model.actuators", "actuated joints of hybrid robots"),
    ("mcdm_pin.export", "export to OpenSim and MuJoCo"),
    ("mcdm_pin.export.mjcf", "a robot as a MuJoCo model (MJCF), with the coordinate maps"),
    ("mcdm_pin.control", "force distribution in a control loop: laws, deadline, fallback, MuJoCo plant"),
    ("mcdm_pin.control.controller", "the controller: a deadline and a fallback around the distribution"),
    ("mcdm_pin.control.laws", "computed-torque laws in joint and task space"),
    ("mcdm_pin.control.plant", "MuJoCo as the plant, with sensor noise"),
    ("mcdm_pin.control.loop", "the closed loop and its tracking errors"),
    ("mcdm_pin.limits", "limits on every input"),
    ("mcdm_pin.viewer", "the 3-D viewer"),
    ("mcdm_pin.plots", "the figures"),
    ("mcdm_pin.exceptions", "the exceptions"),
]

ROLE = re.compile(r":(?:class|func|meth|mod|data|attr|obj|exc|math):`~?([^`]+)`")
TABLE_BORDER = re.compile(r"^\s*=+(\s+=+)+\s*$")
SECTIONS = ("Args:", "Arguments:", "Returns:", "Attributes:", "Raises:", "Yields:", "Example:",
            "Examples:", "Note:")


def inline(text: str) -> str:
    """reST inline markup -> Markdown: ``x`` and :role:`~a.b.x` -> `x` (a tilde keeps the last part)."""
    def role(m):
        target = m.group(0)
        name = m.group(1)
        return f"`{name.split('.')[-1] if ':`~' in target else name}`"
    text = ROLE.sub(role, text)
    return re.sub(r"``([^`]+)``", r"`\1`", text)


def markdown(doc: str | None) -> str:
    """A docstring as Markdown (module docstring)."""
    if not doc:
        return ""
    lines = inspect.cleandoc(doc).splitlines()
    out: list[str] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if TABLE_BORDER.match(line):  # a simple table: three borders, verbatim
            block, borders = [], 0
            while i < len(lines) and borders < 3:
                block.append(lines[i])
                borders += bool(TABLE_BORDER.match(lines[i]))
                i += 1
            out += ["```", *block, "```"]
            continue
        if stripped.startswith(".. math::") or (stripped.endswith("::") and not stripped.startswith("..")):
            lead = stripped[len(".. math::"):].strip() if stripped.startswith(".. math::") else ""
            if not stripped.startswith(".. math::"):
                out.append(inline(line.rstrip()[:-2].rstrip() + (":" if stripped != "::" else "")))
            i += 1
            block = [lead] if lead else []
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith((" ", "\t"))):
                block.append(lines[i])
                i += 1
            while block and not block[-1].strip():
                block.pop()
            while block and not block[0].strip():
                block.pop(0)
            out += ["", "```", *inspect.cleandoc("\n".join(block)).splitlines(), "```", ""]
            continue
        if stripped in SECTIONS:
            out += ["", f"**{stripped[:-1]}**", ""]
            i += 1
            item: list[str] = []
            base = None
            while i < len(lines) and (not lines[i].strip() or lines[i].startswith((" ", "\t"))):
                raw = lines[i]
                if raw.strip():
                    indent = len(raw) - len(raw.lstrip())
                    base = indent if base is None else base
                    if indent == base and item:
                        out.append(inline(" ".join(item)))
                        item = []
                    item.append(("- " if indent == base else "") + raw.strip())
                i += 1
            if item:
                out.append(inline(" ".join(item)))
            out.append("")
            continue
        out.append(inline(line.strip() if line.startswith((" ", "\t")) and not stripped.startswith("* ") else line))
        i += 1
    text = "\n".join(out)
    return re.sub(r"\n{3,}", "\n\n", text).strip() + "\n"


def signature(obj, name: str) -> str:
    try:
        sig = str(inspect.signature(obj))
    except (TypeError, ValueError):
        return name
    sig = re.sub(r"(: |-> )[\"']+([^\"']*)[\"']+", r"\1\2", sig)  # annotations stored as strings
    sig = re.sub(r" at 0x[0-9a-f]+", "", sig)
    text = f"{name}{sig}"
    if len(text) <= 100:
        return text
    inner = sig[1:sig.rindex(")")]
    params, depth, cur = [], 0, ""
    for ch in inner:  # split at top-level commas
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == "," and depth == 0:
            params.append(cur.strip())
            cur = ""
        else:
            cur += ch
    if cur.strip():
        params.append(cur.strip())
    return f"{name}(\n" + "".join(f"    {p},\n" for p in params) + ")" + sig[sig.rindex(")") + 1:]


def public_names(module) -> list[str]:
    if hasattr(module, "__all__"):
        return list(module.__all__)
    names = []
    for name, obj in vars(module).items():
        if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
            continue
        if inspect.isclass(obj) or inspect.isfunction(obj):
            names.append(name)
    return sorted(names, key=lambda n: _line(getattr(module, n)))


def _line(obj) -> int:
    try:
        return inspect.getsourcelines(obj)[1]
    except (OSError, TypeError):
        return 0


def _where(obj) -> str:
    mod = getattr(obj, "__module__", "")
    return f" *(from `{mod}`)*" if mod else ""


def field_docs(cls) -> dict[str, str]:
    """A dataclass's field docstrings: the string literal right after each annotated field."""
    try:
        body = ast.parse(inspect.getsource(cls).lstrip()).body[0].body
    except (OSError, TypeError, SyntaxError, IndexError, AttributeError):
        return {}
    out = {}
    for a, b in zip(body, body[1:]):
        if (isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name) and isinstance(b, ast.Expr)
                and isinstance(b.value, ast.Constant) and isinstance(b.value.value, str)):
            out[a.target.id] = inspect.cleandoc(b.value.value)
    return out


def document_fields(cls, name: str) -> list[str]:
    """A dataclass's fields with their defaults and docstrings (:func:`field_docs`)."""
    docs, out = (field_docs(cls) if dataclasses.is_dataclass(cls) else {}), []
    if not docs:  # (a dataclass whose fields its docstring describes)
        return []
    for f in dataclasses.fields(cls):
        if f.name.startswith("_"):
            continue
        default = "" if f.default is dataclasses.MISSING else f" = {f.default!r}"
        out += [f"### `{name}.{f.name}`{default}", ""]
        if f.name in docs:
            out.append(markdown(docs[f.name]))
    return out


def document_class(cls, name: str, module_name: str) -> list[str]:
    out = [f"## `{name}`", "", "```python", f"class {signature(cls, name)}", "```", ""]
    if cls.__module__ != module_name:
        out += [f"Defined in `{cls.__module__}`.", ""]
    out.append(markdown(inspect.getdoc(cls)))
    if cls.__module__ == module_name:
        out += document_fields(cls, name)
    members = []
    for attr, value in vars(cls).items():
        if attr.startswith("_") and attr != "__call__":
            continue
        if isinstance(value, property):
            members.append((attr, "property", value.fget))
        elif isinstance(value, (classmethod, staticmethod)):
            members.append((attr, type(value).__name__, value.__func__))
        elif inspect.isfunction(value):
            members.append((attr, "method", value))
    for attr, kind, func in members:
        if kind == "property":
            out += [f"### `{name}.{attr}` (property)", ""]
        else:
            prefix = "" if kind == "method" else f"@{kind}\n"
            out += [f"### `{name}.{attr}`", "", "```python", prefix + signature(func, attr), "```", ""]
        doc = inspect.getdoc(func) if func.__doc__ else ""
        if doc:
            out.append(markdown(doc))
    return out


def page(module_name: str) -> str:
    module = importlib.import_module(module_name)
    out = [f"# `{module_name}`", "", "[API reference](README.md)", "", markdown(module.__doc__)]
    for name in public_names(module):
        obj = getattr(module, name)
        if inspect.ismodule(obj):
            continue
        if inspect.isclass(obj):
            out += document_class(obj, name, module_name)
        elif callable(obj):
            out += [f"## `{name}`", "", "```python", f"def {signature(obj, name)}", "```", ""]
            if getattr(obj, "__module__", module_name) != module_name:
                out += [f"Defined in `{obj.__module__}`.", ""]
            out.append(markdown(inspect.getdoc(obj)))
        else:
            text = repr(obj)
            shown = text if len(text) <= 90 and "\n" not in text else f"<{type(obj).__name__}>"
            out += [f"## `{name}`", "", "```python", f"{name} = {shown}", "```", ""]
    return re.sub(r"\n{3,}", "\n\n", "\n".join(out)).rstrip() + "\n"


def index() -> str:
    rows = "\n".join(f"- [`{name}`]({name}.md): {what}" for name, what in MODULES)
    return (
        "# API reference\n\n"
        "Generated from the docstrings by `python docs/api/generate.py` (do not edit these pages by "
        "hand; `tests/test_docs.py` rebuilds them and fails when they differ from the code).\n\n"
        f"{rows}\n\n"
        "The command line is documented by `mcdm-pin --help` and `mcdm-pin COMMAND --help`; the "
        "sidecar's keys in [../sidecar.md](../sidecar.md).\n")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(HERE), help="output folder (default: docs/api)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "README.md").write_text(index(), encoding="utf-8")
    for name, _ in MODULES:
        (out / f"{name}.md").write_text(page(name), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
