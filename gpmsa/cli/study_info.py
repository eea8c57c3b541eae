"""``gpmsa info STUDY`` for a study file (gpmsa.studies): its models, elements and posterior."""

from __future__ import annotations

from gpmsa.cli.index_text import index_text
from gpmsa.cli.text import level_moves_text, number, numbers, plain, safe, tempering_text, value


def study_lines(file: str, manifest: dict, study) -> list[str]:
    """A verified study (``gpmsa.load_study``) and its manifest for a person; every string
    from the file printed escaped."""
    st = manifest["study"]
    lines = [
        f"file:            {safe(file)}",
        f"format:          {safe(manifest['format'])} schema {manifest['schema_version']} "
        f"(gpmsa {plain(manifest.get('library_version'))}, written "
        f"{plain(manifest.get('created_utc'))})",
        f"content sha256:  {safe(manifest['content_sha256'])} (verified)",
        f"study:           {safe(st['kind'])} of {len(st['models'])} models; shared "
        f"[{', '.join(safe(n, 60) for n in st['shared'])}], hierarchical "
        f"[{', '.join(safe(n, 60) for n in st['hierarchical'])}]",
    ]
    for i, (mod, emu) in enumerate(zip(st["models"], study.members, strict=True)):
        params = ", ".join(
            f"{safe(n, 60)}{' [' + safe(u, 60) + ']' if u else ''} in [{lo}, {hi}]"
            for n, u in zip(emu.t_names, emu.t_units, strict=True)
            for lo, hi in [numbers(*emu.domain[n])]
        )
        lines.append(f"model {safe(mod['label'], 60)}: file {safe(mod['file'], 160)} sha256 "
                     f"{safe(mod['sha256'], 64)} (verified); m={emu.m}, p={emu.p}, "
                     f"l_sim={emu.l_sim}; parameters {params}")  # fmt: skip
        index = index_text(emu)
        if index is not None:  # as an emulator file's "output index:" line
            lines.append(f"  output index {index}")
        disc = study.discrepancy(i)
        if disc is not None:  # the model's discrepancy and its precision groups
            groups = disc["discrepancy_groups"]
            lines.append(f"  discrepancy {plain(disc['discrepancy'])}, precision groups "
                         f"{plain(groups) if isinstance(groups, list) else 'one'}")  # fmt: skip
    if st["hierarchical"]:
        hp = manifest["priors"]["hyper"]
        if hp.get("sd_prior", "gamma") == "uniform":
            spread = f"sd = 1/sqrt(lam) ~ Uniform(0, {number(hp['sd_max'])})"
        else:
            spread = f"lam ~ Gamma({number(hp['lam_a'])}, {number(hp['lam_b'])}) (SEPIA's)"
        lines.append(f"hyperpriors:     mu ~ Normal({number(hp['mu_mean'])}, "
                     f"{number(hp['mu_sd'])}) on (0, 1); {spread} (unit scale)")  # fmt: skip
    flat = [f"{safe(k, 60)}={plain(v)}" for k, v in manifest["settings"].items()
            if not isinstance(v, (list, dict))]  # fmt: skip
    lines.append("settings:        " + ", ".join(flat))
    if "temperatures" in manifest["settings"]:  # calibrate_study(..., temperatures=): lists
        lines.append(f"tempering:       {tempering_text(manifest['settings'])}")
    if "level_offsets" in manifest["settings"]:  # a categorical parameter's joint level move
        lines.append(f"level moves:     {level_moves_text(manifest['settings']['level_offsets'])}")
    for k, v in manifest["metadata"].items():
        lines.append(f"metadata {safe(k, 60)}: {value(v)}")
    for name, row in study.summary(0.9).items():
        if row["held"]:  # fixed=: no ESS or R-hat to give
            lines.append(f"posterior {safe(name, 80)}: held at {row['mean']:.6g} (fixed=)")
            continue
        mean, q5, q95 = numbers(row["mean"], row["q5"], row["q95"])
        lines.append(f"posterior {safe(name, 80)}: mean {mean} sd "
                     f"{row['sd']:.4g} 90% [{q5}, {q95}] ESS "
                     f"{number(row['ess'], '.0f')} R-hat {number(row['rhat'], '.3f')}")  # fmt: skip
    return lines
