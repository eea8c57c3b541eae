"""Text from a file, made safe to print: control and format characters escaped, long values cut.

An emulator file comes from people the reader need not trust; its names, units, metadata and
even its member names (quoted in error messages) may hold terminal escape sequences (ESC [ ...),
carriage returns or bidirectional overrides that would rewrite the terminal or disguise text.
Everything the CLI prints from a file goes through ``safe``.
"""

from __future__ import annotations

import json

from gpmsa.errors import numbers_text

MAX_VALUE_CHARS = 300
"""Longest value printed whole; longer ones are cut and their length stated."""


def safe(text: object, limit: int | None = None) -> str:
    """``str(text)`` with every non-printable character (C0/C1 controls, DEL, format and
    separator characters other than the space) written as a Python escape (``\\x1b``,
    ``\\u202e``), cut to ``limit`` characters if given."""
    s = str(text)
    cut = ""
    if limit is not None and len(s) > limit:
        cut = f"... ({len(s)} characters)"
        s = s[:limit]
    out = []
    for ch in s:
        if ch.isprintable() or ch == " ":
            out.append(ch)
        elif ord(ch) < 0x100:
            out.append(f"\\x{ord(ch):02x}")
        elif ord(ch) < 0x10000:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(f"\\U{ord(ch):08x}")
    return "".join(out) + cut


def value(obj: object) -> str:
    """A JSON value for a person: compact JSON (ASCII escapes), cut at MAX_VALUE_CHARS."""
    try:
        text = json.dumps(obj, ensure_ascii=True, allow_nan=True)
    except (TypeError, ValueError, RecursionError):
        text = repr(obj)
    return safe(text, MAX_VALUE_CHARS)


def plain(obj: object) -> str:
    """A string as itself (escaped, cut), any other JSON value as ``value`` shows it."""
    return safe(obj, MAX_VALUE_CHARS) if isinstance(obj, str) else value(obj)


def number(obj: object, fmt: str = ".4g") -> str:
    """A number formatted with ``fmt``, or the value as ``value`` shows it if it is none (or
    an integer beyond float64, 10**400 from a file's JSON, that a float format cannot take)."""
    if isinstance(obj, (int, float)) and not isinstance(obj, bool):
        try:
            return format(obj, fmt)
        except OverflowError:
            pass
    return value(obj)


def numbers(*objs: object, digits: int = 6) -> tuple[str, ...]:
    """Numbers shown side by side (a range's ends, a value and its range) as
    ``gpmsa.errors.numbers_text`` writes them: ``digits`` significant digits, more where two
    distinct ones would read alike; a value that is no float (a string from a file, an integer
    beyond float64) as ``number`` shows it, the others then with ``digits``."""
    fmt = f".{digits}g"
    try:
        floats = [float(v) for v in objs if isinstance(v, (int, float)) and not isinstance(v, bool)]
    except OverflowError:
        floats = []
    if len(floats) < len(objs):
        return tuple(number(v, fmt) for v in objs)
    return numbers_text(*floats, digits=digits)


def internal_error(exc: BaseException) -> str:
    """One line for an error that the library's checks should have turned into a GPMSAError
    (printed instead of a traceback: its text is escaped, cut at MAX_VALUE_CHARS)."""
    return (
        f"unexpected {type(exc).__name__} ({safe(exc, MAX_VALUE_CHARS)}): the file or the input "
        "is outside what gpmsa checks; please report it"
    )


def tempering_text(settings: dict) -> str:
    """Parallel tempering's records (settings "temperatures", "swap_every", "swap_rate", with
    ``adapt_ladder`` "adapted_temperatures"; not checked by the reader: any JSON printed as it
    is), in words."""
    temps, rates = settings.get("temperatures"), settings.get("swap_rate")
    if isinstance(temps, list):
        ladder = f"{len(temps)} temperatures [{', '.join(number(t, '.6g') for t in temps)}]"
    else:
        ladder = f"temperatures {value(temps)}"
    if isinstance(rates, list) and all(isinstance(r, list) for r in rates):
        rate_text = "; ".join(", ".join(number(v, ".3f") for v in r) for r in rates)
        rate_text = f"[{rate_text}] (per chain; per neighbour pair, over the draws)"
    else:
        rate_text = value(rates)
    adapted = settings.get("adapted_temperatures")  # adapt_ladder=True: per chain
    if isinstance(adapted, list) and all(isinstance(r, list) for r in adapted):
        ladder += (" adapted to [" + "; ".join(", ".join(number(t, ".4g") for t in r)
                                                for r in adapted) + "] (per chain)")  # fmt: skip
    elif adapted is not None:
        ladder += f" adapted to {value(adapted)}"
    return safe(f"{ladder}, a swap round every {plain(settings.get('swap_every'))} sweep(s); "
                f"swap rates {rate_text}", 600)  # fmt: skip


def level_moves_text(record: object) -> str:
    """The joint level moves' record (settings "level_offsets", ``level_moves.native_record``:
    a joint fit's, or a study's by study element names; not checked by the reader: anything
    else printed as it is), in words: per categorical theta and chain, the shifted elements'
    conditional modes at each level (native units)."""
    if not isinstance(record, dict):
        return value(record)
    parts = []
    for name, rec in record.items():
        try:
            levels, shifted, modes = rec["levels"], rec["shifted"], rec["modes"]
            chains = "; ".join(
                f"chain {c + 1}: " + ", ".join(
                    f"{number(lv, 'g')} -> "
                    + (number(m[0], ".4g") if len(m) == 1
                       else "(" + ", ".join(number(v, ".4g") for v in m) + ")")
                    for lv, m in zip(levels, per, strict=True))
                for c, per in enumerate(modes))  # fmt: skip
            what = ", ".join(safe(n, 60) for n in shifted)
            parts.append(f"{safe(name, 60)} shifts {what} between their modes at each level "
                         f"({chains})")  # fmt: skip
        except (KeyError, TypeError, ValueError):
            parts.append(f"{safe(name, 60)}: {value(rec)}")
    return safe("; ".join(parts) + " (native units)", 600)
