"""The ``gpmsa`` console command (argparse subcommands)."""

from __future__ import annotations

import argparse
import json
import os
import sys

from gpmsa.errors import EmulatorFileError


def _info(args: argparse.Namespace) -> int:
    from gpmsa.io.container import read_raw

    try:
        manifest, arrays = read_raw(args.file)
    except EmulatorFileError as exc:
        print(f"gpmsa info: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(manifest, indent=1, sort_keys=True))
        return 0
    model = manifest.get("model", {})
    lines = [
        f"file:            {args.file}",
        f"format:          {manifest['format']} schema {manifest['schema_version']} "
        f"(gpmsa {manifest.get('library_version')}, written {manifest.get('created_utc')})",
        f"content sha256:  {manifest['content_sha256']} (verified)",
        f"model:           m={model.get('m')} runs, p={model.get('p')}, q={model.get('q')}, "
        f"l_sim={model.get('l_sim')}, p_u={model.get('p_u')}",
    ]
    units = manifest["units"]
    for kind, label in (("x", "known inputs"), ("t", "parameters"), ("y", "outputs")):
        names = manifest["names"][kind]
        if kind == "y" and len(names) > 8:
            lines.append(f"{label + ':':17s}{len(names)} ({names[0]} .. {names[-1]})")
            continue
        parts = []
        for n, u in zip(names, units[kind], strict=False):
            dom = manifest.get("domain", {}).get(n)
            rng = f" in [{dom[0]:.6g}, {dom[1]:.6g}]" if dom else ""
            parts.append(f"{n}{' [' + u + ']' if u else ''}{rng}")
        lines.append(f"{label + ':':17s}{', '.join(parts)}")
    s = manifest["settings"]
    plain = [f"{k}={v}" for k, v in s.items() if not isinstance(v, (list, dict))]
    lines.append("settings:        " + ", ".join(plain))
    for k, v in manifest["metadata"].items():
        lines.append(f"metadata {k}: {json.dumps(v)}")
    for name, d in manifest["diagnostics"].items():
        mean = ", ".join(f"{v:.4g}" for v in d.get("mean", []) if v is not None)
        ess = ", ".join(f"{v:.0f}" for v in d.get("ess", []) if v is not None)
        lines.append(f"posterior {name}: mean [{mean}] ESS [{ess}]")
    n_arr = sum(int(a.size) for a in arrays.values())
    lines.append(f"arrays:          {len(arrays)} ({n_arr} values)")
    print("\n".join(lines))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(prog="gpmsa", description="GPM/SA emulator tools")
    sub = parser.add_subparsers(dest="command", required=True)
    info = sub.add_parser("info", help="print an emulator file's manifest (verifies it first)")
    info.add_argument("file", help="path to a .gpmsa file")
    info.add_argument("--json", action="store_true", help="print the raw manifest as JSON")
    info.set_defaults(func=_info)
    from gpmsa.cli.calibrate import add_parser as add_calibrate

    add_calibrate(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``gpmsa`` console script."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except BrokenPipeError:  # the reader went away (`gpmsa info FILE | head`): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
