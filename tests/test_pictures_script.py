"""tools/make_pictures.py runs the commands the docs show (issue 27 item 3): every picture under
docs/img is made by it, and each picture's commands are those of one code block of the page it names,
in that order (continuation lines joined, comments dropped). Nothing is rendered here."""

from __future__ import annotations

import importlib.util
import re
import sys

from .conftest import REPO


def _script():
    spec = importlib.util.spec_from_file_location("make_pictures", REPO / "tools" / "make_pictures.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("make_pictures", module)  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def doc_commands(text: str) -> list[list[str]]:
    """The shell commands of each fenced code block (``bash``, ``sh`` or no language) of a Markdown
    page: continuation lines joined, comments and blank lines dropped, spaces collapsed."""
    blocks, block, lang = [], None, ""
    for line in text.splitlines():
        if line.startswith("```"):
            if block is None:
                block, lang = [], line[3:].strip()
            else:
                if lang in ("bash", "sh", ""):
                    blocks.append("\n".join(block))
                block = None
        elif block is not None:
            block.append(line)
    out = []
    for body in blocks:
        joined = re.sub(r"\\\n\s*", " ", body)
        lines = [re.sub(r"\s+#.*$", "", ln).strip() for ln in joined.splitlines()]
        out.append([" ".join(ln.split()) for ln in lines if ln and not ln.startswith("#")])
    return out


def _in_order(commands, block) -> bool:
    it = iter(block)
    return all(any(c == b for b in it) for c in commands)


def test_every_picture_is_made_by_the_script():
    names = {p.name for p in _script().PICTURES}
    pictures = {p.stem for p in (REPO / "docs" / "img").glob("*.png")}
    assert pictures == names, (sorted(pictures - names), sorted(names - pictures))
    for pic in _script().PICTURES:
        written = any(f"docs/img/{pic.name}.png" in c or "--out docs/img" in c for c in pic.commands)
        assert written or f"docs/img/{pic.name}.png" in (REPO / pic.doc).read_text(), pic.name  # a script's default


def test_the_scripts_commands_are_the_docs():
    for pic in _script().PICTURES:
        text = (REPO / pic.doc).read_text()
        assert f"img/{pic.name}.png" in text or pic.doc == "docs/speed.md", \
            f"{pic.doc} does not show {pic.name}.png"
        blocks = doc_commands(text)
        commands = [" ".join(c.split()) for c in pic.commands]
        assert any(_in_order(commands, b) for b in blocks), \
            f"{pic.name}: {pic.doc} has no code block with {commands}"


def test_docs_paths_exist_in_a_clone():
    """No command the docs show reads a build/... path (which only an import on the author's
    machine made); every robot a command reads is committed."""
    for page in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for block in doc_commands(page.read_text()):
            for cmd in block:
                assert "build/" not in cmd, f"{page.name}: {cmd}"
                for path in re.findall(r"\brobots/\S+\.(?:yaml|xml)\b", cmd):
                    assert (REPO / path).is_file(), f"{page.name}: {path} (in {cmd!r}) is not committed"


def test_the_commands_parse():
    """Each command's arguments are accepted by mcdm-pin's parser (no run)."""
    from mcdm_pin.cli import build_parser

    parser = build_parser()
    mod = _script()
    for pic in mod.PICTURES:
        for c in pic.commands:
            words = mod.argv(c)
            if words[1:3] == ["-m", "mcdm_pin"]:
                parser.parse_args(words[3:])
