"""``gpmsa info FILE [--json]``: print an emulator file's manifest for a person (verified)."""

from __future__ import annotations

import argparse
import json
import sys

from gpmsa.errors import EmulatorFileError


def add_parser(sub) -> None:
    """Add the ``info`` subcommand to an argparse subparsers object."""
    p = sub.add_parser("info", help="print an emulator file's manifest (verifies it first)")
    p.add_argument("file", help="path to a .gpmsa file")
    p.add_argument("--json", action="store_true", help="print the raw manifest as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run the subcommand; exit status 0, or 2 with a message on stderr for a bad file."""
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
        rhat = ", ".join(f"{v:.3f}" for v in d.get("rhat", []) if v is not None)
        lines.append(f"posterior {name}: mean [{mean}] ESS [{ess}] R-hat [{rhat}]")
    lines.append(_convergence_line(manifest.get("convergence")))
    n_arr = sum(int(a.size) for a in arrays.values())
    lines.append(f"arrays:          {len(arrays)} ({n_arr} values)")
    print("\n".join(lines))
    return 0


def _convergence_line(rec: dict | None) -> str:
    """One line on the chains' convergence (files of one chain or older ones have no record)."""
    if not rec:
        return "convergence:     not checked (one chain, or a file from before the check)"
    (r_el, r_val), (e_el, e_val) = rec["max_rhat"], rec["min_ess"]
    if r_val is None or e_val is None:
        worst = "R-hat and ESS undefined (constant draws)"
    else:
        worst = f"max R-hat {r_val:.3f} ({r_el}), min bulk ESS {e_val:.0f} ({e_el})"
    head = f"convergence:     {rec['n_chains']} chains x {rec['n_draws']} draws; {worst}; "
    flagged = rec.get("flagged") or {}
    if not flagged:
        return head + f"converged (R-hat <= {rec['rhat_max']}, ESS >= {rec['ess_min']:.0f})"
    return head + "NOT converged: " + "; ".join(f"{k}: {v}" for k, v in flagged.items())
