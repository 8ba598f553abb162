"""House metrics of the ``mcdm_pin`` package: import circles, long files, long functions, solver lines.

Read from the source with :mod:`ast` (nothing is imported or run):

- **import circles**: the graph of module-level imports among the package's modules (statements at
  the top of a module, also inside module-level ``try``/``if`` blocks, but not under
  ``if TYPE_CHECKING:``, which never runs). ``import a.b`` and ``from a.b import x`` give an edge to
  ``a.b``; ``from a import b`` with ``b`` a submodule gives an edge to ``a.b`` (not to ``a``'s
  ``__init__``). A circle is a strongly connected component of two or more modules (or a module
  importing itself); each is listed with its modules and one shortest cycle through them. Imports
  inside functions (the usual way around a circle) are counted apart, and the circles they would
  close at module level are listed too, with the imports that **dodge a circle**: an import inside a
  function of module ``a`` of a module ``b`` that imports ``a`` (directly or through others, at
  module level or inside functions), i.e. one that closes a circle once every import counts.
- **files over 600 lines** and **functions over 80 lines** (``def`` line to last line, docstring
  included; methods and nested functions by their dotted names);
- **kernels with more than 15 arguments**: functions decorated with numba's ``njit`` or
  ``register_jitable`` (compiled kernels and what is compiled inline into them) whose positional
  parameters number more than ``--max-args`` (a kernel takes named structures, not two dozen arrays);
- **lines in ``solvers/``**: per file and in all, beside the package's total.

    python tools/house_metrics.py [--package mcdm_pin] [--max-file 600] [--max-function 80] [--max-args 15]
                                  [--json FILE]
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from collections import deque
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def modules(package: Path) -> dict[str, Path]:
    """Dotted module name -> file, for every ``.py`` file under ``package`` (``__init__`` as the package)."""
    out = {}
    for path in sorted(package.rglob("*.py")):
        parts = list(path.relative_to(package.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _module_level(body):
    """The import statements run at import time: top level and inside module-level try/if/with."""
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, ast.If):
            if not _is_type_checking(node):
                yield from _module_level(node.body)
            yield from _module_level(node.orelse)
        elif isinstance(node, ast.Try):
            for block in (node.body, node.orelse, node.finalbody, *[h.body for h in node.handlers]):
                yield from _module_level(block)
        elif isinstance(node, ast.With):
            yield from _module_level(node.body)


def _base(name: str, node: ast.ImportFrom, is_package: bool) -> str:
    """The absolute module a ``from`` import names (relative levels resolved against ``name``)."""
    if not node.level:
        return node.module or ""
    parts = name.split(".")
    anchor = parts if is_package else parts[:-1]  # a package's "." is itself
    anchor = anchor[: len(anchor) - (node.level - 1)]
    return ".".join(anchor + ([node.module] if node.module else []))


def targets(name: str, node, known: dict, is_package: bool) -> set[str]:
    """The package's modules an import statement of module ``name`` imports."""
    out = set()
    if isinstance(node, ast.Import):
        for alias in node.names:
            if alias.name in known:
                out.add(alias.name)
        return out
    base = _base(name, node, is_package)
    subs = {f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in known}
    plain = [a for a in node.names if f"{base}.{a.name}" not in known]
    out |= subs
    if base in known and (plain or not subs):
        out.add(base)
    return out


def import_graph(mods: dict[str, Path]) -> tuple[dict[str, set[str]], dict[str, set[str]], list]:
    """(module -> modules it imports at module level, the same with the imports inside functions
    added, the package's imports inside functions as ``(module, line, imported modules)``)."""
    graph, full, inner = {}, {}, []
    for name, path in mods.items():
        tree = ast.parse(path.read_text(), str(path))
        is_package = path.name == "__init__.py"
        top = list(_module_level(tree.body))
        graph[name] = set().union(*(targets(name, n, mods, is_package) for n in top)) if top else set()
        full[name] = set(graph[name])
        top_ids = {id(n) for n in top}
        for n in ast.walk(tree):
            if isinstance(n, (ast.Import, ast.ImportFrom)) and id(n) not in top_ids:
                t = targets(name, n, mods, is_package)
                if t:
                    inner.append((name, n.lineno, sorted(t)))
                full[name] |= t
    return graph, full, inner


def reaches(graph: dict[str, set[str]], start: str, goal: str) -> bool:
    """Whether ``goal`` is reachable from ``start`` along ``graph``'s edges."""
    seen, todo = {start}, [start]
    while todo:
        v = todo.pop()
        if v == goal:
            return True
        for w in graph.get(v, ()):
            if w not in seen:
                seen.add(w)
                todo.append(w)
    return False


def dodging(full: dict[str, set[str]], inner: list) -> list[tuple[str, int, str]]:
    """The imports inside functions that dodge a circle (module docstring): ``(module, line, target)``
    (``full``: the graph with the imports inside functions)."""
    return [(a, line, b) for a, line, ts in inner for b in ts if b != a and reaches(full, b, a)]


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with a cycle (Tarjan), each sorted; largest first."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):  # recursion depth: the package's import depth (tens)
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph.get(v, ()):
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(out, key=lambda c: (-len(c), c))


def shortest_cycle(graph: dict[str, set[str]], comp: list[str]) -> list[str]:
    """One shortest cycle within ``comp`` (breadth-first from each member), as a list ``a, b, ..., a``."""
    members, best = set(comp), None
    for s in comp:
        prev, queue = {s: None}, deque([s])
        while queue:
            v = queue.popleft()
            for w in sorted(graph[v] & members):
                if w == s:
                    path = [v]
                    while prev[path[-1]] is not None:
                        path.append(prev[path[-1]])
                    cyc = [s] + path[::-1][1:] + [s] if path[-1] == s else path[::-1] + [s]
                    if best is None or len(cyc) < len(best):
                        best = cyc
                    queue.clear()
                    break
                if w not in prev:
                    prev[w] = v
                    queue.append(w)
    return best or comp


def long_functions(path: Path, limit: int) -> list[tuple[str, int, int]]:
    """(dotted name, first line, length) of every function longer than ``limit`` lines."""
    out = []

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                length = child.end_lineno - child.lineno + 1
                if length > limit:
                    out.append((prefix + child.name, child.lineno, length))
                walk(child, prefix + child.name + ".")
            elif isinstance(child, ast.ClassDef):
                walk(child, prefix + child.name + ".")
            else:
                walk(child, prefix)

    walk(ast.parse(path.read_text(), str(path)), "")
    return out


def wide_kernels(path: Path, limit: int) -> tuple[int, list[tuple[str, int, int]]]:
    """How many kernels ``path`` defines, and (name, line, parameters) of those with more than
    ``limit`` positional parameters."""
    kernels, wide = 0, []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.FunctionDef) and any(
                "njit" in ast.unparse(d) or "register_jitable" in ast.unparse(d) for d in node.decorator_list):
            kernels += 1
            if len(node.args.args) > limit:
                wide.append((node.name, node.lineno, len(node.args.args)))
    return kernels, wide


def measure(package: Path, max_file: int, max_function: int, max_args: int = 15) -> dict:
    mods = modules(package)
    graph, full, inner = import_graph(mods)
    comps = circles(graph)
    dodged = circles(full)
    lines = {p: len(p.read_text().splitlines()) for p in mods.values()}
    rel = lambda p: str(p.relative_to(package.parent))  # noqa: E731
    solvers = {rel(p): n for p, n in lines.items() if "solvers" in p.relative_to(package).parts}
    kern = {rel(p): wide_kernels(p, max_args) for p in mods.values()}
    return dict(
        kernels=sum(k for k, _ in kern.values()), max_args=max_args,
        wide_kernels=sorted(((p, name, line, n) for p, (_, w) in kern.items() for name, line, n in w),
                            key=lambda x: -x[3]),
        package=str(package), modules=len(mods), lines_total=sum(lines.values()),
        import_edges=sum(len(v) for v in graph.values()), function_level_imports=len(inner),
        dodging_imports=dodging(full, inner),
        circles=[dict(modules=c, cycle=shortest_cycle(graph, c)) for c in comps],
        circles_with_function_imports=[dict(modules=c, cycle=shortest_cycle(full, c)) for c in dodged],
        long_files=sorted(((rel(p), n) for p, n in lines.items() if n > max_file), key=lambda x: -x[1]),
        long_functions=sorted(((rel(p), name, line, n) for p in mods.values()
                               for name, line, n in long_functions(p, max_function)), key=lambda x: -x[3]),
        solvers_lines=sum(solvers.values()), solvers_files=dict(sorted(solvers.items(), key=lambda x: -x[1])),
        max_file=max_file, max_function=max_function)


def report(m: dict) -> str:
    out = [f"package {m['package']}: {m['modules']} modules, {m['lines_total']} lines, "
           f"{m['import_edges']} module-level import edges",
           f"import circles (module level): {len(m['circles'])}"]
    for i, c in enumerate(m["circles"], 1):
        out.append(f"  {i}. {len(c['modules'])} modules: {', '.join(c['modules'])}")
        out.append(f"     shortest cycle: {' -> '.join(c['cycle'])}")
    out.append(f"imports of package modules inside functions: {m['function_level_imports']}")
    out.append(f"imports inside functions that dodge a circle: {len(m['dodging_imports'])}")
    out += [f"  {a}:{line} imports {b}" for a, line, b in m["dodging_imports"]]
    out.append(f"circles once the imports inside functions count too: "
               f"{len(m['circles_with_function_imports'])}")
    for i, c in enumerate(m["circles_with_function_imports"], 1):
        out.append(f"  {i}. {', '.join(c['modules'])}; shortest cycle: {' -> '.join(c['cycle'])}")
    out.append(f"files over {m['max_file']} lines: {len(m['long_files'])}")
    out += [f"  {n:5d}  {p}" for p, n in m["long_files"]]
    out.append(f"functions over {m['max_function']} lines: {len(m['long_functions'])}")
    out += [f"  {n:5d}  {p}:{line} {name}" for p, name, line, n in m["long_functions"]]
    out.append(f"kernels with more than {m['max_args']} arguments: {len(m['wide_kernels'])} of {m['kernels']}")
    out += [f"  {n:5d}  {p}:{line} {name}" for p, name, line, n in m["wide_kernels"]]
    out.append(f"lines in solvers/: {m['solvers_lines']} of {m['lines_total']}")
    out += [f"  {n:5d}  {p}" for p, n in m["solvers_files"].items()]
    return "\n".join(out)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--package", default=str(REPO / "mcdm_pin"), help="the package folder (default mcdm_pin)")
    p.add_argument("--max-file", type=int, default=600, help="longest allowed file, lines (default 600)")
    p.add_argument("--max-function", type=int, default=80, help="longest allowed function, lines (default 80)")
    p.add_argument("--max-args", type=int, default=15, help="most positional arguments of a kernel (default 15)")
    p.add_argument("--json", help="write the measurements as JSON")
    args = p.parse_args(argv)
    m = measure(Path(args.package).resolve(), args.max_file, args.max_function, args.max_args)
    print(report(m))
    if args.json:
        Path(args.json).write_text(json.dumps(m, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
