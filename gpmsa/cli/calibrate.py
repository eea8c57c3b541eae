"""``gpmsa calibrate FILE --x v=1.25 --y f=12.1``: print the posterior of one observation
(``--y-csv PATH``: its outputs from a CSV file, a functional output's many values; ``--fixed
GD=400`` holds a calibration parameter, or lamOs, at a known value: MCMC), and name each
calibration parameter piled against a bound of the emulator's domain (``gpmsa.mcmc.bounds``:
the command is a one-off, unlike the Calibrator's updates in a loop, which stay silent)."""

from __future__ import annotations

import argparse
import csv
import itertools
import json
import re
import sys
import time
import warnings

import numpy as np

from gpmsa.calibration.posterior import quantile_keys
from gpmsa.cli.text import internal_error, numbers, safe
from gpmsa.errors import GPMSAError
from gpmsa.io.container import home_path, jsonable
from gpmsa.model.data import check_seed

Y_CSV_MAX_BYTES = 64 * 1024**2
"""Most bytes of a ``--y-csv`` file read (one observation's values take far fewer); a longer
file, or a device or pipe that never ends, is refused at this size."""
Y_CSV_FIELDS_PER_OUTPUT = 4
"""Most fields a ``--y-csv`` file's rows hold together, per output of the emulator file: twice
a header row and one row of values (n fields each); the line that takes the file past them
is refused without reading on (a file of a few more values than the outputs is named as such)."""
_LINE_BREAKS = "\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029"
"""The characters that end a line, as ``str.splitlines`` reads them (CR LF one break)."""
SPREADSHEET_ERRORS = ("#N/A", "#VALUE!", "#REF!", "#DIV/0!", "#NUM!", "#NAME?", "#NULL!")
"""A spreadsheet's error values (its missing value "#N/A" among them): a field that starts a
line with one is a value to refuse, not a comment."""
_ERROR_VALUE = "|".join(re.escape(e[1:]) for e in SPREADSHEET_ERRORS)


def _skipped_pattern(possessive: bool = True, most: int | None = None) -> str:
    """The pattern of `_SKIPPED`: possessive quantifiers (Python >= 3.11), or, for Python 3.10's
    re, which has none, greedy ones (the same matches: nothing after them can fail, so they
    never give back) and at most ``most`` lines a match (a greedy group repeat holds a few
    hundred bytes a repeat until the match ends: 0.5 GB for a million comment lines)."""
    p = "+" if possessive else ""
    blank_next = (  # blanks and a number or another error value: a blank-separated line
        rf" +{p}(?:[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|#(?:{_ERROR_VALUE}))(?:\s|$)"
    )
    repeat = f"*{p}" if most is None else f"{{0,{most}}}"
    return (
        rf"(?:\s+{p}|#(?!(?:{_ERROR_VALUE})(?: *{p}(?:[,;\t{_LINE_BREAKS}]|$)|{blank_next}))"
        rf"[^{_LINE_BREAKS}]*{p}){repeat}"
    )


_SKIPPED_MOST = 1024
"""Python 3.10: the most blank runs and comment lines `_SKIPPED` passes in one match."""
_SKIPPED = re.compile(
    _skipped_pattern() if sys.version_info >= (3, 11) else _skipped_pattern(False, _SKIPPED_MOST)
)
"""Blank lines and lines starting with "#" (the next line's leading blanks too), from a line's
start (re's whitespace is ``str.isspace``'s, every line break among it); a line that starts
with a spreadsheet's error value (`SPREADSHEET_ERRORS`) as its first field is no comment: one
ending the line or followed by a separator, or by blanks and a number or another error value
(a blank-separated line; "#N/A means missing" is a comment). `_skipped_end` matches it."""
_MISSING_MARKS = frozenset({"na", "n/a", "null", "none", "-", "--", "?", "missing",
                            *(e.lower() for e in SPREADSHEET_ERRORS)})  # fmt: skip
"""Fields (lower case) that mark a missing value in files from spreadsheets, loggers and
pandas (``to_csv``'s ``na_rep``)."""
_GROUPED = re.compile(r"[+-]?[\d.,;'\"\s\u00a0\u202f]*\d[\d.,;'\"\s\u00a0\u202f]*")
"""A field of digits with separators no float holds: a decimal comma ("1,5"), digit grouping
("1,234.5", "1.234,5", "1 234", "1'234"), or a semicolon-separated line's values split at its
decimal commas ("5;2")."""
_LINE = re.compile(rf"[^{_LINE_BREAKS}]*")
_WORD = re.compile(r"\S+")
_FIELD = {sep: re.compile(rf' *(?:"(?:[^"]|"")*"?)?[^{sep}]*') for sep in ",;"}
"""One CSV field as ``csv.reader(delimiter=sep, skipinitialspace=True)`` reads it: blanks, a
quoted part (doubled quotes inside; to the line's end if never closed), then up to ``sep``."""


def add_parser(sub) -> None:
    """Add the ``calibrate`` subcommand to an argparse subparsers object."""
    p = sub.add_parser(
        "calibrate",
        help="calibrate an emulator file on one observation and print the posterior summary",
    )
    p.add_argument("file", help="path to a .gpmsa file")
    p.add_argument("--x", action="append", default=[], metavar="NAME=VALUE",
                   help="a known input, native units (repeat for each x name)")  # fmt: skip
    p.add_argument("--y", action="append", default=[], metavar="NAME=VALUE",
                   help="an observed output, native units (repeat for each y name)")  # fmt: skip
    p.add_argument("--y-csv", default=None, metavar="PATH",
                   help="the observed outputs from a CSV file instead of --y: the "
                        "observation's values in one row (or one column), in the order of "
                        "the file's y names, or under a header row of those names")  # fmt: skip
    p.add_argument("--fixed", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a calibration parameter (a t_name, or lamOs) at VALUE, native "
                        "units (repeat for each; MCMC)")  # fmt: skip
    p.add_argument("--method", choices=("auto", "grid", "mcmc"), default="auto",
                   help="exact grid (1-2 parameters) or MCMC (default: auto, MCMC with "
                        "--fixed)")  # fmt: skip
    p.add_argument("--level", type=_level, default=0.9, help="central interval level (0.9)")
    p.add_argument("--seed", type=_seed, default=None,
                   help="seed of the draws / MCMC, an integer in [0, 2**128)")  # fmt: skip
    p.add_argument(
        "--extrapolate",
        action="store_true",
        help="allow x more than 10%% of its width outside the domain",
    )
    p.add_argument("--json", action="store_true", help="print JSON for programs")
    p.set_defaults(func=run)


def _seed(text: str) -> int:
    """argparse type of --seed: an integer in [0, 2**128) (`check_seed`), checked before the
    file is read."""
    shown = repr(text) if len(text) <= 60 else f"{text[:40]!r}... ({len(text)} characters)"
    out_of_range = argparse.ArgumentTypeError(
        f"{shown} is out of range: allowed integers in [0, 2**128)"
    )
    try:
        seed = int(text)
    except ValueError:  # int() refuses over 4,300 digits (sys.get_int_max_str_digits): no seed
        if re.fullmatch(r"\s*[+-]?\d+(_\d+)*\s*", text):
            raise out_of_range from None
        raise argparse.ArgumentTypeError(f"{shown} is not an integer") from None
    try:
        return check_seed(seed)
    except GPMSAError:
        raise out_of_range from None


def _level(text: str) -> float:
    """argparse type of --level: a number in (0, 1) whose interval ends differ from the median
    in float64 (checked before any work)."""
    try:
        level = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not 0 < level < 1:  # NaN too
        raise argparse.ArgumentTypeError(f"{text!r} must lie in (0, 1)")
    try:
        quantile_keys(level)
    except GPMSAError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return level


def _given(items: list[str], names: tuple[str, ...], what: str) -> dict[str, float]:
    """NAME -> value from NAME=VALUE strings (split at the last "=": a name may hold "=", a
    number never does). A NAME that is not one of ``names`` is read without its surrounding
    spaces (``" v=1"`` gives v); one that is, whole (a name may end in a space). GPMSAError for
    an item without "=", a name given twice or a value that is not a finite number (named here,
    as a --y-csv file's: the library would name x_obs or y_obs)."""
    given = {}
    for item in items:
        name, sep, value = item.rpartition("=")
        if not sep:
            raise GPMSAError(f"--{what} expects NAME=VALUE, got {item!r}")
        key = name if name in names else name.strip()
        if key in given:  # the later one silently won
            raise GPMSAError(f"--{what} {key} is given twice; give each name once")
        try:
            if "_" in value:  # float() reads "1_0" as 10: a typo for 1.0 must not pass
                raise ValueError(value)
            given[key] = float(value)
        except ValueError as exc:
            raise GPMSAError(f"--{what} {name}: {value!r} is not a number") from exc
        if not np.isfinite(given[key]):
            overflow = np.isinf(given[key]) and "inf" not in value.lower()  # e.g. 1e400
            beyond = " (beyond float64's range)" if overflow else ""
            raise GPMSAError(f"--{what} {key}: {value.strip()} is not a finite number{beyond}")
    return given


def _pairs(items: list[str], names: tuple[str, ...], what: str) -> np.ndarray:
    """Values ordered as ``names`` from NAME=VALUE strings (`_given`), one for every name (a
    name with surrounding blanks, as a table's header may give it, also without them)."""
    bare = dict(zip(_bare(names), names, strict=True))  # " v " (a CSV header's) given as v
    given = {}
    for key, value in _given(items, names, what).items():
        name = key if key in names else bare.get(key, key)
        if name in given:
            raise GPMSAError(f"--{what} {name} is given twice; give each name once")
        given[name] = value
    unknown = sorted(set(given) - set(names))
    missing = [n for n in names if n not in given]
    if unknown and not names:  # x of a file with p = 0
        raise GPMSAError(f"--{what} {', '.join(unknown)}: the file has no known inputs "
                         f"({what}); leave --{what} out")  # fmt: skip
    if unknown or missing:
        raise GPMSAError(
            f"--{what} needs exactly the names {list(names)}; unknown {unknown}, missing {missing}"
        )
    return np.array([[given[n] for n in names]])


def _observed(args: argparse.Namespace, names: tuple[str, ...]) -> np.ndarray:
    """The observation's outputs (1, l_sim), ordered as ``names``: from ``--y`` pairs, or from
    ``--y-csv`` (`_csv_row`); GPMSAError for both, or neither where outputs are missing (the
    advice names --y-csv for a vector output)."""
    if args.y_csv is not None:
        if args.y:
            raise GPMSAError("give the observed outputs by --y NAME=VALUE or by --y-csv PATH, "
                             "not both")  # fmt: skip
        return _csv_row(args.y_csv, names)[None, :]
    try:
        return _pairs(args.y, names, "y")
    except GPMSAError as exc:
        if len(names) > 1 and not args.y:
            raise GPMSAError(f"{exc} (or --y-csv PATH: the {len(names)} values in one row or "
                             "one column of a CSV file)") from None  # fmt: skip
        raise


def _csv_row(path: str, names: tuple[str, ...]) -> np.ndarray:
    """The values (len(names),) of one observation from the CSV file ``path``: one row or one
    column of numbers (`_fields`; blank lines and lines starting with "#" skipped), in the
    order of ``names``, or under a first row that names the columns (exactly ``names``, any
    order: read by name; a row of no numbers, not all of them `_value_like`, or of those names
    above another row); a leading ``~`` the home folder, as for FILE. UTF-8 (a
    byte order mark skipped) or UTF-16 with its byte order mark; an empty last field ending
    every line (a spreadsheet's empty last column) dropped; header names matched without the
    names' surrounding blanks (`_bare`).
    GPMSAError naming the file, and the row and column, for a file that cannot be read or
    holds more than ``Y_CSV_MAX_BYTES``, rows of more than ``Y_CSV_FIELDS_PER_OUTPUT`` fields
    per name together (refused at the line that passes them, `_rows`), a field that is not a
    finite number (`_not_a_value`: a missing-value mark, a decimal comma or digit grouping
    named as such) or holds bytes that are not UTF-8 (`_check_utf8`), rows of unequal length
    (the header row too), or another count of values."""
    where = f"--y-csv {safe(path, 200)}"
    try:
        with open(home_path(path), "rb") as fh:  # a pipe or device may never end: bounded
            raw = _bounded_read(fh, Y_CSV_MAX_BYTES + 1)
    except OSError as exc:
        raise GPMSAError(f"{where}: cannot read it ({type(exc).__name__}: {exc})") from None
    if len(raw) > Y_CSV_MAX_BYTES:  # (before decoding: the limit may cut a character)
        raise GPMSAError(
            f"{where}: it holds more than {Y_CSV_MAX_BYTES} bytes, more than one observation's "
            "values take (gpmsa.cli.calibrate.Y_CSV_MAX_BYTES)"
        )
    utf16 = raw.startswith((b"\xff\xfe", b"\xfe\xff"))
    if not utf16 and b"\0" in raw:  # no text file holds NUL bytes
        raise GPMSAError(
            f"{where}: it holds NUL bytes, which no UTF-8 text holds: UTF-16 without its byte "
            "order mark (or not a text file)? Save it as UTF-8 (or as UTF-16 with its mark)"
        )
    try:  # UTF-16 with its byte order mark (a spreadsheet's "Unicode text"), else UTF-8
        text = raw.decode("utf-16") if utf16 else raw.decode("utf-8-sig", "surrogateescape")
    except UnicodeDecodeError as exc:
        raise GPMSAError(f"{where}: cannot read it ({type(exc).__name__}: {exc})") from None
    try:
        rows = _rows(text, where, names)
    except csv.Error as exc:  # a field beyond csv's size limit
        raise GPMSAError(f"{where}: cannot read it as CSV ({safe(exc, 200)})") from None
    if not rows:
        raise GPMSAError(f"{where}: the file holds no values (give the {len(names)} observed "
                         "outputs in one row or one column)")  # fmt: skip
    rows = [(k, [f.strip() for f in fields]) for k, fields in rows]
    _check_utf8(where, rows)
    trailing = all(len(f) > 1 and not f[-1] for _, f in rows)  # a separator ending every line
    if trailing:
        rows = [(k, fields[:-1]) for k, fields in rows]
    header = None
    first = rows[0][1]  # a row of names (numbers too where they are the outputs' names)
    no_number = not any(_number(f) is not None for f in first)
    if (no_number and not all(map(_value_like, first))) or (  # not only marks or "1,5"s
        len(rows) > 1 and sorted(first) == sorted(_bare(names))
    ):
        (header_line, header), rows = rows[0], rows[1:]
    widths = {len(fields) for _, fields in rows}
    if len(widths) > 1:
        (k0, first), (k, other) = rows[0], next(r for r in rows if len(r[1]) != len(rows[0][1]))
        raise GPMSAError(f"{where}: line {k} has {len(other)} fields, line {k0} {len(first)}: "
                         "every row must have the same number of columns")  # fmt: skip
    values = []
    for k, fields in rows:
        for c, field in enumerate(fields, 1):
            v = _number(field)
            if v is None or not np.isfinite(v):
                raise GPMSAError(f"{where}: line {k}, column {c} {_not_a_value(field, v)}")
            values.append(v)
    n_rows, n_cols = len(rows), (widths.pop() if widths else 0)
    if header is not None:
        return _by_header(where, (header_line, header), rows, names)
    if len(values) != len(names) or (n_rows > 1 and n_cols > 1):
        dropped = " (the empty last column, a separator ending every line, dropped)"
        raise GPMSAError(
            f"{where}: {n_rows} row(s) x {n_cols} column(s) of values"
            f"{dropped if trailing else ''}; the file's outputs are "
            f"{len(names)} ({_names_text(names)}): give the one observation's {len(names)} "
            "values in one row or one column (this command calibrates on one observation; "
            "for several, gpmsa.calibrate in Python)"
        )
    return np.array(values)


def _value_like(field: str) -> bool:
    """Whether ``field`` is a value, not a name: a number, a number written with a decimal
    comma or digit grouping, or a missing-value mark (all refused later, naming the field)."""
    return (_number(field) is not None or field.lower() in _MISSING_MARKS
            or _GROUPED.fullmatch(field) is not None)  # fmt: skip


def _not_a_value(field: str, value: float | None) -> str:
    """Why the field ``field`` (`_number`: ``value``) is no value, for a message: empty, a
    missing-value mark, a number written with a decimal comma or digit grouping, not finite,
    or not a number."""
    shown = repr(safe(field, 40))
    missing = " (a missing value? give every output's value)"
    if not field:
        return "is empty (a missing value?)"
    if value is not None:
        beyond = np.isinf(value) and "inf" not in field.lower()  # 1e400
        why = missing if np.isnan(value) else " (beyond float64's range)" if beyond else ""
        return f"{shown} is not a finite number{why}"
    if field.lower() in _MISSING_MARKS:
        return f"{shown} is not a number{missing}"
    if _GROUPED.fullmatch(field):
        return (f"{shown} is not a number: a decimal comma or a thousands separator? The "
                "file is read with '.' as the decimal mark and no digit grouping: save it "
                "so (a spreadsheet's CSV in an English locale, or numpy.savetxt)")  # fmt: skip
    return f"{shown} is not a number"


def _check_utf8(where: str, rows: list[tuple[int, list[str]]]) -> None:
    """GPMSAError naming the line and column of the first field that holds bytes that are not
    UTF-8 (decoded as surrogates; such bytes in a skipped comment line do no harm)."""
    for k, fields in rows:
        for c, field in enumerate(fields, 1):
            bad = re.search("[\udc80-\udcff]", field)
            if bad:
                byte = ord(bad.group()) - 0xDC00
                raise GPMSAError(f"{where}: line {k}, column {c} holds the byte 0x{byte:02x}, "
                                 "which is not UTF-8 (a latin-1 or Windows file?): save the "
                                 "file as UTF-8 (a spreadsheet's \"CSV UTF-8\")")  # fmt: skip


def _bounded_read(fh, most: int, chunk: int = 1024**2) -> bytes:
    """At most ``most`` bytes of the binary file ``fh``, read a ``chunk`` at a time (a single
    ``read(most)`` sets aside ``most`` bytes, however short the file)."""
    parts, size = [], 0
    while size < most and (part := fh.read(min(chunk, most - size))):
        parts.append(part)
        size += len(part)
    return b"".join(parts)


def _rows(text: str, where: str, names: tuple[str, ...]) -> list[tuple[int, list[str]]]:
    """The lines of ``text`` that hold values, as (line number, fields) (`_fields`; blank lines
    and lines starting with "#" skipped); GPMSAError naming the line that takes the fields past
    ``Y_CSV_FIELDS_PER_OUTPUT`` per name, before its fields or any later line are read."""
    bound = Y_CSV_FIELDS_PER_OUTPUT * len(names)
    rows, seen = [], 0
    for k, line in _lines(text):
        if seen + _field_count(line, bound - seen) > bound:
            raise GPMSAError(
                f"{where}: line {k} takes the file past {bound} fields "
                f"({Y_CSV_FIELDS_PER_OUTPUT} per output: twice a header row and one row of "
                f"values); the file's outputs are {len(names)} ({_names_text(names)}): give "
                f"the one observation's {len(names)} values in one row or one column (this "
                "command calibrates on one observation; for several, gpmsa.calibrate in Python)"
            )
        rows.append((k, _fields(line)))
        seen += len(rows[-1][1])
    return rows


def _lines(text: str):
    """(line number, line) of each line of ``text`` that holds values (not blank, not starting
    with "#"), numbered as ``str.splitlines`` splits them; the lines between are passed over
    in one step (a file of millions of them takes no step per line)."""
    pos, k = 0, 1
    while pos < len(text):
        run = _skipped_end(text, pos)
        if run == len(text):
            return
        start = max(pos - 1, *(text.rfind(c, pos, run) for c in _LINE_BREAKS)) + 1
        k += _breaks(text, pos, start)
        end = _LINE.match(text, start).end()
        yield k, text[start:end]
        pos, k = end + (2 if text.startswith("\r\n", end) else 1), k + 1


def _skipped_end(text: str, pos: int, pattern: re.Pattern[str] = _SKIPPED) -> int:
    """Where the blank and comment lines that start at ``pos`` end (``pattern``: `_SKIPPED`);
    a pattern of at most some lines a match (Python 3.10's) is matched again where it ended."""
    while (end := pattern.match(text, pos).end()) > pos:
        pos = end
    return pos


def _breaks(text: str, start: int, end: int) -> int:
    """The line breaks in ``text[start:end]``, CR LF one."""
    count = sum(text.count(c, start, end) for c in _LINE_BREAKS)
    return count - text.count("\r\n", start, end)


def _field_count(line: str, most: int) -> int:
    """The number of fields `_fields` splits ``line`` into, counted up to ``most`` + 1 (a
    longer line is not split: its count is all that is read)."""
    sep = next((s for s in ",;" if s in line), None)
    if sep is None:  # blanks: ``str.split``'s words (re's \S is str.isspace's complement)
        return sum(1 for _ in itertools.islice(_WORD.finditer(line), most + 1))
    pattern, pos, count = _FIELD[sep], 0, 0
    while True:
        pos = pattern.match(line, pos).end() + 1  # the field and its separator
        count += 1
        if pos > len(line) or count > most:
            return count


def _fields(line: str) -> list[str]:
    """One CSV line's fields: split at commas (a field in double quotes as CSV writers quote
    names, its quotes dropped), else at semicolons (a spreadsheet's CSV in some locales), else
    at blanks (as ``numpy.savetxt`` writes a row)."""
    for sep in (",", ";"):
        if sep in line:
            return next(csv.reader([line], delimiter=sep, skipinitialspace=True))
    return line.split()


def _by_header(
    where: str, head: tuple[int, list[str]], rows: list, names: tuple[str, ...]
) -> np.ndarray:
    """The one row under the header row ``head`` ((its line number, the columns' names: exactly
    ``names``, any order)), with one value under each name, ordered as ``names``; GPMSAError
    otherwise."""
    header_line, header = head
    keys = _bare(names)  # a header's fields are read without their surrounding blanks
    unknown = [h for h in header if h not in keys]
    missing = [n for n, key in zip(names, keys, strict=True) if key not in header]
    twice = sorted({h for h in header if header.count(h) > 1})
    if unknown or missing or twice:
        case = ""
        if unknown and sorted(h.lower() for h in unknown) == sorted(n.lower() for n in missing):
            case = " (names are case-sensitive: give them as the file's outputs spell them)"
        raise GPMSAError(f"{where}: the header row must name the file's outputs "
                         f"({_names_text(names)}) once each; unknown {safe(unknown, 200)}, "
                         f"missing {safe(missing, 200)}, twice {safe(twice, 200)}"
                         f"{case}")  # fmt: skip
    if len(rows) != 1:
        raise GPMSAError(f"{where}: under a header row give one row of values (one "
                         f"observation), got {len(rows)}")  # fmt: skip
    k, fields = rows[0]
    if len(fields) != len(header):  # a value without a name, or a name without a value
        raise GPMSAError(
            f"{where}: line {k} has {len(fields)} fields, the header row (line {header_line}) "
            f"{len(header)}: give one value under each name"
        )
    row = [_number(f) for f in fields]
    return np.array([row[header.index(key)] for key in keys])


def _bare(names: tuple[str, ...]) -> tuple[str, ...]:
    """``names`` without their surrounding blanks (as a CSV row's fields are read), where that
    leaves them apart; else ``names`` as they are."""
    bare = tuple(n.strip() for n in names)
    return bare if len(set(bare)) == len(bare) else tuple(names)


def _names_text(names: tuple[str, ...]) -> str:
    """The names for a message: all of up to 4, else the first two ... the last."""
    shown = list(names) if len(names) <= 4 else [names[0], names[1], "...", names[-1]]
    return safe(", ".join(shown), 200)


def _number(text: str) -> float | None:
    """``text`` as a float (nan and inf too: the caller refuses them), or None for anything
    else (an underscore too: float() reads "1_0" as 10)."""
    try:
        return None if "_" in text else float(text)
    except ValueError:
        return None


def _fixed(items: list[str], emu) -> dict[str, float]:
    """``--fixed``'s NAME -> value (native units; NAME one of the file's t_names or lamOs),
    each checked now, before any work, as ``calibrate(..., fixed=)`` checks it (`_check_held`);
    GPMSAError naming the item otherwise (first, as the Calibrator would: a file it refuses)."""
    from gpmsa.calibration.observations import check_emulator

    if not items:
        return {}
    check_emulator(emu, categorical_theta=True)
    t_names = tuple(str(n) for n in emu.t_names)
    allowed = (*t_names, "lamOs")
    given = _given(items, allowed, "fixed")
    for name, value in given.items():
        if name not in allowed:
            raise GPMSAError(f"--fixed {name}: not a calibration parameter of the file; give "
                             f"one of {list(allowed)}")  # fmt: skip
        _check_held(emu, t_names, name, value)
    return given


def _check_held(emu, t_names: tuple[str, ...], name: str, value: float) -> None:
    """GPMSAError where ``calibrate`` would refuse to hold ``name`` at ``value`` (its own
    checks: theta inside the design's open range, a categorical one at one of its levels;
    lamOs inside its prior's bounds), in the command's words, naming what is allowed."""
    from gpmsa.calibration.calibrate import calibration_fixed
    from gpmsa.model.problem import checked_fixed

    try:
        if name == "lamOs":
            checked_fixed("lamOs", value, (1,), emu.priors)
        else:
            calibration_fixed(emu, {"theta": {name: value}})
        return
    except GPMSAError:
        shown, allowed = _holdable(emu, t_names, name, value)
    raise GPMSAError(f"--fixed {name}={shown} cannot be held: give a value {allowed}")


def _holdable(emu, t_names: tuple[str, ...], name: str, value: float) -> tuple[str, str]:
    """``value`` as text, and the values ``--fixed`` may hold ``name`` at, in words (native
    units); a value and the bounds it misses with the digits that tell them apart (a level is
    matched within 1e-9: 12 digits tell a value off it)."""
    if name == "lamOs":
        g = emu.priors.precision_prior("lamOs")
        lo, hi = numbers(g.lower, g.upper, value)[:2]
        shown = numbers(value, g.lower, g.upper, digits=12)[0]
        return shown, f"inside its prior's bounds ({lo}, {hi})"
    k = t_names.index(name)
    levels = None if emu.levels is None else emu.levels[emu.x_unit.shape[1] + k]
    if levels is not None:
        return f"{value:.12g}", f"at one of its levels {[float(v) for v in levels]}"
    lo, hi = emu.standardizer.t_min[k], emu.standardizer.t_max[k]
    shown, lo, hi = numbers(value, lo, hi, digits=12)
    return shown, f"inside the design's open range ({lo}, {hi})"


def run(args: argparse.Namespace) -> int:
    """Run the subcommand; exit status 0, or 2 with a message on stderr for bad input (1 for
    an unexpected error, named in one line)."""
    from gpmsa.calibration.calibrator import Calibrator
    from gpmsa.fitting.emulator import load

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UserWarning)
        code = _run(args, load, Calibrator)
    for w in caught:  # their messages quote names from the file: printed escaped
        print(f"gpmsa calibrate: {w.category.__name__}: {safe(w.message)}", file=sys.stderr)
    return code


def _run(args: argparse.Namespace, load, Calibrator) -> int:
    try:
        if args.fixed and args.method == "grid":  # the grid refuses fixed=
            raise GPMSAError("--fixed holds parameters on the MCMC path, and --method grid "
                             "cannot hold them: use --method mcmc, or leave --method out "
                             "(auto chooses MCMC with --fixed)")  # fmt: skip
        emu = load(args.file)
        x = _pairs(args.x, tuple(emu.x_names), "x")
        y = _observed(args, tuple(emu.y_names))
        fixed = _fixed(args.fixed, emu)
        options = {"fixed": _fixed_option(fixed)} if fixed else None
        method = "mcmc" if fixed else args.method  # auto: MCMC with --fixed
        cal = Calibrator(emu, method=method, extrapolate=args.extrapolate, seed=args.seed,
                         mcmc_options=options)  # fmt: skip
        t0 = time.perf_counter()
        post = cal.update(x, y)
        summary = post.summary(args.level)
        seconds = time.perf_counter() - t0
        piled = _at_bound(emu, post)
    except GPMSAError as exc:  # the library's advice, in this command's words
        advice = str(exc).replace("pass extrapolate=True", "pass --extrapolate")
        print(f"gpmsa calibrate: {safe(advice)}", file=sys.stderr)
        return 2
    except Exception as exc:  # a gap in the library's checks: one line, not a traceback
        print(f"gpmsa calibrate: {safe(args.file)}: {internal_error(exc)}", file=sys.stderr)
        return 1
    if args.json:
        out = {
            "file": args.file,
            "x": dict(zip(emu.x_names, x[0].tolist(), strict=True)),
            "y": dict(zip(emu.y_names, y[0].tolist(), strict=True)),
            "method": post.info.get("method"),
            "level": args.level,
            **({"fixed": fixed} if fixed else {}),
            "seconds": seconds,
            "posterior": summary,
            "at_bound": {name: side for name, (side, _) in piled.items()},
        }
        print(json.dumps(jsonable(out), indent=1, allow_nan=False))  # RFC 8259: no NaN
        return 0
    lo_key, hi_key = quantile_keys(args.level)
    given = [", ".join(f"{safe(n, 60)}={_echo(v)}" for n, v in zip(names, row, strict=True))
             for names, row in ((emu.x_names, x[0]), (emu.y_names, y[0])) if names]  # fmt: skip
    print(f"posterior ({post.info.get('method')}, {1e3 * seconds:.2f} ms) given "
          + "; ".join(given))  # fmt: skip
    units = dict(zip(emu.t_names, emu.t_units, strict=True))  # lamOs: a precision, no unit
    print(f"{'name':>10s} {'mean':>12s} {'sd':>12s} {lo_key:>12s} {'median':>12s} {hi_key:>12s}"
          + (" unit" if any(units.values()) else ""))  # fmt: skip
    for name, s in summary.items():
        # in brackets, as `gpmsa info` prints it: a unit that reads as a number ("1e-6 m^3",
        # the shipped GD's) is not taken for one more figure of the row
        unit = f" [{safe(units[name], 60)}]" if units.get(name) else ""
        if s.get("held"):  # as `gpmsa info` prints a parameter held whole
            print(f"{safe(name, 60):>10s} held at {s['mean']:.12g}{unit} (fixed=)")
            continue
        # the location figures side by side as numbers_text gives them: distinct ones never
        # read alike (a posterior near 1e6 printed "1e+06" for its mean, ends and median)
        mean, lo, median, hi = numbers(s["mean"], s[lo_key], s["median"], s[hi_key], digits=5)
        print(f"{safe(name, 60):>10s} {mean:>12s} {s['sd']:12.5g} {lo:>12s} {median:>12s} "
              f"{hi:>12s}{unit}")  # fmt: skip
    for name, (_, text) in piled.items():
        print(f"{safe(name, 60)}: piled against the emulator's domain at {text}: the truth may "
              "lie outside the simulation design (widen it beyond that bound and refit), or "
              "the model misses something theta absorbs (check the emulator and units, add a "
              "discrepancy)")  # fmt: skip
    return 0


def _echo(value: float) -> str:
    """A given number for the summary's first line: as ``%g`` writes it where that reads back
    as the value ("1.25", "3"), else its shortest exact text ("1000000.5", not "1e+06")."""
    text = f"{value:g}"
    return text if float(text) == value else repr(float(value))


def _at_bound(emu, post) -> dict[str, tuple[str, str]]:
    """name -> (side, `bound_text`'s words) for each calibration parameter that the posterior
    piles against a bound of the emulator's domain (``gpmsa.mcmc.bounds.at_bound``, the rule
    of ``gpmsa.calibrate``: half its mass within 1 % of the width of the bound), judged on
    the grid posterior's exact marginal (its CDF: no draws) where it has one, else on the
    draws; held (--fixed) and categorical parameters are not judged."""
    from gpmsa.calibration.observations import theta_levels_native
    from gpmsa.calibration.posterior import held_names
    from gpmsa.mcmc.bounds import at_bound, bound_text

    names = list(emu.t_names)
    skip = {*held_names(post.info), *theta_levels_native(emu)}
    judged = [n for n in names if n not in skip]
    values = {n: post.grids[n] if n in post.grids else post.samples[n] for n in judged}
    lo, hi = emu.standardizer.t_min, emu.standardizer.t_max
    found = at_bound(values, names, lo, hi, skip)
    return {n: (side, bound_text(side, values[n], float(lo[names.index(n)]),
                                 float(hi[names.index(n)])))
            for n, side in found.items()}  # fmt: skip


def _fixed_option(fixed: dict[str, float]) -> dict:
    """``calibrate``'s ``fixed=`` from `_fixed`'s NAME -> value: {"theta": {t_name: value},
    "lamOs": value}."""
    out: dict = {}
    theta = {n: v for n, v in fixed.items() if n != "lamOs"}
    if theta:
        out["theta"] = theta
    if "lamOs" in fixed:
        out["lamOs"] = fixed["lamOs"]
    return out
