"""``Study``: several models' emulators and their joint calibration draws; its files.

A study is saved as a set of files in one folder: the study file (``STUDY.gpmsa``, the
container of ``gpmsa.io.container`` with format "gpmsa-study": the draws and a manifest listing
each model's emulator file with its content sha256) and one emulator file per model
(``STUDY.LABEL.gpmsa``, an ordinary emulator file). ``load_study`` reads the models' files
through ``gpmsa.load`` with the listed sha256, so an edited model file is refused.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from gpmsa.calibration.observations import emulator_record, theta_levels, theta_levels_native
from gpmsa.calibration.posterior import Posterior, held_names, recorded_units
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.fitting.emulator import _check_metadata, build, read_checked
from gpmsa.io.atomic import atomic_group, folder_lock
from gpmsa.io.container import (
    FORMAT,
    STUDY_FORMAT,
    check_expected_sha256,
    check_path,
    jsonable,
    read_manifest,
    read_raw,
    refuse_to_replace,
    seal,
    verify_content,
    write_sealed,
)
from gpmsa.mcmc.bounds import at_bound
from gpmsa.mcmc.diagnostics import convergence, summarize, to_inference_data
from gpmsa.model.data import as_real, check_count
from gpmsa.model.discrepancy import to_samples
from gpmsa.studies.layout import HyperPriors, Layout, build_layout, model_theta_priors
from gpmsa.studies.record import (
    DISCREPANCIES,
    FILE_RE,
    _short,
    check_study_arrays,
    check_study_claims,
    check_study_manifest,
    discrepancy_arrays,
)

OBS_DIGESTS = "obs_values_sha256_by_model"
"""The settings key of a calibrated study's record of each model's observations: label ->
``ObsData.values_digest()`` of its x_obs and y_obs (``member_posterior``'s info
"obs_values_sha256", as ``gpmsa.calibrate`` records it)."""
OBS_LAYOUTS = "obs_layout_sha256_by_model"
"""The settings key of a calibrated study's record of where each model's observations lie and
how precise they are: label -> ``layout_digest`` (``member_posterior``'s info
"obs_layout_sha256", as ``gpmsa.calibrate`` records it)."""

HELD_THETA = "held_theta"
"""The settings key of a study whose models hold theta elements (``fixed=``): study element
name -> the native value held, as given; the posterior reports exactly it (as
``gpmsa.calibrate`` does), where the unit-scale draws read back through the element's range
can come back an ulp off."""


def layout_of(emulators, labels, shared, hierarchical) -> Layout:
    """The study layout of fitted emulators (their t names, t ranges and theta priors); a
    GPMSAError where per-element theta priors do not give one per calibration parameter."""
    return build_layout(
        tuple(labels), [tuple(e.t_names) for e in emulators],
        [(e.standardizer.t_min, e.standardizer.t_max) for e in emulators],
        [model_theta_priors(e.priors, len(e.t_names)) for e in emulators], shared, hierarchical,
    )  # fmt: skip


def _check_study_name(path: Path, labels) -> None:
    """GPMSAError unless the model files ``<stem>.<label>.gpmsa`` that a study saved to ``path``
    writes beside it have names ``FILE_RE`` allows (ASCII letters, digits, '_', '-', '.'; no
    leading '.'; at most 157 characters)."""
    longest = max(labels, key=len)
    member = f"{path.stem}.{longest}.gpmsa"
    if not FILE_RE.match(member):
        most = 150 - len(longest)  # FILE_RE: 151 characters before ".gpmsa", "." + label here
        raise GPMSAError(
            f"path: the study file's name {path.name!r} may use only ASCII letters, digits, "
            f"'_', '-' and '.', not start with '.', and have a stem of at most {most} "
            f"characters with these labels (it names the model files beside it, e.g. "
            f"{member!r}); choose another name"
        )


def _refuse_other_studies(path: Path, files: list[str]) -> None:
    """GPMSAError if another study file beside ``path`` with the same stem (``run`` or
    ``run.bak`` beside ``run.gpmsa``) lists one of the model files ``files`` that saving to
    ``path`` writes: replaced, that study would no longer load (its sha256 differing)."""
    try:
        names = [e.name for e in os.scandir(path.parent) if e.name != path.name]
    except OSError:  # no folder, or not listable: writing there says why
        return
    for name in sorted(n for n in names if Path(n).stem == path.stem):
        other = path.with_name(name)
        try:
            manifest = read_manifest(other, (STUDY_FORMAT,))
            check_study_manifest(manifest)
        except (GPMSAError, OSError):  # not a readable study: no model files of its own
            continue
        theirs = {mod["file"] for mod in manifest["study"]["models"]}
        shared = [f for f in files if f in theirs]
        if shared:
            raise GPMSAError(
                f"refusing to write {path}: its model file {shared[0]} belongs to the study "
                f"{other} beside it, which would no longer load; choose another name, or remove "
                "that study first"
            )


def _through_link(path: Path) -> Path:
    """``path``, or the file a symbolic link ``path`` points to: the model files lie beside the
    study file itself, not beside a link to it."""
    try:
        return Path(os.path.realpath(path)) if path.is_symlink() else path
    except OSError:  # e.g. a name too long: reading or writing it says so
        return path


def native_chains(layout: Layout, draws: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Named (C, N) chains in native units from the unit-scale draws: each study element, each
    model's lamOs ("lamOs[LABEL]") and, where its draws hold them, its discrepancy parameters
    (NAME[LABEL], NAME as ``gpmsa.calibrate`` names them: "betaV[LABEL]", "lamVz[LABEL]";
    "betaV[k][LABEL]" for several inputs; "betaV[k,g][LABEL]", "lamVz[g][LABEL]" for several
    groups), each group's mean "NAME.mu" and sd "NAME.sd" (native: the unit-scale 1/sqrt(lam)
    times the parameter's range) and precision "NAME.lam" (unit scale)."""
    out = {}
    for e, el in enumerate(layout.elements):
        lo, hi = layout.bounds[e]
        out[el.name] = lo + draws["theta"][:, :, e] * (hi - lo)
    for i, lab in enumerate(layout.labels):
        out[f"lamOs[{lab}]"] = draws["lamOs"][:, :, i]
        out.update({f"{k}[{lab}]": v for k, v in _drawn_discrepancy(draws, i).items()})
    for h, name in enumerate(layout.groups):
        e = layout.members_of(h)[0]
        lo, hi = layout.bounds[e]
        out[f"{name}.mu"] = lo + draws["mu"][:, :, h] * (hi - lo)
        out[f"{name}.sd"] = (hi - lo) / np.sqrt(draws["lam"][:, :, h])
        out[f"{name}.lam"] = draws["lam"][:, :, h]
    return out


def theta_domains(layout: Layout) -> tuple[list[str], np.ndarray, np.ndarray]:
    """The posterior names that ``gpmsa.mcmc.bounds.at_bound`` judges, and each one's native
    domain (lower, upper bounds): each study element's (its models' range: a shared or
    hierarchical parameter's is one range in every model, ``build_layout``; a model's own, its
    emulator's) and each hierarchical group's mean "NAME.mu", whose prior stops at that same
    range (mu is truncated to it, as its elements are): piled there, the group's centre lies
    beyond the design. The group's sd and precision, and lamOs, have no such bound."""
    names = [el.name for el in layout.elements]
    bounds = list(layout.bounds)
    for h, name in enumerate(layout.groups):
        names.append(f"{name}.mu")
        bounds.append(layout.bounds[layout.members_of(h)[0]])
    lo, hi = np.array(bounds, dtype=np.float64).reshape(-1, 2).T
    return names, lo, hi


def _at_bound(layout: Layout, samples: dict, settings: dict, levels) -> dict[str, str]:
    """``posterior.info["at_bound"]`` of a study: `at_bound` over `theta_domains`, its held
    (``settings``) and categorical (``levels``: their names) elements not judged."""
    return at_bound(samples, *theta_domains(layout), {*held_names(settings), *levels})


def study_units(layout: Layout, members) -> dict[str, str]:
    """The unit of each study posterior name that has one (``Posterior.info["units"]``, as
    ``gpmsa.calibrate`` records it, so that plots label its axes): each study element's, its
    models' ``t_units`` of the parameter where they agree (a shared one's models may differ:
    then none), and each hierarchical group's mean "NAME.mu" and sd "NAME.sd" (native units)
    their elements'; "NAME.lam" (unit scale) and lamOs have none. Read from the members, so
    study files of every version have them."""
    out = {}
    for el in layout.elements:
        units = {members[i].t_units[k] for i, k in el.uses}
        if len(units) == 1:
            out[el.name] = units.pop()
    for h, name in enumerate(layout.groups):
        units = {out.get(layout.elements[e].name) for e in layout.members_of(h)}
        if len(units) == 1 and None not in units:
            out[f"{name}.mu"] = out[f"{name}.sd"] = units.pop()
    return out


def element_levels(layout: Layout, members) -> list[tuple[float, ...] | None]:
    """Each study element's unit-scale levels where its parameter is categorical (its first
    model's emulator's, ``theta_levels``; ``gpmsa.studies.sampler.element_levels`` makes its
    models agree), else None."""
    per = [theta_levels(m) for m in members]
    return [None if per[el.uses[0][0]] is None else per[el.uses[0][0]][el.uses[0][1]]
            for el in layout.elements]  # fmt: skip


def _held_theta(layout: Layout, draws: dict[str, np.ndarray], settings: dict) -> dict[str, float]:
    """``settings[HELD_THETA]`` checked against the draws (absent: {}, as in files written
    before it): GPMSAError unless each name is a study element whose every draw is one unit
    value, the value given within the rounding ``Layout.same_unit_value`` allows."""
    held = settings.get(HELD_THETA)
    if held is None:
        return {}
    where = f"settings[{HELD_THETA!r}]"
    if not isinstance(held, dict):
        raise GPMSAError(f"{where} must be an object element name -> native value, got "
                         f"{type(held).__name__}")  # fmt: skip
    names = [el.name for el in layout.elements]
    out = {}
    for name, value in held.items():
        if name not in names:
            raise GPMSAError(f"{where}: {_short(name)} is no study element; they are {names}")
        key = f"{where}[{name!r}]"
        if isinstance(value, bool) or not isinstance(value, int | float | np.number):
            raise GPMSAError(f"{key} must be a number, got {_short(value)}")
        value = as_real(value, key)
        if not np.isfinite(value):
            raise GPMSAError(f"{key} must be finite, got {value!r}")
        e = names.index(name)
        lo, hi = layout.bounds[e]
        col = draws["theta"][:, :, e]
        if col.size and not (np.all(col == col.flat[0])
                             and layout.same_unit_value(e, float(col.flat[0]),
                                                        (value - lo) / (hi - lo))):  # fmt: skip
            raise GPMSAError(f"{key} = {value!r} is not the value its draws hold")
        out[name] = value
    return out


class Study:
    """Several models calibrated together (shared and hierarchical theta); docs/models.md.

    Attributes:
        kind: "calibration" (the emulators fixed, ``calibrate_study``) or "fit" (emulators and
            calibration fitted jointly, ``fit_study``).
        members: the models' ``gpmsa.Emulator``s, in order; labels: their labels.
        layout: the study elements (``gpmsa.studies.layout.Layout``); hyper: the hyperpriors.
        draws: unit-scale kept draws: theta (C, N, G), mu and lam (C, N, H), lamOs (C, N, M),
            log_post (C, N); a calibration with a discrepancy: model j's betaV (C, N, p, G) and
            lamVz (C, N, G) as "betaV_j", "lamVz_j".
        posterior: ``gpmsa.Posterior`` in native units (names: ``native_chains``); ``summary()``
            and ``to_arviz()`` give its summary (held parameters marked) and its chains.
        diagnostics, convergence: the native chains' summary (ESS, R-hat per name) and its
            verdict, as an Emulator's (``gpmsa.mcmc.diagnostics``; also in
            ``posterior.info``).
        settings, metadata: how it was run; the user's JSON-able dict (saved).
        sha256: the ``content_sha256`` of the study file it was read from or last saved to
            (None before either); a continuation (``init=study``) records it as
            ``settings["continued_from"]``.
    """

    def __init__(self, kind: str, members, layout: Layout, hyper: HyperPriors,
                 draws: dict[str, np.ndarray], settings: dict | None = None,
                 metadata: dict | None = None):  # fmt: skip
        self.kind = kind
        self.members = tuple(members)
        self.layout = layout
        self.hyper = hyper
        self.draws = {k: np.asarray(v, dtype=np.float64) for k, v in draws.items()}
        self.settings = dict(settings or {})
        self.metadata = dict(metadata or {})
        self.sha256: str | None = None
        chains = native_chains(layout, self.draws)
        levels = {}  # a categorical element's codes: Posterior.info["levels"] (level quantiles)
        for el, lv in zip(layout.elements, element_levels(layout, self.members), strict=True):
            if lv is not None:  # a categorical element's draws: exactly the level codes
                chains[el.name] = np.round(chains[el.name])
                i, k = el.uses[0]
                member = self.members[i]
                levels[el.name] = theta_levels_native(member)[member.t_names[k]]
        for name, value in _held_theta(layout, self.draws, self.settings).items():
            chains[name][...] = value
        samples = {k: v.reshape(-1) for k, v in chains.items()}
        self.diagnostics = summarize(chains)
        n_chains, n_draws = self.draws["log_post"].shape
        info = {"method": f"study {kind}", "diagnostics": self.diagnostics, **self.settings,
                "units": study_units(layout, self.members)}  # fmt: skip
        if levels:
            info["levels"] = levels
        shapes = {k: () for k in chains}  # one chain too: its split R-hat (as gpmsa.fit's)
        held = held_names(self.settings)  # fitted with fixed=: not judged
        # piled against a bound of the domain (calibrate_study and fit_study warn of it; a
        # study read from a file is judged anew, silently, as calibration_posterior's)
        info["at_bound"] = _at_bound(layout, samples, self.settings, levels)
        self.convergence = convergence(self.diagnostics, shapes, n_chains, n_draws, held,
                                       levels=set(levels))  # fmt: skip
        info["convergence"] = self.convergence
        self.posterior = Posterior(samples, chains=chains, info=info)

    def __setstate__(self, state: dict) -> None:
        """For pickle: a study pickled before ``posterior.info["at_bound"]`` was kept is judged
        now (as one read from a file), so that ``member_posterior`` finds it."""
        self.__dict__.update(state)
        info = self.posterior.info
        if "at_bound" not in info:
            info["at_bound"] = _at_bound(self.layout, self.posterior.samples, self.settings,
                                         info.get("levels") or {})  # fmt: skip

    @property
    def labels(self) -> tuple[str, ...]:
        """The models' labels."""
        return self.layout.labels

    def _member(self, model: int | str) -> int:
        if isinstance(model, str):
            if model not in self.labels:
                raise GPMSAError(f"unknown model {model!r}; this study has {list(self.labels)}")
            return self.labels.index(model)
        return check_count(model, "model index", 0, len(self.members) - 1)

    def member_posterior(self, model: int | str) -> Posterior:
        """One model's calibration as a ``gpmsa.Posterior`` named as its emulator's t_names and
        "lamOs" (native units), and for a study fitted with a discrepancy its "betaV" (one
        input; "betaV[k]" for several) and "lamVz" (several precision groups: "betaV[k,g]",
        "lamVz[g]"), e.g. for ``gpmsa.full_prediction``'s
        ``posterior=`` or ``gpmsa.predictive.calibrated_predict``. Its info carries the record of
        the model's observations (a fitted model's "obs_sha256", a calibrated one's
        "obs_values_sha256"), so that ``full_prediction(posterior=)`` refuses other ones, and
        its emulator's ``model_sha256`` ("emulator_sha256"): another emulator is refused; with
        ``fixed=``, "held": its names held (``summary()``'s "held", as ``calibrate``'s)."""
        i = self._member(model)
        chains = self.posterior.chains
        out = {}
        for k, name in enumerate(self.members[i].t_names):
            out[name] = chains[self.layout.elements[self.layout.index[i][k]].name]
        out["lamOs"] = chains[f"lamOs[{self.labels[i]}]"]
        if self.kind == "fit":  # a calibration's members may be joint fits of their own
            out.update(_discrepancy_chains(self.members[i], out["lamOs"].shape))
        out.update(_drawn_discrepancy(self.draws, i))
        info = {
            "method": f"study {self.kind}",
            "model": self.labels[i],
            **emulator_record(self.members[i]),
            "units": dict(zip(self.members[i].t_names, self.members[i].t_units, strict=True)),
        }
        # the record of the model's observations, so that full_prediction(posterior=) refuses
        # other ones: a fitted model's (as calibration_posterior), a calibrated one's (as
        # gpmsa.calibrate; absent from study files written before it was kept)
        settings = self.members[i].settings if self.kind == "fit" else {}
        info.update({k: settings[k] for k in ("obs_lengths", "obs_sha256", "discrepancy",
                                              "discrepancy_sha256", "discrepancy_groups",
                                              "discrepancy_scale")
                     if settings.get(k) is not None})  # fmt: skip
        basis = self.settings.get(DISCREPANCIES, {}).get(self.labels[i])
        if basis is not None:  # a calibration's basis: full_prediction refuses another
            info.update(basis)
        for key, name in ((OBS_DIGESTS, "obs_values_sha256"), (OBS_LAYOUTS, "obs_layout_sha256")):
            digests = self.settings.get(key)
            digest = digests.get(self.labels[i]) if isinstance(digests, dict) else None
            if isinstance(digest, str):
                info[name] = digest
        held = held_names(self.settings)  # fixed=: under the model's own names, as calibrate's
        pooled = {n: self.layout.elements[self.layout.index[i][k]].name
                  for k, n in enumerate(self.members[i].t_names)}  # fmt: skip
        own = [n for n in out if pooled.get(n, f"{n}[{self.labels[i]}]") in held]
        if own:
            info["held"] = own
        codes = theta_levels_native(self.members[i])
        if codes:  # a categorical theta: its quantiles are levels (as study.posterior's)
            info["levels"] = codes
        flagged = self.posterior.info["at_bound"]  # its elements', as calibrate records it
        info["at_bound"] = {n: flagged[pooled[n]] for n in self.members[i].t_names
                            if pooled[n] in flagged}  # fmt: skip
        return Posterior({k: v.reshape(-1) for k, v in out.items()}, chains=out, info=info)

    def summary(self, level: float = 0.9) -> dict[str, dict[str, float]]:
        """The pooled posterior's summary over every chain, native units: name -> {mean, sd,
        q_lo, median, q_hi, n_draws, exact_grid, ess, rhat, held} (``Posterior.summary`` of
        ``study.posterior``: the interval at ``level``, its ends named by their percentages,
        "q5" and "q95" for 0.9; the bulk ESS and split R-hat over the chains). The names are
        ``study.posterior``'s: a shared element by its own name ("E"), a model's own parameter
        as "NAME[LABEL]" (its theta elements, "lamOs[LABEL]", its discrepancy's), a
        hierarchical group's "NAME.mu", "NAME.sd", "NAME.lam"; a model's entries equal those
        of ``member_posterior(LABEL).summary(level)`` under its own names. "held": True for a
        parameter held with ``fixed=`` (every draw its value: sd 0, ESS and R-hat NaN), as
        ``gpmsa info`` prints it."""
        return self.posterior.summary(level)  # its info holds the settings' "held"

    def to_arviz(self):
        """ArviZ InferenceData of the pooled posterior (arviz imported lazily): every name of
        ``study.posterior`` (native units) as (chain, draw), the study's chains kept apart, and
        the log posterior as sample_stats "lp", as ``Emulator.to_arviz`` gives it. A parameter
        held with ``fixed=`` is its value in every draw (``summary``'s "held"). Each parameter's
        unit (``study.posterior.info["units"]``) is its variable's "units" attribute."""
        chains = {k: np.asarray(v) for k, v in self.posterior.chains.items()}
        units = recorded_units(self.posterior.info)
        return to_inference_data(chains, self.draws["log_post"], units=units)

    def discrepancy(self, model: int | str) -> dict | None:
        """One model's discrepancy as its calibration or fit recorded it: {"discrepancy":
        "constant", "linear", "given" (an array) or "list" (per-experiment arrays),
        "discrepancy_groups": the precision groups
        (several) or None (one)}; None for a model without one."""
        i = self._member(model)
        if self.kind == "fit":
            rec = self.members[i].settings or {}
        else:
            rec = self.settings.get(DISCREPANCIES, {}).get(self.labels[i]) or {}
        if rec.get("discrepancy") is None:
            return None
        return {"discrepancy": rec["discrepancy"],
                "discrepancy_groups": rec.get("discrepancy_groups")}  # fmt: skip

    def to_record(self, files: list[str], hashes: list[str]) -> tuple[dict, dict]:
        """The study file's (manifest, arrays), its models' files and sha256 given."""
        _check_metadata(self.metadata, "metadata")
        models = [{"label": lab, "file": f, "sha256": h}
                  for lab, f, h in zip(self.labels, files, hashes, strict=True)]  # fmt: skip
        manifest = {
            "names": {"models": list(self.labels),
                      "elements": [el.name for el in self.layout.elements],
                      "t": {lab: list(e.t_names) for lab, e in zip(self.labels, self.members,
                                                                   strict=True)}},
            "units": {lab: list(e.t_units) for lab, e in zip(self.labels, self.members,
                                                             strict=True)},
            "priors": {"hyper": self.hyper.to_dict()},
            "settings": self.settings,
            "metadata": self.metadata,
            "diagnostics": self.diagnostics,
            "study": {"kind": self.kind, "shared": list(self.layout.shared),
                      "hierarchical": list(self.layout.groups), "models": models},
        }  # fmt: skip
        manifest["convergence"] = self.convergence
        return jsonable(manifest), {k: np.ascontiguousarray(v) for k, v in self.draws.items()}

    def save(self, path: str | Path) -> Path:
        """Write the study file ``path`` and beside it each model's emulator file
        ``<stem>.<label>.gpmsa``; returns ``path``.

        Every record (each model's and the study's) is built and checked as ``load_study`` checks it
        before anything is written: a refused save (GPMSAError) writes nothing. The files are then
        written whole to temporary files and moved over their paths together
        (``gpmsa.io.atomic.atomic_group``), so a save that fails leaves an existing study at
        ``path`` as it was (only an OS failure during the final moves could mix the two; an I/O
        error flushing the folder after them names it, the new files in place and ``sha256``
        theirs). A study is not written over an emulator file, nor a model file over a study file
        (GPMSAError): such a file belongs to another study, which would no longer load; nor are the
        model files of another study beside ``path`` with the same stem (``run`` or ``run.bak``
        beside ``run.gpmsa``) replaced. Nor is any file written over a non-empty file that is not a
        gpmsa file (a user's CSV or notes). ``path``'s name names the model files, so it may use
        only ASCII letters, digits, '_', '-' and '.', not start with '.', and its stem be at most
        150 - len(longest label) characters (GPMSAError up front otherwise). A symbolic link
        ``path`` is written through: the study file and its model files go beside the link's target,
        named after it (as ``load_study`` reads them).
        """
        given = check_path(path)
        path = _through_link(given)
        _check_study_name(path, self.labels)
        refuse_to_replace(path, STUDY_FORMAT)
        _refuse_other_studies(path, [f"{path.stem}.{lab}.gpmsa" for lab in self.labels])
        files, hashes, sealed = [], [], []
        for lab, emu in zip(self.labels, self.members, strict=True):
            file = f"{path.stem}.{lab}.gpmsa"
            refuse_to_replace(path.with_name(file), FORMAT)
            manifest, arrays = emu.checked_record(path.with_name(file))
            head, raw = seal(manifest, arrays)
            files.append(file)
            hashes.append(head["content_sha256"])
            sealed.append((path.with_name(file), raw, arrays))
        manifest, arrays = self.to_record(files, hashes)
        head, raw = seal(manifest, arrays, fmt=STUDY_FORMAT)
        try:
            check_study_manifest(head)
            check_study_arrays(
                head,
                arrays,
                self.layout,
                tuple(e.p for e in self.members),
                element_levels(self.layout, self.members),
            )
            check_study_claims(head, self)
        except EmulatorFileError as exc:
            raise GPMSAError(f"refusing to write {path}, it could not be read back: {exc}") from exc
        sealed.append((path, raw, arrays))

        def moved() -> None:  # (a failed folder flush after the moves leaves the new files)
            self.sha256 = head["content_sha256"]

        with atomic_group(on_moved=moved) as stage:
            for target, raw_manifest, member_arrays in sealed:
                write_sealed(target, raw_manifest, member_arrays, stage)
        return given

    def __repr__(self) -> str:
        c, n = self.draws["log_post"].shape
        return (f"Study({self.kind}, models={list(self.labels)}, shared={list(self.layout.shared)}"
                f", hierarchical={list(self.layout.groups)}, {c} chains x {n} draws)")  # fmt: skip


def load_study(path: str | Path, *, sha256: str | None = None) -> Study:
    """Read a study written by ``Study.save``: the study file and each model's file beside it.
    ``sha256``: the study file's expected ``content_sha256`` (``gpmsa info`` prints it), as
    ``gpmsa.load`` takes one: the study file lists each model file's, so it vouches for all.

    Every model file is read by ``gpmsa.load`` with the sha256 the study lists (an edited or
    replaced model file is refused); the study's fields and draws are validated against the
    models, and what the manifest says of them (the models' names and units, the kind, the
    chain and draw counts) against the draws and models
    (``gpmsa.studies.record.check_study_claims``); the diagnostics and convergence record are
    computed anew from the draws, as is ``posterior.info["at_bound"]`` (without a warning). A
    symbolic link ``path`` reads the model files beside the link's target. Raises
    EmulatorFileError naming the file and the field.

    >>> import gpmsa
    >>> gpmsa.load_study("no-such-study.gpmsa")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    gpmsa.errors.EmulatorFileError: ...no-such-study.gpmsa...
    """
    expected = check_expected_sha256(sha256)
    path = _through_link(check_path(path))
    # the files are read under the folder's shared lock: a save's moves (under its exclusive
    # lock) come before or after the reads, never between the study file's and its members'
    with folder_lock(path.parent, EmulatorFileError, shared=True):
        manifest, arrays = read_raw(path, check_study_manifest, formats=(STUDY_FORMAT,))
        verify_content(manifest, expected, path)
        study = manifest["study"]
        records = [_read_member(path, j, mod) for j, mod in enumerate(study["models"])]
    members = []
    for j, (mod, record) in enumerate(zip(study["models"], records, strict=True)):
        try:
            members.append(build(path.with_name(mod["file"]), *record))
        except EmulatorFileError as exc:
            raise EmulatorFileError(f"{path}: study.models[{j}] ({mod['label']}): {exc}") from exc
    labels = [mod["label"] for mod in study["models"]]
    try:
        layout = layout_of(members, labels, study["shared"], study["hierarchical"])
        check_study_arrays(
            manifest, arrays, layout, tuple(e.p for e in members), element_levels(layout, members)
        )
        saved = manifest["priors"]["hyper"]
        hyper = HyperPriors(**{"sd_prior": "gamma", **saved})  # no sd_prior: SEPIA's, as before
        out = Study(study["kind"], members, layout, hyper, arrays, manifest["settings"],
                    manifest["metadata"])  # fmt: skip
        check_study_claims(manifest, out)
        out.sha256 = manifest["content_sha256"]
        return out
    except EmulatorFileError as exc:
        raise EmulatorFileError(f"{path}: {exc}") from exc
    except GPMSAError as exc:
        raise EmulatorFileError(f"{path}: study: {exc}") from exc


def _read_member(path: Path, j: int, mod: dict) -> tuple[dict, dict]:
    """The record (manifest, arrays) of the study ``path``'s model ``j`` (``mod``: its entry of
    ``study.models``), read and checked as ``gpmsa.load`` reads it, with the sha256 listed."""
    try:
        return read_checked(path.with_name(mod["file"]), sha256=mod["sha256"])
    except EmulatorFileError as exc:
        raise EmulatorFileError(f"{path}: study.models[{j}] ({mod['label']}): {exc}") from exc


def _drawn_discrepancy(draws: dict[str, np.ndarray], j: int) -> dict[str, np.ndarray]:
    """Model j's discrepancy chains (C, N) from a calibration's draws ("betaV_j", "lamVz_j"),
    named as ``gpmsa.calibrate`` names them; none where the draws hold none."""
    beta, lam = discrepancy_arrays(j)
    if lam not in draws:
        return {}
    return to_samples(draws[beta], draws[lam])


def _discrepancy_chains(member, shape: tuple[int, int]) -> dict[str, np.ndarray]:
    """A fitted study model's discrepancy draws as chains of ``shape`` (n_chains, n_draws):
    "betaV" (one known input) or "betaV[k]", and "lamVz" (several precision groups:
    "betaV[k,g]", "lamVz[g]"); none for a model without one."""
    cal = getattr(member, "calibration", None) or {}
    if "betaV" not in cal or "lamVz" not in cal:
        return {}
    lam_vz = np.asarray(cal["lamVz"], dtype=float).reshape(*shape, -1)
    beta_v = np.asarray(cal["betaV"], dtype=float).reshape(*shape, member.p, lam_vz.shape[-1])
    return to_samples(beta_v, lam_vz)
