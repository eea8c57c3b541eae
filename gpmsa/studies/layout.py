"""The study's calibration parameters: which theta element of which model is which study element.

A study of M models has one vector of study elements g (unit scale). Model i's theta (q_i,) is
``g[layout.index[i]]``. An element used by several models is *shared* (one value, one prior);
an element of a *hierarchical* group belongs to one model and has the prior
theta ~ Normal(mu, 1/lam) truncated to (0, 1), with mu and lam (the group's precision) sampled
too; every other element is the model's own, with the model's theta prior. docs/models.md.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gpmsa.errors import GPMSAError, UnusedSettingWarning, user_stacklevel

LABEL_RE = re.compile(r"\A[A-Za-z0-9_-]{1,48}\Z")  # \Z: "$" also matches before a final "\n"
"""A model's label: letters, digits, _ and -, at most 48 (it names the model's file)."""


SD_PRIORS = ("uniform", "gamma")
"""The group-spread priors: a uniform sd (the default) or SEPIA's Gamma on the precision."""


@dataclass(frozen=True)
class HyperPriors:
    """Hyperpriors of a hierarchical group (unit scale).

    mu ~ Normal(mu_mean, mu_sd) truncated to (0, 1). The group's spread: with ``sd_prior =
    "uniform"`` (default) its sd = 1/sqrt(lam) ~ Uniform(0, sd_max) (Gelman 2006's choice for
    few groups); with ``"gamma"`` the precision lam ~ Gamma(lam_a, lam_b) (shape, rate), SEPIA's
    prior (``HyperPriors.sepia()``). lam_start: the precision a chain starts from (None: SEPIA's
    5, or 4 / sd_max^2, an sd of sd_max / 2, where the uniform sd prior excludes 5). A study
    refuses an sd_max below ``SD_MAX_MIN`` (1e-3), which its chains cannot mix.
    """

    mu_mean: float = 0.5
    mu_sd: float = 10.0
    sd_prior: str = "uniform"
    sd_max: float = 1.0
    lam_a: float = 1.0
    lam_b: float = 1e-3
    lam_start: float | None = None

    def __post_init__(self) -> None:
        for name in NUMBERS:
            val = getattr(self, name)
            if name == "lam_start" and val is None:
                continue  # its default is set below, from sd_max
            if isinstance(val, bool) or not isinstance(val, (int, float, np.floating, np.integer)):
                raise GPMSAError(f"HyperPriors.{name} must be a number, got {val!r}")
            if not finite(val) or (name != "mu_mean" and not val > 0):
                need = "finite" if name == "mu_mean" else "finite and > 0"
                raise GPMSAError(f"HyperPriors.{name} must be {need}, got {val!r:.60}")
        far = (abs(self.mu_mean - 0.5) + 0.5) / self.mu_sd  # mu's farthest point, in mu_sd
        if not far < 1e150:  # ((mu - mu_mean) / mu_sd) ** 2 must stay a finite float
            raise GPMSAError(f"HyperPriors.mu_mean={self.mu_mean!r:.60} with mu_sd="
                             f"{self.mu_sd!r:.60}: the unit range (0, 1) of mu lies {far:.3g} "
                             "sds from the mean, beyond float range; give a mean within 1e150 "
                             "sds of (0, 1)")  # fmt: skip
        if not sd_max_usable(self.sd_max):
            raise GPMSAError(f"HyperPriors.sd_max={self.sd_max!r:.60}: its square and "
                             "4/sd_max^2 (the default start precision) must be finite, non-zero "
                             "float64s (sd_max within about 1.5e-154 to 1.3e154; an sd on the "
                             "unit scale: 0.01 to 10 is the useful range)")  # fmt: skip
        sd2 = float(np.float64(self.sd_max) ** 2)
        if self.lam_start is None:
            inside = self.sd_prior != "uniform" or 5.0 * sd2 > 1.0
            object.__setattr__(self, "lam_start", 5.0 if inside else 4.0 / sd2)
        if self.sd_prior not in SD_PRIORS:
            raise GPMSAError(f"HyperPriors.sd_prior must be one of {SD_PRIORS}, got "
                             f"{self.sd_prior!r}")  # fmt: skip
        if self.sd_prior == "uniform" and (self.lam_a, self.lam_b) != (1.0, 1e-3):
            warnings.warn(
                f"HyperPriors: lam_a={self.lam_a!r} and lam_b={self.lam_b!r} set the gamma "
                "prior of the precision, which sd_prior='uniform' does not use; give "
                "sd_prior='gamma' (SEPIA's: HyperPriors.sepia())", UnusedSettingWarning,
                stacklevel=user_stacklevel(),
            )  # fmt: skip
        if self.sd_prior == "uniform" and self.lam_start * self.sd_max**2 <= 1.0:
            raise GPMSAError(f"HyperPriors.lam_start={self.lam_start!r} gives a start sd "
                             f"{self.lam_start**-0.5:.3g} outside the uniform sd prior's "
                             f"(0, sd_max={self.sd_max!r})")  # fmt: skip

    @classmethod
    def sepia(cls) -> HyperPriors:
        """SEPIA's hyperpriors: mu ~ Normal(0.5, 10), lam ~ Gamma(1, 1e-3), start lam = 5."""
        return cls(sd_prior="gamma")

    @property
    def lam_min(self) -> float:
        """The smallest precision the spread prior allows (0 for the Gamma prior)."""
        return self.sd_max**-2 if self.sd_prior == "uniform" else 0.0

    def log_prior_lam(self, lam: float) -> float:
        """Log prior density of the precision lam, up to a constant (-inf outside its support)."""
        if not lam > self.lam_min:
            return -math.inf
        if self.sd_prior == "uniform":  # p(sd) = 1/sd_max: p(lam) = p(sd) |d sd / d lam|
            return -1.5 * math.log(lam)
        return (self.lam_a - 1.0) * math.log(lam) - self.lam_b * lam

    def to_dict(self) -> dict[str, float | str]:
        """JSON-able dict."""
        return {"sd_prior": self.sd_prior, **{k: float(getattr(self, k)) for k in NUMBERS}}


NUMBERS = ("mu_mean", "mu_sd", "sd_max", "lam_a", "lam_b", "lam_start")
"""HyperPriors' numeric fields."""

SD_MAX_DEFAULT = HyperPriors.sd_max
"""``HyperPriors.sd_max``'s default (1): a gamma sd prior takes no other."""

SD_MAX_MIN = 1e-3
"""The smallest ``HyperPriors.sd_max`` (uniform sd prior) a study with a hierarchical group runs
with. The sweep moves a group's elements and its mean one at a time, each within about sd_max
of the others: measured (docs/models.md), two chains at sd_max 3e-3 agreed after 10,000 sweeps
(R-hat 1.00), at 1e-3 they had not (1.65), and from about 1e-4 down a chain can stay at its
start (every proposal rejected, lam drifting to 1e308, the group sd reported as 1e-154)."""


@dataclass(frozen=True)
class Element:
    """One study element: its display name, the parameter's name, the (model, theta index) pairs
    that use it, its hierarchical group (-1: none) and its models' theta prior (mean, sd) of
    it (``Priors.theta_prior``; a hierarchical element's is its group's instead)."""

    name: str
    param: str
    uses: tuple[tuple[int, int], ...]
    group: int
    prior: tuple[float, float]


@dataclass(frozen=True)
class Layout:
    """The study's elements and how the models use them.

    labels: the models' labels; elements: the study elements in order; index: per model, the
    study element of each of its theta elements; groups: hierarchical parameter names (group g
    holds the elements with ``group == g``); bounds: native (lo, hi) of each element.
    """

    labels: tuple[str, ...]
    elements: tuple[Element, ...]
    index: tuple[tuple[int, ...], ...]
    groups: tuple[str, ...]
    bounds: tuple[tuple[float, float], ...]
    shared: tuple[str, ...]

    @property
    def n_elements(self) -> int:
        """Number of study elements."""
        return len(self.elements)

    def members_of(self, g: int) -> list[int]:
        """Study elements of hierarchical group g."""
        return [e for e, el in enumerate(self.elements) if el.group == g]

    def same_unit_value(self, e: int, a: float, b: float) -> bool:
        """Whether unit-scale values ``a`` and ``b`` of study element ``e`` are one native
        value: the layout takes models whose ranges of a shared parameter agree to 1e-12
        (relative), so one native value reads unit values that far apart (and a few ulps of
        rounding)."""
        lo, hi = self.bounds[e]
        return abs(a - b) <= 2e-12 * (abs(lo) + abs(hi)) / (hi - lo) + 8 * np.finfo(float).eps


def _names(arg, what: str) -> tuple[str, ...]:
    if isinstance(arg, str):
        arg = (arg,)
    if isinstance(arg, Mapping):  # {"E": 2e11}: its values would act on nothing
        raise GPMSAError(
            f"{what} must be a list of parameter names, got a dict {arg!r:.80}: its values "
            "would have no effect (fixed= holds a parameter at a value; hyper= sets every "
            f"hierarchical group's hyperpriors); give {what}={list(arg)!r:.80}"
        )
    if isinstance(arg, (set, frozenset)):  # its order varies from process to process
        raise GPMSAError(
            f"{what} must be a list or tuple of parameter names, got a set {arg!r:.80}: a "
            "set's order changes from one Python process to the next, and the study keeps it "
            "(init=study compares it; the hierarchical groups' order sets their posterior "
            "names' and the sweep's), so a seeded study would not rerun alike; give "
            f"{what}={sorted(map(str, arg))!r:.80} (a list)"
        )
    try:
        out = tuple(arg)
    except TypeError as exc:
        raise GPMSAError(f"{what} must be a sequence of parameter names, got {arg!r}") from exc
    for n in out:
        if not isinstance(n, str):
            raise GPMSAError(f"{what} must hold parameter names (str), got {n!r}")
    if len(set(out)) != len(out):
        raise GPMSAError(f"{what} names a parameter twice: {list(out)}")
    return out


def check_labels(labels, n_models: int) -> tuple[str, ...]:
    """The models' labels (default model0, model1, ...); GPMSAError for a bad or repeated one."""
    if labels is None:
        return tuple(f"model{i}" for i in range(n_models))
    if isinstance(labels, str):  # tuple("ab") would be ("a", "b")
        raise GPMSAError(f"labels must be a sequence of {n_models} strings, got {labels!r}")
    if isinstance(labels, (set, frozenset)):  # its order is not the models'
        raise GPMSAError(
            f"labels must be a list or tuple of {n_models} strings in the models' order, got a "
            f"set {labels!r:.80}: a set's order changes from one Python process to the next, so "
            "a model could take another's label"
        )
    labels = tuple(labels)
    if len(labels) != n_models:
        raise GPMSAError(f"got {len(labels)} labels for {n_models} models")
    for lab in labels:
        if not isinstance(lab, str) or not LABEL_RE.match(lab):
            raise GPMSAError(
                f"model label {lab!r}: use 1-48 letters, digits, '_' or '-' (it names a file)"
            )
    if len({lab.lower() for lab in labels}) != len(labels):  # files differ on any file system
        raise GPMSAError(f"model labels must differ, also in more than case, got {list(labels)}")
    return labels


def model_theta_priors(priors, q: int) -> list[tuple[float, float]]:
    """The theta prior (mean, sd) of each of a model's ``q`` calibration parameters under its
    ``priors`` (a ``gpmsa.Priors``: one shared, or per element; GPMSAError where those are not
    one per parameter)."""
    priors.theta_moments(q)
    return [priors.theta_prior(k) for k in range(q)]


def _element_prior(priors, k: int) -> tuple[float, float]:
    """Parameter k's (mean, sd) of one model's theta priors as ``build_layout`` takes them."""
    shared = len(priors) == 2 and all(isinstance(v, int | float) for v in priors)
    return tuple(priors) if shared else tuple(priors[k])


def build_layout(
    labels: tuple[str, ...],
    t_names: list[tuple[str, ...]],
    t_bounds: list[tuple[np.ndarray, np.ndarray]],
    theta_priors: list,
    shared=(),
    hierarchical=(),
) -> Layout:
    """The study's layout from each model's parameter names, native (t_min, t_max) and theta
    priors: per model, one (mean, sd) shared by its parameters or a list of one (mean, sd) per
    parameter (``model_theta_priors``).

    Raises GPMSAError naming the problem: a shared or hierarchical name no model has or only one
    model has, a name both shared and hierarchical, models whose ranges (t_min, t_max) of a
    shared or hierarchical parameter differ (the unit scale would mean different things), a
    shared parameter whose models' theta priors (of that parameter) differ.
    """
    shared = _names(shared, "shared")
    hier = _names(hierarchical, "hierarchical")
    both = sorted(set(shared) & set(hier))
    if both:
        raise GPMSAError(f"parameters {both} are both shared and hierarchical; choose one")
    if len(t_names) != len(labels) or len(t_bounds) != len(labels):
        raise GPMSAError(f"got {len(t_names)} models' parameter names and {len(t_bounds)} "
                         f"models' ranges for {len(labels)} labels")  # fmt: skip
    for what, names in (("shared", shared), ("hierarchical", hier)):
        for n in names:
            have = [labels[i] for i, ts in enumerate(t_names) if n in ts]
            if not have:
                known = sorted({t for ts in t_names for t in ts})
                raise GPMSAError(f"{what} parameter {n!r} is unknown: no model has it "
                                 f"(the models' parameters: {known})")  # fmt: skip
            if len(have) < 2:
                raise GPMSAError(f"{what} parameter {n!r} is in one model only ({have[0]}); "
                                 "it needs two or more")  # fmt: skip
            ranges = {labels[i]: (float(lo[ts.index(n)]), float(hi[ts.index(n)]))
                      for i, (ts, (lo, hi)) in enumerate(zip(t_names, t_bounds, strict=True))
                      if n in ts}  # fmt: skip
            first = next(iter(ranges.values()))
            if any(not np.allclose(r, first, rtol=1e-12, atol=0.0) for r in ranges.values()):
                raise GPMSAError(
                    f"{what} parameter {n!r} has different bounds in the models' designs "
                    f"(t ranges {ranges}); give the models one range for it (the unit scale "
                    "must mean the same value in every model)"
                )
    elements: list[Element] = []
    bounds: list[tuple[float, float]] = []
    index: list[list[int]] = []
    by_shared: dict[str, int] = {}
    for i, ts in enumerate(t_names):
        row = []
        lo, hi = t_bounds[i]
        for k, n in enumerate(ts):
            if n in by_shared:
                e = by_shared[n]
                el = elements[e]
                prior = _element_prior(theta_priors[i], k)
                if el.prior != prior:
                    raise GPMSAError(
                        f"shared parameter {n!r}: the models' theta priors (mean, sd) of it "
                        f"differ ({labels[el.uses[0][0]]}: {el.prior}, {labels[i]}: {prior}); "
                        "give each model the same prior of it, at its own position (fit_study's "
                        "priors=, one per model; a fitted emulator's with_calibration_priors)"
                    )
                elements[e] = Element(el.name, n, (*el.uses, (i, k)), -1, el.prior)
            else:
                e = len(elements)
                if n in shared:
                    by_shared[n] = e
                name = n if n in shared else f"{n}[{labels[i]}]"
                group = hier.index(n) if n in hier else -1
                elements.append(Element(name, n, ((i, k),), group,
                                        _element_prior(theta_priors[i], k)))  # fmt: skip
                bounds.append((float(lo[k]), float(hi[k])))
            row.append(e)
        index.append(row)
    return Layout(tuple(labels), tuple(elements), tuple(tuple(r) for r in index), hier,
                  tuple(bounds), shared)  # fmt: skip


def posterior_names(layout: Layout) -> list[str]:
    """The names of a study's posterior (``gpmsa.studies.study.native_chains``), in order."""
    return ([el.name for el in layout.elements] + [f"lamOs[{lab}]" for lab in layout.labels]
            + [f"{g}.{k}" for g in layout.groups for k in ("mu", "sd", "lam")])  # fmt: skip


def check_study_names(layout: Layout) -> None:
    """GPMSAError when a study's posterior names could be confused: a calibration parameter
    whose name holds "[" or "]" (the study names a model's own parameter NAME[LABEL] and its
    lamOs lamOs[LABEL]), or two posterior names alike (e.g. a shared parameter "E.mu" and the
    mean "E.mu" of a hierarchical E), whose draws would overwrite each other."""
    for el in layout.elements:
        if "[" in el.param or "]" in el.param:
            raise GPMSAError(
                f"calibration parameter {el.param!r}: a study's parameter names may not hold '[' "
                "or ']' (the study names a model's own parameter NAME[LABEL] and its lamOs "
                "lamOs[LABEL]); rename it"
            )
    names = posterior_names(layout)
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise GPMSAError(
            f"the study's posterior would name several quantities {twice} (a hierarchical "
            "group's NAME.mu, NAME.sd and NAME.lam, a model's NAME[LABEL] and lamOs[LABEL]); "
            "rename the calibration parameter"
        )


def check_hyper(hyper: HyperPriors, given: bool, layout: Layout, fresh: bool = True) -> None:
    """GPMSAError where the study's hyperpriors cannot act as given: ``hyper=`` passed
    (``given``) to a study with no hierarchical group, or with ``sd_prior="gamma"`` and an
    ``sd_max`` of its own in a new study (``fresh``; only the uniform sd prior uses it; a
    continuation takes its source's as they are), or a uniform sd prior's ``sd_max`` below
    ``SD_MAX_MIN`` in one with a group."""
    if not layout.groups:
        if given:
            raise GPMSAError(
                "hyper: hyperpriors set the priors of a hierarchical group's mean and spread, "
                "and this study has no hierarchical group (hierarchical=()); name the "
                "parameter(s) whose per-model values form a group (hierarchical=['E']), or "
                "leave hyper out"
            )
        return
    if given and fresh and hyper.sd_prior == "gamma" and hyper.sd_max != SD_MAX_DEFAULT:
        raise GPMSAError(
            f"HyperPriors.sd_max={hyper.sd_max!r:.60} with sd_prior='gamma': sd_max bounds the "
            "uniform sd prior, and the gamma prior (lam ~ Gamma(lam_a, lam_b)) does not use it, "
            "so it would have no effect; give sd_prior='uniform' to bound the group sd by "
            "sd_max, or leave sd_max out (the gamma prior's spread is set by lam_a and lam_b)"
        )
    if hyper.sd_prior == "uniform" and not hyper.sd_max >= SD_MAX_MIN:
        raise GPMSAError(
            f"HyperPriors.sd_max={hyper.sd_max!r:.60} is below {SD_MAX_MIN:g}: the study's "
            "sampler cannot mix a hierarchical group whose sd is held that small (its chains "
            "stay near their start); 0.01 to 10 is the useful range (unit scale), and for a "
            f"parameter that takes one value in every model use shared={list(layout.groups)}"
        )


def sd_max_usable(sd_max) -> bool:
    """Whether the finite ``sd_max`` > 0 has a square and a 4/sd_max^2 (the default start
    precision) that are finite, non-zero float64s: the prior works with sd^2, lam_min 1/sd^2
    and the default start lam 4/sd^2 (sd_max within about 1.5e-154 to 1.3e154)."""
    with np.errstate(over="ignore", under="ignore", divide="ignore"):
        sd2 = float(np.float64(sd_max) ** 2)
    return finite(sd2) and sd2 > 0 and finite(4.0 / sd2)


def finite(val) -> bool:
    """Whether the number ``val`` is finite; an integer beyond float64 (10**400) is not, and a
    huge one within it (10**30, which numpy's isfinite refuses) is."""
    try:
        return math.isfinite(float(val))
    except OverflowError:
        return False
