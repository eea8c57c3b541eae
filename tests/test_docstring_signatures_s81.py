"""The public API's docstrings and docs/*.md name what the code takes (session 81 audit).

For every function and class that gpmsa, control, roadgen and vehicle export in ``__all__``, and
the public methods of those classes: each name an ``Args:`` or ``Attributes:`` section lists is a
parameter (a class: a parameter, a field or an attribute), a default written there ("default
X", "X (the default)", ``name=X`` (the default)) is the signature's, and a dataclass's
constructor fields are all named in its docstring. In docs/*.md and README.md: every backticked
dotted name ``gpmsa.x.y`` resolves, and every keyword a backticked call of a public function
passes (``gpmsa.fit(..., n_chains=4)``) is one it takes (a backend option where it forwards
``**options``, a settings field where it forwards ``**overrides``)."""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import re
from functools import cache
from pathlib import Path

import pytest

import control
import gpmsa
import roadgen  # noqa: F401  (imported here, at collection: the tests read what it exports)
import vehicle  # noqa: F401

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("gpmsa", "control", "roadgen", "vehicle")
DOCS = (*sorted((ROOT / "docs").glob("*.md")), ROOT / "README.md")
ENTRY_SECTIONS = ("Args", "Arguments", "Attributes", "Parameters", "Keyword Args")
HEADER = re.compile(r"^(\s*)([A-Z][A-Za-z ]*):\s*(.*)$")
ENTRY = re.compile(
    r"^(\s*)(\*{0,2}[A-Za-z_]\w*(?:\s*,\s*\*{0,2}[A-Za-z_]\w*)*)(?:\s*\([^)]*\))?:(?:\s|$)"
)
INLINE = re.compile(  # not after "e.g. "/"i.e. ", nor prose's "default: 5", "note: ..."
    r"(?<=\. )(?<!e\.g\. )(?<!i\.e\. )(?!(?:defaults?|notes?)\b)"
    r"([a-z_][a-z0-9_]*(?:, [a-z_][a-z0-9_]*)*): "
)
LITERAL = r"`{0,2}([-+]?\d[\d,_]*(?:\.\d+)?(?:e[-+]?\d+)?%?(?![\w.])|[\w.\"'+-]+?)`{0,2}"
DEFAULT = re.compile(
    rf"\bdefaults?(?: is| to|:)?\s+{LITERAL}(?=[\s,;)]|\.?$)|{LITERAL}\s+\((?:the )?default\)",
    re.I,
)


def _own(obj) -> bool:
    return (getattr(obj, "__module__", "") or "").split(".")[0] in PACKAGES


@cache
def public_callables() -> tuple[tuple[str, object], ...]:
    """(qualified name, object) of every exported function and class and its own methods."""
    out = []
    for pkg in PACKAGES:
        module = importlib.import_module(pkg)
        for name in module.__all__:
            obj = getattr(module, name)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)) or not _own(obj):
                continue
            out.append((f"{pkg}.{name}", obj))
            if inspect.isclass(obj):
                for attr, value in vars(obj).items():
                    value = getattr(value, "__func__", value)  # static/class methods
                    if not attr.startswith("_") and inspect.isfunction(value):
                        out.append((f"{pkg}.{name}.{attr}", value))
    return tuple(out)


def _doc(obj) -> str:
    doc = inspect.getdoc(obj) or ""
    init = vars(obj).get("__init__") if inspect.isclass(obj) else None
    if init is not None and init.__doc__:
        doc += "\n" + inspect.getdoc(init)
    return doc


def _sections(doc: str) -> dict[str, list[str]]:
    """Google-style section name -> its lines (a section ends at a line that is not indented)."""
    out: dict[str, list[str]] = {}
    current = None
    for line in doc.splitlines():
        head = HEADER.match(line)
        if head and head.group(2) in (*ENTRY_SECTIONS, "Returns", "Raises", "Example", "Examples"):
            current = head.group(2)
            out.setdefault(current, [])
            if head.group(3):
                out[current].append("    " + head.group(3))
        elif current is not None:
            if line.strip() and not line.startswith((" ", "\t")):
                current = None
            else:
                out[current].append(line)
    return out


def entries(doc: str) -> dict[str, str]:
    """name -> its description, for each entry of the Args/Attributes sections: ``name:``,
    ``name (type):`` or ``a, b:`` at the entries' indent, and ``. name: ...`` inside one."""
    out: dict[str, str] = {}
    for section, lines in _sections(doc).items():
        if section not in ENTRY_SECTIONS:
            continue
        indent, names, text = None, [], []
        for line in lines:
            match = ENTRY.match(line)
            if match and (indent is None or len(match.group(1)) == indent):
                _close(out, names, text)
                indent = len(match.group(1))
                names = [n.strip().lstrip("*") for n in match.group(2).split(",")]
                text = [line[match.end() :]]
            elif line.strip():
                text.append(line)
        _close(out, names, text)
    return out


def _close(out: dict[str, str], names: list[str], text: list[str]) -> None:
    """One entry's names and lines into ``out``, with the "x: ... y: ..." entries it holds."""
    parts = INLINE.split(" ".join(" ".join(text).split()))
    for name in names:
        out.setdefault(name, parts[0])
    for k in range(1, len(parts) - 1, 2):
        for name in parts[k].split(", "):
            out.setdefault(name, parts[k + 1])


def _parameters(obj) -> dict[str, inspect.Parameter]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return {}
    return {n: p for n, p in sig.parameters.items() if n not in ("self", "cls")}


@cache
def _class_names(cls) -> frozenset[str]:
    """What a class's Attributes may name: its fields, attributes and those its code sets."""
    names = set(dir(cls))
    for klass in cls.__mro__:
        if not _own(klass):
            continue
        names |= set(getattr(klass, "__annotations__", {}))
        try:
            source = inspect.getsource(klass)
        except (OSError, TypeError):
            continue
        names |= set(re.findall(r"self\.([A-Za-z_]\w*)\s*(?::[^=\n]+)?=", source))
        names |= set(re.findall(r"__setattr__\(self, \"(\w+)\"", source))
    return frozenset(names)


def _literal(text: str):
    """A literal written in a docstring (numbers with separators, True/False/None, a quoted
    string), or the sentinel ``...`` where the text is no literal (prose, an expression)."""
    text = text.strip("`").rstrip(".").replace(",", "").replace("_", "")
    percent = text.endswith("%")
    try:
        value = ast.literal_eval(text[:-1] if percent else text)
    except (ValueError, SyntaxError):
        return ...
    if percent and isinstance(value, int | float):
        return value / 100
    return value


def _agrees(written, default) -> bool:
    if written is ... or isinstance(default, dataclasses.Field):
        return True
    if default is None:  # None: a value computed at the call ("default 129 for q = 1")
        return True
    if isinstance(default, bool) or isinstance(written, bool):
        return written is default
    if isinstance(default, int | float) and isinstance(written, int | float):
        return abs(written - default) <= 1e-12 * max(1.0, abs(default))
    if isinstance(default, str):
        return not isinstance(written, str) or written == default
    return True


def test_the_audit_sees_the_public_api():
    names = dict(public_callables())
    assert {"gpmsa.fit", "control.run_closed_loop", "roadgen.track", "vehicle.simulate"} <= set(
        names
    )
    assert "gpmsa.Calibrator.update" in names and len(names) > 200
    calibrator = entries(_doc(names["gpmsa.Calibrator"]))
    assert {"emulator", "method", "n_grid", "mcmc_options"} <= set(calibrator)
    run_campaign = entries(_doc(names["vehicle.run_campaign"]))
    assert {"model", "band", "rate_hz", "substeps", "progress"} <= set(run_campaign)  # inline
    assert "full grid" in run_campaign["band"]
    assert _literal("1,000") == 1000 and _literal("99.5%") == 0.995 and _literal("a") is ...


def test_listed_arguments_and_attributes_exist():
    stale = []
    for qualname, obj in public_callables():
        allowed = set(_parameters(obj))
        if inspect.isclass(obj):
            allowed |= _class_names(obj)
        stale += [f"{qualname}: {n}" for n in entries(_doc(obj)) if n not in allowed]
    assert not stale, "docstrings list names the signatures do not take:\n" + "\n".join(stale)


def test_written_defaults_are_the_signatures():
    wrong = []
    for qualname, obj in public_callables():
        params = _parameters(obj)
        doc = _doc(obj)
        found = []
        for name, text in entries(doc).items():
            if name in params:
                found += [(name, m.group(1) or m.group(2)) for m in DEFAULT.finditer(text)][:1]
        for name in params:
            pattern = rf"``{name}=([^`]+)``,? \(?(?:the|its)? ?default\b"
            found += [(name, m.group(1)) for m in re.finditer(pattern, doc)]
        for name, text in found:
            default = params[name].default
            if default is not inspect.Parameter.empty and not _agrees(_literal(text), default):
                wrong.append(
                    f"{qualname}: {name} documented default {text!r}, signature {default!r}"
                )
    assert not wrong, "\n".join(wrong)


def test_dataclass_fields_are_documented():
    missing = []
    for qualname, obj in public_callables():
        if inspect.isclass(obj) and dataclasses.is_dataclass(obj):
            doc = inspect.getdoc(obj) or ""
            for f in dataclasses.fields(obj):
                if f.init and not re.search(rf"(?<![\w.]){re.escape(f.name)}(?!\w)", doc):
                    missing.append(f"{qualname}.{f.name}")
    assert not missing, "constructor fields no docstring names: " + ", ".join(missing)


def _spans(text: str):
    for match in re.finditer(r"`+([^`\n]+?)`+", text):
        yield text.count("\n", 0, match.start()) + 1, match.group(1)


def _resolve(dotted: str):
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ModuleNotFoundError:
            continue
        for i, part in enumerate(parts[k:]):
            fields = getattr(obj, "__dataclass_fields__", {})
            if not hasattr(obj, part) and part not in fields:
                return ".".join(parts[: k + i + 1])
            obj = getattr(obj, part, None)
        return None
    return dotted


def test_dotted_names_in_the_docs_resolve():
    broken = []
    for path in DOCS:
        for line, span in _spans(path.read_text()):
            for dotted in re.findall(
                r"(?<![\w.])((?:gpmsa|control|roadgen|vehicle)(?:\.\w+)+)", span
            ):
                bad = _resolve(dotted)
                if bad is not None:
                    broken.append(f"{path.name}:{line}: {dotted} ({bad} does not exist)")
    assert not broken, "\n".join(broken)


@cache
def _backend_options() -> frozenset[str]:
    """The keywords of the backends' ``sample`` (read from the source: torch need not be
    installed), which ``gpmsa.fit`` and ``gpmsa.calibrate`` forward as ``**options``."""
    names = set()
    for path in (ROOT / "gpmsa" / "backends").glob("*_backend.py"):
        for node in ast.parse(path.read_text()).body:
            if isinstance(node, ast.FunctionDef) and node.name == "sample":
                args = node.args
                names |= {a.arg for a in (*args.args, *args.kwonlyargs)}
    return frozenset(names)


def _callables_by_name() -> dict[str, object]:
    """Names a doc writes a public callable by: ``gpmsa.fit``, ``fit`` (where one package
    exports it), ``Emulator.predict``, ``gpmsa.Emulator.predict``."""
    by_name, seen = {}, {}
    for qualname, obj in public_callables():
        pkg, *rest = qualname.split(".")
        by_name[qualname] = obj
        short = ".".join(rest)
        seen.setdefault(short, []).append(obj)
    by_name.update({k: v[0] for k, v in seen.items() if len(v) == 1})
    return by_name


def _forwarded(obj) -> frozenset[str] | None:
    """Keywords that ``obj``'s ``**kwargs`` take, or None: any."""
    fields = {f.name for f in dataclasses.fields(control.BCRSettings)}
    forwards = {
        gpmsa.fit: _backend_options(),
        gpmsa.calibrate: _backend_options(),
        control.bcr_settings_for: fields,
        control.BCR.from_emulator.__func__: fields,
        control.replay_bag: {f.name for f in dataclasses.fields(control.ReplaySettings)},
    }
    return frozenset(forwards[obj]) if obj in forwards else None


def _keywords(span: str, start: int) -> list[str]:
    """The keyword names of the call whose "(" is at ``start`` (at its top level)."""
    depth, token, out = 0, "", []
    for char in span[start:]:
        if char in "([{":
            depth += 1
            if depth == 1:
                continue
        elif char in ")]}":
            depth -= 1
            if depth == 0:
                break
        if char == "," and depth == 1:
            out.append(token)
            token = ""
        else:
            token += char
    out.append(token)
    return [m.group(1) for t in out if (m := re.match(r"\s*([A-Za-z_]\w*)\s*=(?!=)", t))]


def _ours(text: str) -> str:
    """``text`` without the first cells of tables that set SEPIA's or GPM/SA's calls (their
    first column) beside gpmsa's: SEPIA's ``sensitivity(..., ngrid=)`` is not gpmsa's."""
    lines, theirs, previous = [], False, ""
    for line in text.splitlines():
        if line.startswith("|") and not previous.startswith("|"):  # a table's header
            theirs = any(w in line.split("|")[1] for w in ("SEPIA", "GPM/SA"))
        if line.startswith("|") and theirs:
            line = "|" + "|".join(line.split("|")[2:])
        lines.append(line)
        previous = line
    return "\n".join(lines)


def test_keywords_the_docs_pass_exist():
    by_name = _callables_by_name()
    unknown, checked = [], 0
    for path in DOCS:
        for line, span in _spans(_ours(path.read_text())):
            for call in re.finditer(r"(?<![\w.])([A-Za-z_][\w.]*)\(", span):
                obj = by_name.get(call.group(1))
                if obj is None:
                    continue
                params = _parameters(obj)
                var = any(p.kind is p.VAR_KEYWORD for p in params.values())
                allowed = _forwarded(getattr(obj, "__func__", obj)) if var else frozenset()
                for kw in _keywords(span, call.end() - 1):
                    checked += 1
                    if kw not in params and not (var and (allowed is None or kw in allowed)):
                        unknown.append(f"{path.name}:{line}: {call.group(1)}(..., {kw}=)")
    assert checked > 300
    assert not unknown, "keywords the callables do not take:\n" + "\n".join(unknown)


@pytest.mark.parametrize(
    "doc, names",
    [
        ("Args:\n    a: one. b_c: two.\n    d, e (int): three.\n", ["a", "b_c", "d", "e"]),
        ("Attributes:\n    x: the x\n        (more: text)\n    y: the y\n", ["x", "y"]),
        # prose inside an entry is no entry (it read "default" and "m" as names taken)
        ("Args:\n    n: nodes per axis. default: 129. m: runs.\n", ["n", "m"]),
        ("Args:\n    u: the unit (e.g. m: metres; i.e. s: seconds). note: kept.\n", ["u"]),
    ],
)
def test_the_entry_parser(doc, names):
    assert list(entries(doc)) == names


def test_a_default_written_after_a_sentence_is_read():
    text = entries("Args:\n    n: nodes per axis. default: 129\n")["n"]
    assert [m.group(1) for m in DEFAULT.finditer(text)] == ["129"], text
