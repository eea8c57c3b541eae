"""What the library's messages and option help name exists (session 83's sweep of the advice
that error and warning messages give): every ``docs/<file>.md`` a message string names is a
file of docs/, and a section it names with it (``docs/closed-loop.md, Guards``, ``docs/robot.md,
section 4``) is a heading there; every ``--flag`` a message names is an option of one of the
project's command lines (its scripts', ``gpmsa``'s, ``terrain-replay``'s)."""

import ast
import re
from functools import cache
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("gpmsa", "control", "roadgen", "vehicle", "examples", "benchmarks")
FLAG = r"(?<![\w-])--[a-z][a-z0-9-]*"
OTHER_FLAGS = {"--help", "--version", "--upgrade"}  # argparse's own, pip's (install advice)


def _text(node: ast.AST) -> str | None:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return node.value
    if isinstance(node, ast.JoinedStr):
        return "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
    return None


@cache
def _sources(holding: str) -> list[tuple[str, ast.Module]]:
    """(file, syntax tree) of the project's modules whose text matches ``holding``."""
    texts = {p: p.read_text(encoding="utf-8") for d in PACKAGES for p in (ROOT / d).rglob("*.py")}
    return [(str(p.relative_to(ROOT)), ast.parse(text))
            for p, text in sorted(texts.items()) if re.search(holding, text)]  # fmt: skip


@cache
def _strings(holding: str) -> list[tuple[str, int, str]]:
    """(file, line, text) of every string literal that is not a docstring (f-strings' holes as
    {}) and matches ``holding``."""
    out = []
    for name, tree in _sources(holding):
        docs, parts = set(), set()
        for node in ast.walk(tree):
            body = getattr(node, "body", None)
            if isinstance(body, list) and body and isinstance(body[0], ast.Expr):
                docs.add(id(body[0].value))
            if isinstance(node, ast.JoinedStr):
                parts.update(id(v) for v in node.values)
        skip = docs | parts
        for node in ast.walk(tree):
            text = None if id(node) in skip else _text(node)
            if text and re.search(holding, text):
                out.append((name, node.lineno, text))
    return out


def _headings(doc: Path) -> list[str]:
    lines = doc.read_text(encoding="utf-8").splitlines()
    return [line.lstrip("#").strip() for line in lines if line.startswith("#")]


def test_every_docs_file_and_section_a_message_names_exists():
    named = 0
    for where, line, text in _strings("docs/"):
        for m in re.finditer(r"docs/([\w.-]+\.md)(?:, ([^,;)]+))?", text):
            doc = ROOT / "docs" / m.group(1)
            assert doc.is_file(), f"{where}:{line} names {m.group(0)!r}"
            named += 1
            section = m.group(2)
            if section is None or section.split()[0] in ("says", "has", "the"):
                continue  # (a sentence goes on, names no section)
            heads = _headings(doc)
            number = re.fullmatch(r"section (\d+)", section)
            if number:
                ok = any(h.startswith(f"{number.group(1)}.") for h in heads)
            else:
                ok = any(h.startswith(section.strip("'\" ")) for h in heads)
            assert ok, f"{where}:{line}: {m.group(1)} has no section {section!r}"
    assert named >= 5


def test_every_command_line_flag_a_message_names_is_an_option():
    flags = set(OTHER_FLAGS)
    for _, tree in _sources("add_argument"):
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "add_argument":
                flags.update(a.value for a in node.args if isinstance(a, ast.Constant))
    named = [(where, line, flag) for where, line, text in _strings(FLAG)
             for flag in re.findall(FLAG, text)]  # fmt: skip
    missing = [item for item in named if item[2] not in flags]
    assert not missing
    assert len(named) > 50
