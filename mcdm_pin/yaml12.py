"""Reading YAML safely and as YAML 1.2: no duplicate keys, no YAML 1.1 surprises, bounded aliases.

PyYAML's ``safe_load`` speaks YAML 1.1: it reads ``1:30`` as the sexagesimal number 90, ``0100`` as the
octal 64 and ``yes``/``on`` as booleans, and it lets a repeated key silently replace the first (a second
``cables:`` block dropping the first one). :func:`load` reads with the YAML 1.2 core schema instead
(``0100`` is 100, ``1:30`` a string, only ``true``/``false`` are booleans, ``1e3`` is a number),
rejects a repeated key naming both lines, and refuses documents whose aliases expand beyond
:data:`~mcdm_pin.limits.MAX_YAML_NODES` nodes before anything walks them (an alias bomb of a few hundred
bytes expands to billions). Errors are :class:`YamlError` with a line number.
"""

from __future__ import annotations

import re

import yaml
from yaml.nodes import MappingNode, ScalarNode, SequenceNode

from .limits import MAX_YAML_ALIASES, MAX_YAML_DEPTH, MAX_YAML_NODES

_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_FLOAT = re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$")
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")


class YamlError(ValueError):
    """Malformed or unsafe YAML: ``line`` (1-based, or None) and ``problem``."""

    def __init__(self, problem: str, line: int | None = None):
        self.problem, self.line = problem, line
        super().__init__(f"{problem}" + (f" (line {line})" if line else ""))


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 core-schema implicit types, duplicate-key and alias checks."""

    def __init__(self, stream):
        super().__init__(stream)
        self._aliases = 0
        self._depth = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_YAML_ALIASES:
                mark = self.peek_event().start_mark
                raise YamlError(f"more than {MAX_YAML_ALIASES} aliases", mark.line + 1)
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                mark = self.peek_event().start_mark
                raise YamlError(f"nested more than {MAX_YAML_DEPTH} levels deep", mark.line + 1)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):
        seen: dict = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            try:
                hash(key)
            except TypeError:
                raise YamlError("a mapping key must be a plain value", key_node.start_mark.line + 1) from None
            if key in seen:
                raise YamlError(f"duplicate key {key!r} at line {key_node.start_mark.line + 1} (first at line "
                                f"{seen[key]}): a repeated key would silently replace the first",
                                key_node.start_mark.line + 1)
            seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)


# YAML 1.2 core schema: replace PyYAML's YAML 1.1 implicit resolvers
_Loader.yaml_implicit_resolvers = {}
for _tag, _regex, _first in (
        ("tag:yaml.org,2002:bool", _BOOL, list("tTfF")),
        ("tag:yaml.org,2002:int", _INT, list("-+0123456789")),
        ("tag:yaml.org,2002:float", _FLOAT, list("-+.0123456789")),
        ("tag:yaml.org,2002:null", _NULL, ["~", "n", "N", ""])):
    _Loader.add_implicit_resolver(_tag, _regex, _first)


def _construct_int(loader, node):
    text = loader.construct_scalar(node)
    if text.startswith("0o"):
        return int(text[2:], 8)
    if text.startswith("0x"):
        return int(text[2:], 16)
    return int(text)


def _construct_float(loader, node):
    text = loader.construct_scalar(node).lower()
    if text.endswith(".inf"):
        return float("-inf") if text.startswith("-") else float("inf")
    if text == ".nan":
        return float("nan")
    return float(text)


_Loader.add_constructor("tag:yaml.org,2002:int", _construct_int)
_Loader.add_constructor("tag:yaml.org,2002:float", _construct_float)


def _expanded_size(node, memo: dict) -> int:
    """Nodes reachable from ``node`` counting every alias use (shared subtrees counted per use)."""
    key = id(node)
    if key in memo:
        if memo[key] is None:
            raise YamlError("a recursive alias (a value that contains itself)", node.start_mark.line + 1)
        return memo[key]
    memo[key] = None  # in progress: meeting it again below is a cycle
    if isinstance(node, ScalarNode):
        size = 1
    elif isinstance(node, SequenceNode):
        size = 1 + sum(_expanded_size(n, memo) for n in node.value)
    elif isinstance(node, MappingNode):
        size = 1 + sum(_expanded_size(k, memo) + _expanded_size(v, memo) for k, v in node.value)
    else:
        size = 1
    memo[key] = min(size, 2 * MAX_YAML_NODES)
    return memo[key]


def load(text: str):
    """The document in ``text`` (one), read as YAML 1.2 with the checks of the module docstring."""
    loader = None
    try:
        loader = _Loader(text)  # the reader checks the characters here already
        node = loader.get_single_node()
        if node is None:
            return None
        if _expanded_size(node, {}) > MAX_YAML_NODES:
            raise YamlError(f"the document expands to more than {MAX_YAML_NODES} nodes through its aliases "
                            f"(an alias bomb?)", node.start_mark.line + 1)
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise YamlError(problem, mark.line + 1 if mark else None) from None
    except RecursionError:
        raise YamlError("nesting too deep") from None
    finally:
        if loader is not None:
            loader.dispose()
