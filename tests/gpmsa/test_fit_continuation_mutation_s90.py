"""Session 90: a fit's continuation (``gpmsa.fitting.continuation``) pinned where mutation
testing found the tests loose: the append step and its refusals at their edges, the pooled
chains and counts by hand, the source's sweeps, the ladder and hot copies a continuation
resumes, the pooled acceptance rates, the component order and the prior comparison."""

from __future__ import annotations

import functools
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from _continue_cases import continue_data
from _emulator_edit import replaced

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.fitting import continuation as cont
from gpmsa.model.problem import prepare


@functools.cache
def _tiny(joint: bool = True) -> gpmsa.Emulator:
    """A 4-sweep untuned fit of the shared problem, 2 chains, every sweep kept (thin 1)."""
    data, obs = continue_data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(data, obs if joint else None, n_iter=4, n_chains=2, seed=0, tune=False,
                         n_jobs=1)  # fmt: skip


def _source(**attrs) -> SimpleNamespace:
    """A stand-in for a fitted Emulator: only the attributes the function under test reads."""
    base = {
        "settings": {},
        "draws": {"lamUz": np.ones((2, 1))},
        "log_post": np.zeros(2),
        "calibration": None,
    }
    return SimpleNamespace(**{**base, **attrs})


# --- append_step, appended_thin ------------------------------------------------------------


@pytest.mark.parametrize("thin", [True, False, 0, -1, 1.0, 3.0, "3", None])
def test_append_step_refuses_a_step_that_is_not_a_positive_integer(thin):
    with pytest.raises(GPMSAError, match=r"init=emulator records none \(settings\['thin'\] = "):
        cont.append_step(thin, 10, 2, None)


def test_append_step_keeps_a_draw_from_n_iter_equal_to_the_step():
    assert cont.append_step(1, 1, 1, None) == 1
    assert cont.append_step(3, 3, 2, None) == 3  # the edge: one draw a chain
    assert cont.append_step(3, 3, 2, 2) == 3
    with pytest.raises(GPMSAError) as err:
        cont.append_step(3, 2, 2, None, source="init=study")
    assert str(err.value) == (
        "append=True keeps one sweep in 3 (init=study's step, settings['thin']): n_iter=2 "
        "keeps none; pass n_iter >= 3"
    )


def test_append_step_names_the_count_the_step_keeps():
    assert cont.append_step(3, 7, 2, 4) == 3  # 2 chains x (7 // 3) = 4
    for wrong in (3, 5, 8):
        with pytest.raises(GPMSAError) as err:
            cont.append_step(3, 7, 2, wrong)
        assert str(err.value) == (
            "append=True thins by init=emulator's step 3 (settings['thin']), which keeps 4 draws "
            f"of 2 chain(s) x 7 sweeps: pass n_keep=4, or leave n_keep out (got n_keep={wrong})"
        )


def test_appended_thin_checks_the_source_then_its_step():
    src = _source(settings={"n_chains": 2, "thin": 4})
    assert cont.appended_thin(src, 8, 2, None) == 4
    assert cont.appended_thin(src, 8, 2, 4) == 4
    with pytest.raises(GPMSAError, match=r"continues its 2 chain\(s\): pass n_chains=2$"):
        cont.appended_thin(src, 8, 1, None)
    with pytest.raises(GPMSAError, match="this emulator has no draws"):
        cont.appended_thin(_source(settings={"n_chains": 2, "thin": 4}, draws={}), 8, 2, None)
    with pytest.raises(GPMSAError, match=r"settings\['thin'\] = None"):
        cont.appended_thin(_source(settings={"n_chains": 2}), 8, 2, None)


def _two_components():
    """A simulator-only problem of 8 runs, 5 outputs and 2 components (betaU (2, 2))."""
    rng = np.random.default_rng(0)
    x, t = rng.random((8, 1)), rng.random((8, 1))
    g = np.linspace(0.0, 1.0, 5)
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + g) + t * g**2, x_names=["x"],
                         t_names=["t"])  # fmt: skip
    return prepare(data, n_pc=2).problem


# --- continued_widths -----------------------------------------------------------------------


def test_continued_widths_are_the_recorded_ones_in_this_fits_component_order():
    problem = _two_components()
    record = {"lamUz": [[1.0, 2.0], [3.0, 4.0]], "betaU": [[[0.1, 0.2], [0.3, 0.4]]] * 2,
              "lamWOs": [[5.0], [6.0]]}  # fmt: skip
    src = _source(settings={"backend": "torch", "step_widths": record})
    got = cont.continued_widths(src, problem, 2, [1, 0])
    assert got == {"lamUz": [[2.0, 1.0], [4.0, 3.0]], "betaU": [[[0.2, 0.1], [0.4, 0.3]]] * 2,
                   "lamWOs": [[5.0], [6.0]]}  # fmt: skip
    assert cont.continued_widths(src, problem, 2) == record
    for settings in (
        {"backend": "pyro", "step_widths": record},
        {"step_widths": record},
        {"backend": "numpy", "step_widths": {}},
        {"backend": "numpy"},
        None,
    ):
        assert cont.continued_widths(_source(settings=settings), problem, 2) is None
    damaged = _source(settings={"backend": "numpy", "step_widths": {"lamUz": [[1.0, 2.0]]}})
    with pytest.raises(GPMSAError) as err:
        cont.continued_widths(damaged, problem, 2)
    text = str(err.value)
    assert text.startswith("init=emulator: its recorded step widths (settings['step_widths']) "
                           "do not fit this fit (")  # fmt: skip
    assert text.endswith("); pass step_widths= or tune=True")
    assert err.value.__cause__ is None and err.value.__suppress_context__


# --- _has_draws, _chains_of, check_append --------------------------------------------------


def test_a_source_without_draws_or_log_posteriors_is_refused():
    cont._has_draws(_source())
    for attrs in ({"draws": {}}, {"log_post": np.zeros(0)}, {"draws": {}, "log_post": np.zeros(0)}):
        with pytest.raises(GPMSAError) as err:
            cont._has_draws(_source(**attrs))
        assert str(err.value) == (
            "init=emulator continues a fit's chains; this emulator has no draws "
            "(Emulator.from_params?)"
        )


@pytest.mark.parametrize(
    ("settings", "n_prev"), [(None, 1), ({}, 1), ({"n_chains": 0}, 1), ({"n_chains": 3}, 3)]
)
def test_the_chains_a_source_ran_must_be_the_continuations(settings, n_prev):
    cont._chains_of(_source(settings=settings), n_prev)
    for other in (n_prev - 1, n_prev + 1):
        with pytest.raises(GPMSAError) as err:
            cont._chains_of(_source(settings=settings), other)
        assert str(err.value) == (
            f"init=emulator continues its {n_prev} chain(s): pass n_chains={n_prev}"
        )


class _Kind:
    """A stand-in for the type whose instance ``append=True`` needs."""


def test_check_append_passes_a_plain_continuation_and_refuses_naming_the_argument():
    src = _Kind()
    assert cont.check_append(False, None, 5, kind=_Kind) is False
    assert cont.check_append(False, "fit.gpmsa", 5, kind=_Kind) is False
    assert cont.check_append(True, src, None, kind=_Kind) is True
    assert cont.check_append(True, src, 0, kind=_Kind) is True
    got = {None: "None", "fit.gpmsa": "'fit.gpmsa'", 3: "int", (1,): "tuple"}
    for init, text in got.items():
        with pytest.raises(GPMSAError) as err:
            cont.check_append(True, init, None, kind=_Kind, source="study", of="study")
        assert str(err.value) == (
            "append=True appends a continuation's draws to those of the study it continues: "
            f"pass init=that study (got init={text})"
        )
    for n_burn in (1, -1, 5):
        with pytest.raises(GPMSAError) as err:
            cont.check_append(True, src, n_burn, kind=_Kind)
        assert str(err.value).endswith(f"n_burn must be 0 or None, got {n_burn!r}")


# --- pool_chains, pool_draws ---------------------------------------------------------------


def test_pool_chains_puts_each_chains_second_draws_after_its_first():
    first = np.arange(8).reshape(4, 2)  # 2 chains x 2 draws
    second = 100 + np.arange(6).reshape(3, 2)[[0, 1, 2, 0, 1, 2]]  # 2 chains x 3 draws
    second[3:] += 10
    got = cont.pool_chains(first, second, 2)
    want = [[0, 1], [2, 3], [100, 101], [102, 103], [104, 105],
            [4, 5], [6, 7], [110, 111], [112, 113], [114, 115]]  # fmt: skip
    assert got.dtype == np.float64
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(cont.pool_chains([1.0, 2.0], [3.0], 1), [1.0, 2.0, 3.0])


def test_pool_draws_pools_every_part_and_refuses_what_the_source_lacks():
    src = _source(
        draws={"lamUz": np.array([[1.0], [2.0], [3.0], [4.0]]), "betaU": np.zeros((4, 2, 1))},
        calibration={"theta": np.array([[0.1], [0.2], [0.3], [0.4]])},
        log_post=np.array([-1.0, -2.0, -3.0, -4.0]),
    )
    retained = {"lamUz": np.array([[5.0], [6.0]]), "theta": np.array([[0.5], [0.6]])}
    pooled, lp, cal = cont.pool_draws(
        src, retained, np.array([-5.0, -6.0]), {"theta": np.array([[0.7], [0.8]])}, 2
    )
    np.testing.assert_array_equal(pooled["lamUz"], [[1.0], [2.0], [5.0], [3.0], [4.0], [6.0]])
    np.testing.assert_array_equal(pooled["theta"], [[0.1], [0.2], [0.5], [0.3], [0.4], [0.6]])
    np.testing.assert_array_equal(lp, [-1.0, -2.0, -5.0, -3.0, -4.0, -6.0])
    np.testing.assert_array_equal(cal["theta"], [[0.1], [0.2], [0.7], [0.3], [0.4], [0.8]])
    _, _, none = cont.pool_draws(src, {}, np.array([-5.0, -6.0]), None, 2)
    assert none is None
    with pytest.raises(GPMSAError) as err:
        cont.pool_draws(src, {"lamWs": np.ones((2, 1))}, np.zeros(2), None, 2)
    assert str(err.value) == (
        "append=True: init=emulator has no lamWs draws of shape (1,) to append to (another model?)"
    )
    with pytest.raises(GPMSAError, match=r"no lamUz draws of shape \(2,\)"):
        cont.pool_draws(src, {"lamUz": np.ones((2, 2))}, np.zeros(2), None, 2)
    with pytest.raises(GPMSAError, match=r"no lamOs draws of shape \(1,\)"):
        cont.pool_draws(src, {"lamOs": np.ones((2, 1))}, np.zeros(2), None, 2)
    with pytest.raises(GPMSAError) as err:
        cont.pool_draws(src, {}, np.zeros(2), {"theta": np.ones((2, 1)), "lamOs": None}, 2)
    assert str(err.value) == (
        "append=True: init=emulator's calibration draws ['theta'] are not this fit's "
        "['lamOs', 'theta']"
    )


def test_pool_draws_puts_per_component_draws_in_this_fits_order():
    src = _source(draws={"lamUz": np.array([[1.0, 2.0], [3.0, 4.0]])}, log_post=np.zeros(2))
    pooled, _, _ = cont.pool_draws(src, {"lamUz": np.array([[9.0, 8.0]])}, np.zeros(1), None, 1,
                                   order=[1, 0])  # fmt: skip
    np.testing.assert_array_equal(pooled["lamUz"], [[2.0, 1.0], [4.0, 3.0], [9.0, 8.0]])


# --- _sweeps, appended_counts, appended_record, sweeps_run ---------------------------------


@pytest.mark.parametrize(
    ("settings", "want"),
    [
        ({"n_iter": 60, "n_burn": 12}, (48, 60)),
        ({"n_iter": 5, "n_burn": 0}, (5, 5)),
        ({"n_iter": 0, "n_burn": 0}, (0, 0)),
        ({"n_iter": 60}, (None, 60)),
        ({"n_iter": 60, "n_burn": -1}, (None, 60)),
        ({"n_iter": 60, "n_burn": True}, (None, 60)),
        ({"n_iter": 60.0, "n_burn": 0}, (None, None)),
        ({"n_iter": -1, "n_burn": 0}, (None, None)),
        ({}, (None, None)),
        (
            {"appended_to": "d", "pooled_sweeps": 88, "sweeps_run": 100, "n_iter": 40, "n_burn": 0},
            (88, 100),
        ),  # fmt: skip
        ({"appended_to": None, "pooled_sweeps": 0, "sweeps_run": False}, (0, None)),
    ],
)
def test_a_sources_sweeps_from_its_settings(settings, want):
    assert cont._sweeps(settings) == want
    assert cont.sweeps_run(settings) == want[1]


def test_appended_counts_add_the_continuations_sweeps():
    got = cont.appended_counts({"n_iter": 60, "n_burn": 12}, "d" * 64, np.int64(16), 40)
    assert got == {"appended_to": "d" * 64, "appended_after": 16, "pooled_sweeps": 88,
                   "sweeps_run": 100}  # fmt: skip
    assert type(got["appended_after"]) is int
    assert cont.appended_counts({"n_iter": 60}, None, 3, 7) == {
        "appended_to": None,
        "appended_after": 3,
        "pooled_sweeps": None,
        "sweeps_run": 67,
    }
    assert cont.appended_counts({}, None, 3, 7)["sweeps_run"] is None
    src = SimpleNamespace(settings={"n_iter": 10, "n_burn": 2}, model_sha256="e" * 64, n_draws=12)
    assert cont.appended_record(src, 5, 3) == {
        "appended_to": "e" * 64,
        "appended_after": 4,
        "pooled_sweeps": 13,
        "sweeps_run": 15,
    }
    src = SimpleNamespace(settings=None, model_sha256=None, n_draws=7)
    assert cont.appended_record(src, 5, 2)["appended_after"] == 3  # 7 // 2


# --- component_order, reordered, _same_up_to_sign, _reordered_list --------------------------


def test_component_order_finds_each_column_up_to_its_sign():
    old = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    assert cont.component_order(SimpleNamespace(w=old), SimpleNamespace(w=old)) == [0, 1, 2]
    new = old[:, [2, 0, 1]] * [1.0, -1.0, 1.0]
    assert cont.component_order(SimpleNamespace(w=old), SimpleNamespace(w=new)) == [2, 0, 1]
    twins = np.array([[1.0, 1.0], [2.0, 2.0]])  # each source column used once
    assert cont.component_order(SimpleNamespace(w=twins), SimpleNamespace(w=-twins)) == [0, 1]
    other = old.copy()
    other[1, 2] += 1e-9
    assert cont.component_order(SimpleNamespace(w=old), SimpleNamespace(w=other)) is None
    assert cont.component_order(SimpleNamespace(w=old), SimpleNamespace(w=old[:, :2])) is None
    assert cont.component_order(SimpleNamespace(w=old), SimpleNamespace(w=old.T)) is None


def test_same_up_to_sign_holds_to_1e_12_absolute():
    a = np.array([1.0, -2.0])
    assert cont._same_up_to_sign(a, a) and cont._same_up_to_sign(a, -a)
    assert cont._same_up_to_sign(a, a + 0.5e-12) and cont._same_up_to_sign(a, -a - 0.5e-12)
    assert not cont._same_up_to_sign(a, a + 2e-12)
    assert not cont._same_up_to_sign(a, -a + 2e-12)
    assert not cont._same_up_to_sign(a, np.array([1.0, 2.0]))
    assert not cont._same_up_to_sign(a, 2.0 * a)


def test_reordered_moves_the_last_axis_of_per_component_parameters_only():
    v = np.arange(6.0).reshape(3, 2)
    for name in cont.PER_COMPONENT:
        np.testing.assert_array_equal(cont.reordered(name, v, [1, 0]), v[:, ::-1])
        assert cont.reordered(name, v, [0, 1]) is v
        assert cont.reordered(name, v, None) is v
    assert cont.reordered("lamWOs", v, [1, 0]) is v
    assert cont.reordered("theta", v, [1, 0]) is v
    got = cont.reordered("betaU", [[1.0, 2.0]], [1, 0])
    np.testing.assert_array_equal(got, [[2.0, 1.0]])


def test_a_recorded_list_is_reordered_or_left_as_given():
    record = [[1.0, None], [3.0, 4.0]]
    assert cont._reordered_list("lamUz", record, [1, 0]) == [[None, 1.0], [4.0, 3.0]]
    assert cont._reordered_list("lamUz", record, [0, 1]) is record
    assert cont._reordered_list("lamWOs", record, [1, 0]) is record
    assert cont._reordered_list("lamUz", 2.0, [1, 0]) == 2.0  # one width for every element
    short = [[1.0], [2.0]]  # a damaged record: its check names it
    assert cont._reordered_list("lamUz", short, [1, 0]) is short


# --- continued_steps ---------------------------------------------------------------------


@pytest.mark.parametrize(
    ("settings", "want"),
    [
        (None, None),
        ({"proportional_steps": True}, None),  # no backend recorded
        ({"backend": "pyro", "proportional_steps": True}, None),
        ({"backend": "numpy", "proportional_steps": True}, True),
        ({"backend": "torch", "proportional_steps": False}, False),
        ({"backend": "numpy", "proportional_steps": False, "tune": False}, False),
        ({"backend": "numpy", "tune": True}, False),
        ({"backend": "numpy", "tune": False}, True),
        ({"backend": "numpy", "tune": "no"}, None),
        ({"backend": "numpy"}, None),
    ],
)
def test_continued_steps_follow_the_record_or_its_tuning(settings, want):
    assert cont.continued_steps(_source(settings=settings)) is want


@pytest.mark.parametrize("steps", [1, 0, "yes", [True]])
def test_continued_steps_refuse_a_damaged_record(steps):
    src = _source(settings={"backend": "numpy", "proportional_steps": steps})
    with pytest.raises(GPMSAError) as err:
        cont.continued_steps(src)
    assert str(err.value) == (
        f"init=emulator: its settings['proportional_steps'] must be true, false or null, got "
        f"{steps!r}; pass proportional_steps= or tune=True"
    )


# --- source_ladders, continued_ladder, resumes_copies -------------------------------------


def test_source_ladders_of_an_untempered_or_a_tempered_source():
    assert cont.source_ladders({}, 2) == (None, None)
    assert cont.source_ladders({"temperatures": None, "n_chains": 5}, 2) == (None, None)
    ladder, every = cont.source_ladders({"temperatures": [1, 2.5], "n_chains": 2}, 2)
    assert every == 1 and ladder.tolist() == [1.0, 2.5] and ladder.ndim == 1
    ladder, every = cont.source_ladders({"temperatures": [1, 2], "swap_every": 4}, 3)
    assert every == 4 and ladder.tolist() == [1.0, 2.0]
    same = {"temperatures": [1, 2], "adapted_temperatures": [[1, 3], [1, 3]]}
    ladder, _ = cont.source_ladders(same, 2)
    assert ladder.tolist() == [1.0, 3.0]  # one ladder where every chain's is the same
    each = {"temperatures": [1, 2], "adapted_temperatures": [[1, 3], [1, 4]]}
    ladder, _ = cont.source_ladders(each, 2)
    assert ladder.tolist() == [[1.0, 3.0], [1.0, 4.0]]


def test_source_ladders_name_other_chains_before_a_damaged_record():
    with pytest.raises(GPMSAError) as err:
        cont.source_ladders({"temperatures": "x", "n_chains": 3}, 2, source="init=study")
    assert str(err.value) == "init=study continues its 3 chain(s): pass n_chains=3"
    for n_prev in (True, 3.0, "3"):  # not an int: left to the record's checks
        assert cont.source_ladders({"temperatures": [1, 2], "n_chains": n_prev}, 2)[1] == 1


@pytest.mark.parametrize(
    ("record", "why"),
    [
        ({"temperatures": 4}, "temperatures is a int, not a list"),
        ({"temperatures": [[1, 2]]}, "temperatures is a list, not a list"),
        ({"temperatures": [1, 2], "adapted_temperatures": [[1, 2]]},
         "adapted_temperatures of shape (1, 2), not (2, 2)"),
        ({"temperatures": [1, 2], "adapted_temperatures": [[1, 2, 3], [1, 2, 3]]},
         "adapted_temperatures of shape (2, 3), not (2, 2)"),
        ({"temperatures": [1, 2], "swap_every": 0}, None),
        ({"temperatures": [2, 3]}, None),
    ],
)  # fmt: skip
def test_source_ladders_name_a_damaged_record(record, why):
    with pytest.raises(GPMSAError) as err:
        cont.source_ladders(record, 2)
    text = str(err.value)
    assert text.startswith(
        "init=emulator: its tempering record (settings 'temperatures', 'adapted_temperatures', "
        "'swap_every') is damaged ("
    )
    assert text.endswith("); pass temperatures=")
    if why is not None:
        assert f"damaged ({why}); pass" in text


def test_continued_ladder_keeps_a_given_ladder_else_takes_the_sources():
    tempered = _source(settings={"temperatures": [1, 2], "swap_every": 5})
    options = {"temperatures": None}
    assert cont.continued_ladder(tempered, options, 2, "given") == "given"
    assert options == {"temperatures": None}
    options = {}
    assert cont.continued_ladder(_source(settings=None), options, 2, None) is None
    assert options == {}
    assert cont.continued_ladder(tempered, options, 2, None) == (1.0, 2.0)
    assert options == {"temperatures": [1.0, 2.0], "swap_every": 5}
    assert type(options["temperatures"]) is list
    options = {"swap_every": 3}
    cont.continued_ladder(tempered, options, 2, None)
    assert options["swap_every"] == 3
    options = {"swap_every": None}
    cont.continued_ladder(tempered, options, 2, None)
    assert options["swap_every"] == 5
    adapted = _source(settings={"temperatures": [1, 2], "adapted_temperatures": [[1, 3], [1, 4]]})
    options = {}
    assert cont.continued_ladder(adapted, options, 2, None) == (1.0, 3.0)
    assert isinstance(options["temperatures"], np.ndarray)
    assert options["temperatures"].tolist() == [[1.0, 3.0], [1.0, 4.0]]
    assert options["swap_every"] == 1


def _hot(**settings) -> dict:
    return {"hot_states": {}, "hot_step_widths": {}, "temperatures": [1, 2], **settings}


def test_resumes_copies_where_the_source_records_them_at_the_same_ladder():
    assert cont.resumes_copies(_hot(), {"temperatures": [1, 2]}, 2) is True
    assert (
        cont.resumes_copies(_hot(), {"temperatures": [1.0, 2.0], "adapt_ladder": False}, 2) is True
    )
    assert cont.resumes_copies(_hot(), {"temperatures": [1, 2], "adapt_ladder": True}, 2) is False
    assert cont.resumes_copies(_hot(), {"temperatures": [1, 3]}, 2) is False
    assert cont.resumes_copies(_hot(), {"temperatures": [1, 2, 4]}, 2) is False
    assert cont.resumes_copies(_hot(temperatures=[1, 2, 4]), {"temperatures": [1, 2]}, 2) is False
    assert cont.resumes_copies(_hot(), {"temperatures": None}, 2) is False
    assert cont.resumes_copies(_hot(), {}, 2) is False
    assert cont.resumes_copies(_hot(temperatures=None), {"temperatures": [1, 2]}, 2) is False
    for key in ("hot_states", "hot_step_widths"):
        assert cont.resumes_copies(_hot(**{key: None}), {"temperatures": [1, 2]}, 2) is False
    each = _hot(adapted_temperatures=[[1, 3], [1, 4]])
    mine = np.array([[1.0, 3.0], [1.0, 4.0]])
    assert cont.resumes_copies(each, {"temperatures": mine}, 2) is True
    assert cont.resumes_copies(each, {"temperatures": mine[::-1].copy()}, 2) is False
    assert cont.resumes_copies(each, {"temperatures": [1, 3]}, 2) is False


def test_resumes_copies_names_other_chains_and_resumes_none_of_a_damaged_record():
    assert cont.resumes_copies(_hot(temperatures="x"), {"temperatures": [1, 2]}, 2) is False
    assert (
        cont.resumes_copies(_hot(temperatures="x", n_chains=2), {"temperatures": [1, 2]}, 2)
        is False
    )
    with pytest.raises(GPMSAError) as err:
        cont.resumes_copies(_hot(n_chains=3), {"temperatures": [1, 2]}, 2, source="init=study")
    assert str(err.value) == "init=study continues its 3 chain(s): pass n_chains=3"
    assert cont.resumes_copies(_hot(n_chains=2), {"temperatures": [1, 2]}, 2) is True


# --- pool_accept ---------------------------------------------------------------------------


def _accept_source(backend="numpy", accept=(0.5, None), **settings):
    return _source(settings={"backend": backend, "n_iter": 60, "n_burn": 12, **settings},
                   diagnostics={"lamUz": {"accept": list(accept)}})  # fmt: skip


def test_pool_accept_weighs_both_parts_by_their_sweeps():
    rate = {"lamUz": np.array([[0.2, 0.4], [0.4, 0.8]])}  # 2 chains: means 0.3, 0.6
    summary = {"lamUz": {}, "lamWs": {}}
    cont.pool_accept(summary, _accept_source(), rate, 40, "torch")
    got = summary["lamUz"]["accept"]
    assert got[0] == pytest.approx((0.5 * 60 + 0.3 * 40) / 100, rel=1e-15) and np.isnan(got[1])
    assert summary["lamWs"] == {}
    summary = {"lamUz": {}}
    appended = _accept_source(appended_to="d", sweeps_run=100, pooled_sweeps=80)
    cont.pool_accept(summary, appended, rate, 50, "numpy")
    assert summary["lamUz"]["accept"][0] == pytest.approx((0.5 * 100 + 0.3 * 50) / 150, rel=1e-15)
    summary = {"lamUz": {}}
    cont.pool_accept(summary, _accept_source(accept=(0.5, 0.1)), rate, 40, "numpy", [1, 0])
    want = [(0.1 * 60 + 0.3 * 40) / 100, (0.5 * 60 + 0.6 * 40) / 100]
    np.testing.assert_allclose(summary["lamUz"]["accept"], want, rtol=1e-15)


def test_pool_accept_gives_no_rate_where_a_part_has_none_or_another_figure():
    rate = {"lamUz": np.array([[0.2, 0.4]])}
    cases = [
        (_accept_source(backend="pyro"), "numpy", rate),
        (_accept_source(), "pyro", rate),
        (_accept_source(n_iter=None), "numpy", rate),
        (_accept_source(accept=(0.5,)), "numpy", rate),
        (_accept_source(), "numpy", {}),
    ]
    for source, backend, rates in cases:
        summary = {"lamUz": {}}
        cont.pool_accept(summary, source, rates, 40, backend)
        assert summary == {"lamUz": {}}
    summary = {"lamUz": {}}  # both NUTS: pooled alike
    cont.pool_accept(summary, _accept_source(backend="pyro"), rate, 40, "pyro")
    assert summary["lamUz"]["accept"][0] == pytest.approx((0.5 * 60 + 0.2 * 40) / 100, rel=1e-15)
    summary = {"lamUz": {}}
    cont.pool_accept(summary, _source(settings={"backend": "numpy", "n_iter": 60, "n_burn": 0},
                                      diagnostics=None), rate, 40, "numpy")  # fmt: skip
    assert summary == {"lamUz": {}}


# --- _close, _prior_fields, _short ---------------------------------------------------------


def test_prior_records_are_the_same_to_1e_12_relative():
    assert cont._close(1.0, 1.0 + 5e-13) and cont._close(-2.0, -2.0 * (1 + 9e-13))
    assert not cont._close(1.0, 1.0 + 2e-12)
    assert cont._close(0.0, 0.0) and not cont._close(0.0, 1e-300)  # no absolute tolerance
    assert cont._close(1, 1.0) and not cont._close(1, 1.0 + 1e-13)  # an int: exactly
    assert cont._close("a", "a") and not cont._close("a", "b") and cont._close(None, None)
    assert cont._close([1.0, (2.0, 3.0)], [1.0, [2.0 + 1e-15, 3.0]])
    assert not cont._close([1.0, 2.0], [1.0, 2.0, 3.0]) and not cont._close([1.0], [2.0])
    assert not cont._close([], {}) and cont._close([], ())
    assert cont._close({"a": 1.0, "b": [2.0]}, {"b": [2.0], "a": 1.0 + 1e-15})
    assert not cont._close({"a": 1.0}, {"a": 1.0, "b": 2.0})
    assert not cont._close({"a": 1.0, "b": 2.0}, {"a": 1.0, "b": 2.1})
    assert not cont._close({"a": 1.0}, {"b": 1.0})


def test_prior_fields_name_up_to_three_fields_the_user_set():
    assert cont._prior_fields({"lamOs": 1, "lamWOs": 2, "corrected": 3}, {}) == ""
    assert cont._prior_fields({"a": 1}, {"a": 1}) == ""
    got = cont._prior_fields({"a": 1, "lamOs": 5, "c": [1]}, {"a": 2, "c": [1], "d": "x"})
    assert got == (" (priors: a: 1 there, 2 here; d: None there, 'x' here: give priors= as the "
                   "source was fitted with)")  # fmt: skip
    three = cont._prior_fields({"a": 1, "b": 1, "c": 1}, {})
    assert three.startswith(" (priors: a: 1 there, None here; b: ") and "more" not in three
    assert "; c: 1 there, None here: give" in three
    five = cont._prior_fields({"e": 1, "d": 1, "c": 1, "b": 1, "a": 1}, {})
    assert "; c: 1 there, None here; and 2 more: give priors=" in five and "d:" not in five
    four = cont._prior_fields({"d": 1, "c": 1, "b": 1, "a": 1}, {})
    assert "None here; and 1 more: give" in four


def test_short_cuts_a_long_repr_at_its_width():
    assert cont._short("x" * 58) == repr("x" * 58)  # 60 characters: as it is
    assert cont._short("x" * 59) == "'" + "x" * 56 + "..."  # 61: cut to 60
    assert len(cont._short(list(range(100)))) == 60
    assert cont._short([1, 2], width=5) == "[1, 2]"[:2] + "..."
    assert cont._short([1, 2], width=6) == "[1, 2]"


# --- _given, check_same_scales -------------------------------------------------------------


def _std(y_mean, y_sd, given=(), columnwise=False, lo=(0.0, 0.0), hi=(1.0, 1.0)):
    return SimpleNamespace(y_mean=np.asarray(y_mean), y_sd=y_sd, y_given=tuple(given),
                           columnwise=columnwise, x_min=np.array([lo[0]]),
                           x_max=np.array([hi[0]]), t_min=np.array([lo[1]]),
                           t_max=np.array([hi[1]]))  # fmt: skip


def test_given_shows_three_values_of_each_and_who_gave_them():
    old, new = _std([1.0, 2.0, 3.0, 4.0], 2.0, ["y_mean"]), _std([1.0, 2.0, 3.0], 0.5, ["y_sd"])
    assert cont._given(old, new, "y_mean") == (
        "[1, 2, 3, ...] (given)",
        "[1, 2, 3] (the runs' own)",
    )
    assert cont._given(old, new, "y_sd") == ("2 (the runs' own)", "0.5 (given)")
    one, two = _std([5.0], 1.0), _std([5.0, 6.0], 1.0, ["y_mean", "y_sd"])
    assert cont._given(one, two, "y_mean") == ("5 (the runs' own)", "[5, 6] (given)")
    near = _std([1.0], 1.0), _std([1.0], 1.0 + 1e-9)
    assert cont._given(*near, "y_sd") == ("1 (the runs' own)", "1.000000001 (the runs' own)")


def _scales_source(std, y):
    return SimpleNamespace(y=np.asarray(y, dtype=float), standardizer=std, x_names=("x",),
                           t_names=("t",))  # fmt: skip


def test_check_same_scales_names_each_input_and_output_scale_that_differs():
    y = [[1.0, 2.0], [3.0, 5.0]]
    same = _std([2.0, 3.5], 1.0)
    cont.check_same_scales(_scales_source(same, y), SimpleNamespace(y=y), _std([2.0, 3.5], 1.0))
    other = _std([0.0, 0.0], 9.0, columnwise=True, lo=(0.0, -1.0), hi=(2.0, 1.0))
    cont.check_same_scales(_scales_source(same, y), SimpleNamespace(y=[[1.0, 2.0]]), other)
    cont.check_same_scales(_scales_source(same, y), SimpleNamespace(y=[[1.0, 2.0], [3, 6]]), other)
    with pytest.raises(GPMSAError) as err:
        cont.check_same_scales(_scales_source(same, y), SimpleNamespace(y=y), other)
    assert str(err.value) == (
        "init=emulator mapped the same runs onto other unit values (SimData's x_range, t_range, "
        "y_scale, y_mean or y_sd): x: [0, 1] in init=emulator's fit, [0, 2] here; t: [0, 1] in "
        "init=emulator's fit, [-1, 1] here; y_scale: 'scalar' in init=emulator's fit, "
        "'columnwise' here; give its fit's, or start afresh"
    )
    lo_only = _std([2.0, 3.5], 1.0, lo=(0.5, 0.0))
    with pytest.raises(GPMSAError, match=r"\): x: \[0, 1\] in init=emulator's fit, \[0.5, 1\] "
                                         r"here; give"):  # fmt: skip
        cont.check_same_scales(_scales_source(same, y), SimpleNamespace(y=y), lo_only)


def test_check_same_scales_compares_a_given_mean_or_sd_whoever_gave_it():
    y = [[1.0, 2.0], [3.0, 5.0]]
    old = _std([2.0, 3.5], 1.0)
    given = _std([2.0, 3.0], 2.0, ["y_mean", "y_sd"], columnwise=True)
    with pytest.raises(GPMSAError) as err:
        cont.check_same_scales(_scales_source(old, y), SimpleNamespace(y=y), given)
    assert (": y_mean: [2, 3.5] (the runs' own) in init=emulator's fit, [2, 3] (given) here; "
            "y_sd: 1 (the runs' own) in init=emulator's fit, 2 (given) here; give") in str(
        err.value)  # fmt: skip
    assert "y_scale:" not in str(err.value)  # a given sd: its scale is the sd's
    with pytest.raises(
        GPMSAError, match=r"; y_sd: 2 \(given\) in init=emulator's fit, 1 \(the runs"
    ):
        cont.check_same_scales(_scales_source(given, y), SimpleNamespace(y=y), old)
    same_given = _std([2.0, 3.5], 1.0, ["y_mean", "y_sd"], columnwise=True)
    cont.check_same_scales(_scales_source(old, y), SimpleNamespace(y=y), same_given)
    with pytest.raises(GPMSAError, match=r"\): y_mean: \[2, 3.5\] \(given\) in init"):
        cont.check_same_scales(_scales_source(_std([2.0, 3.5], 1.0, ["y_mean"]), y),
                               SimpleNamespace(y=y), _std([2.0, 3.0], 1.0))  # fmt: skip
    own_mean = _std([9.0, 9.0], 1.0)  # neither gave a mean: the runs' own, the same runs
    cont.check_same_scales(_scales_source(old, y), SimpleNamespace(y=y), own_mean)


# --- _at_levels, discrepancy_moved ---------------------------------------------------------


def test_at_levels_puts_a_float32_rounded_level_back_on_it():
    problem = SimpleNamespace(theta_levels=[None, [0.0, 0.1, 0.3]])
    theta = np.array([[float(np.float32(0.1)), float(np.float32(0.1))],
                      [0.7, float(np.float32(0.3))], [0.25, 0.2]])  # fmt: skip
    cont._at_levels(problem, theta)
    assert theta.tolist() == [[float(np.float32(0.1)), 0.1], [0.7, 0.3], [0.25, 0.2]]
    same = theta.copy()
    cont._at_levels(SimpleNamespace(theta_levels=None), theta)
    np.testing.assert_array_equal(theta, same)


def test_discrepancy_moved_only_where_the_records_differ_with_observations():
    record = {"discrepancy_sha256": "a", "discrepancy_groups": None}
    assert cont.discrepancy_moved(record, dict(record), object()) is False
    assert cont.discrepancy_moved(record, {**record, "discrepancy_sha256": "b"}, None) is False


# --- _prior_record --------------------------------------------------------------------------


def test_prior_record_writes_shared_and_equal_per_element_priors_alike():
    shared = cont._prior_record(gpmsa.Priors(theta_mean=0.3), 0, 2)
    each = cont._prior_record(gpmsa.Priors(theta_mean=(0.3, 0.3)), 0, 2)
    assert shared == each
    assert (shared["theta_mean"], shared["theta_sd"]) == ([0.3, 0.3], [10.0, 10.0])
    assert "rhoV_a" not in shared and shared["lamVz"] == gpmsa.Priors().to_dict()["lamVz"]
    other = cont._prior_record(gpmsa.Priors(theta_mean=(0.3, 0.3, 0.2)), 0, 2)
    assert (other["theta_mean"], other["theta_sd"]) == ([0.3, 0.3, 0.2], 10.0)  # as written
    assert cont._prior_record(gpmsa.Priors(), 0, 0)["theta_mean"] == []


def test_prior_record_writes_each_groups_discrepancy_priors():
    gamma = gpmsa.GammaPrior(1.0, 0.0001)
    one = gpmsa.Priors(lamVz=gamma)
    record = cont._prior_record(one, 2, 1)
    assert record["lamVz"] == [{"a": 1.0, "b": 0.0001, "lower": 0.0, "upper": "inf"}] * 2
    assert (record["rhoV_a"], record["rhoV_b"]) == ([1.0, 1.0], [0.1, 0.1])
    assert record == cont._prior_record(gpmsa.Priors(lamVz=[gamma, gamma]), 2, 1)
    three = gpmsa.Priors(lamVz=[gamma] * 3)
    assert cont._prior_record(three, 2, 1)["lamVz"] == three.to_dict()["lamVz"]  # as written
    rho = gpmsa.Priors(rhoV_a=(1.0, 2.0), rhoV_b=(0.1, 0.3))
    got = cont._prior_record(rho, 2, 1)
    assert (got["rhoV_a"], got["rhoV_b"]) == ([1.0, 2.0], [0.1, 0.3])
    kept = cont._prior_record(rho, 3, 1)
    assert (kept["rhoV_a"], kept["rhoV_b"]) == (rho.to_dict()["rhoV_a"], rho.to_dict()["rhoV_b"])
    assert kept["lamVz"] == [gpmsa.Priors().to_dict()["lamVz"]] * 3


# --- continued_starts ---------------------------------------------------------------------


def test_continued_starts_refuse_the_same_outputs_at_other_runs():
    data, obs = continue_data()
    emu = _tiny()
    x = data.x.copy()
    x[[0, 1]] = x[[1, 0]]  # two runs' x swapped, their outputs as before: other runs
    moved = gpmsa.SimData(x=x, t=data.t, y=data.y, x_names=["x"], t_names=["t"])
    for sim in (moved, gpmsa.SimData(x=data.x, t=data.t[::-1].copy(), y=data.y, x_names=["x"],
                                     t_names=["t"])):  # fmt: skip
        prep = prepare(sim, obs)
        np.testing.assert_array_equal(prep.problem.w, emu.w)
        with pytest.raises(GPMSAError) as err:
            cont.continued_starts(emu, prep.problem, prep.K, obs, 2)
        assert str(err.value) == (
            "init=emulator was fitted to other simulation runs (or another n_pc or basis)"
        )
    prep = prepare(data, obs)
    got = cont.continued_starts(emu, prep.problem, prep.K, obs, 2)
    np.testing.assert_array_equal(got["theta"], emu.calibration["theta"][[3, 7]])


# --- continued_copies ---------------------------------------------------------------------


def _categorical_problem():
    """A joint problem of 12 runs whose second calibration input has 4 levels (unit 0, 1/3,
    2/3, 1), two observations."""
    rng = np.random.default_rng(3)
    x = rng.random((12, 1))
    t = np.column_stack([rng.random(12), np.arange(12) % 4])
    sim = gpmsa.SimData(x, t, np.sin(3 * x) + t[:, :1] + 0.5 * t[:, 1:], x_names=["s"],
                        t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
    obs = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[0.9], [1.4]])
    return prepare(sim, obs).problem


def _hot_record(problem, n_chains=2, **starts):
    """A hot-copy record (one hot copy a chain) at the problem's starts, widths 0.5."""

    def each(v):
        return np.broadcast_to(v, (n_chains, 1, *np.shape(v))).tolist()

    start = {k: each(v) for k, v in problem.init.items()}
    start.update(starts)
    widths = {k: each(np.full(np.shape(v), 0.5)) for k, v in problem.init.items()}
    return {"hot_states": start, "hot_step_widths": widths}


def test_continued_copies_put_a_float32_level_back_on_it():
    problem = _categorical_problem()
    third = float(np.float32(1 / 3))
    assert third != 1 / 3 and list(problem.theta_levels[1]) == [0.0, 1 / 3, 2 / 3, 1.0]
    theta = [[[0.25, third]], [[float(np.float32(0.25)), 1.0]]]
    src = _source(settings=_hot_record(problem, theta=theta))
    got = cont.continued_copies(src, problem, 2, [1.0, 2.0])
    assert set(got) == {"starts", "widths"}
    assert got["starts"]["theta"].tolist() == [[[0.25, 1 / 3]], [[float(np.float32(0.25)), 1.0]]]
    assert got["widths"] == src.settings["hot_step_widths"]
    damaged = _source(settings=_hot_record(problem, theta=[[["a", third]], [["b", 1.0]]]))
    with pytest.raises(GPMSAError) as err:
        cont.continued_copies(damaged, problem, 2, [1.0, 2.0])
    text = str(err.value)
    assert text.startswith(
        "init=emulator: its recorded hot copies (settings['hot_states'], "
        "settings['hot_step_widths']) do not fit this fit ("
    )
    assert text.endswith(
        "); pass tune=True (every copy tuned from the chain's last state) or temperatures= "
        "another ladder (1: none)"
    )
    assert err.value.__cause__ is None and err.value.__suppress_context__
    short = _source(settings=_hot_record(problem, theta=[[[third]], [[1.0]]]))
    with pytest.raises(GPMSAError, match="its recorded hot copies"):
        cont.continued_copies(short, problem, 2, [1.0, 2.0])


def test_continued_copies_put_per_component_states_and_widths_in_this_fits_order():
    problem = _two_components()
    record = _hot_record(problem, lamUz=[[[1.0, 2.0]], [[3.0, 4.0]]])
    record["hot_step_widths"]["lamUz"] = [[[0.1, 0.2]], [[0.3, 0.4]]]
    got = cont.continued_copies(_source(settings=record), problem, 2, [1.0, 2.0], [1, 0])
    assert got["starts"]["lamUz"] == [[[2.0, 1.0]], [[4.0, 3.0]]]
    assert got["widths"]["lamUz"] == [[[0.2, 0.1]], [[0.4, 0.3]]]
    assert got["starts"]["lamWOs"] == record["hot_states"]["lamWOs"]
    same = cont.continued_copies(_source(settings=record), problem, 2, [1.0, 2.0])
    assert same["starts"]["lamUz"] == [[[1.0, 2.0]], [[3.0, 4.0]]]
    with pytest.raises(GPMSAError, match="its recorded hot copies"):  # a ladder of 2 hot copies
        cont.continued_copies(_source(settings=record), problem, 2, [1.0, 2.0, 4.0])


def test_continued_starts_name_a_parameter_the_source_lacks_or_holds_in_another_shape():
    data, obs = continue_data()
    emu = _tiny()
    prep = prepare(data, obs)
    cal = dict(emu.calibration)
    lacking = replaced(emu, calibration={k: v for k, v in cal.items() if k != "lamOs"})
    wide = replaced(emu, draws={**emu.draws, "lamWs": np.ones((8, 2))})
    for source, name, shape in ((lacking, "lamOs", "(1,)"), (wide, "lamWs", "(1,)")):
        with pytest.raises(GPMSAError) as err:
            cont.continued_starts(source, prep.problem, prep.K, obs, 2)
        assert str(err.value) == (
            f"init=emulator has no {name} of shape {shape} (another discrepancy basis, groups "
            "or model?)"
        )


def test_continued_starts_name_the_prior_field_that_differs():
    data, obs = continue_data()
    emu = _tiny()
    other = gpmsa.Priors(lamVz=gpmsa.GammaPrior(2.0, 0.001))  # no discrepancy: its own record
    prep = prepare(data, obs, priors=other)
    with pytest.raises(GPMSAError) as err:
        cont.continued_starts(emu, prep.problem, prep.K, obs, 2)
    assert str(err.value) == (
        "init=emulator was another model: its priors differ from this fit's (priors: lamVz: "
        "{'a': 1.0, 'b': 0.001, 'lower': 0.0, 'upper': 'inf'} there, {'a': 2.0, 'b': 0.001, "
        "'lower': 0.0, 'upper': 'inf'} here: give priors= as the source was fitted with); "
        "continue it with the same settings, or start afresh"
    )
    prep = prepare(data, obs)
    assert cont._model_differences(emu, prep.problem) == ([], "")


def test_continued_starts_refuse_other_observations_of_the_same_shape():
    data, obs = continue_data()
    emu = _tiny()
    other = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[0.8], [1.2]])
    prep = prepare(data, other)
    with pytest.raises(GPMSAError) as err:
        cont.continued_starts(emu, prep.problem, prep.K, other, 2)
    assert str(err.value) == "init=emulator was fitted jointly with other observations"
    unrecorded = replaced(emu, settings={**emu.settings, "obs_sha256": None})  # an older file
    got = cont.continued_starts(unrecorded, prep.problem, prep.K, other, 2)
    np.testing.assert_array_equal(got["lamOs"], emu.calibration["lamOs"][[3, 7]])


def test_continued_starts_of_a_simulator_only_fit_and_its_refusals():
    data, obs = continue_data()
    emu = _tiny(joint=False)
    prep = prepare(data)
    got = cont.continued_starts(emu, prep.problem, prep.K, None, 2)
    assert set(got) == {"betaU", "lamUz", "lamWs", "lamWOs"}
    for name, value in got.items():
        np.testing.assert_array_equal(value, emu.draws[name][[3, 7]])
        assert value.dtype == np.float64
    with pytest.raises(GPMSAError) as err:
        cont.continued_starts(emu, prep.problem, prep.K, obs, 2)
    assert str(err.value) == (
        "init=emulator is a simulator-only fit; a joint fit (obs=) starts its own chains"
    )
    with pytest.raises(GPMSAError) as err:
        cont.continued_starts(_tiny(), prep.problem, prep.K, None, 2)
    assert str(err.value) == "init=emulator is a joint fit: pass its observations (obs=)"


def test_continued_starts_of_a_discrepancy_fit_and_a_discrepancy_added_or_dropped():
    data, obs = continue_data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(data, obs, n_iter=3, n_chains=2, seed=0, tune=False, n_jobs=1,
                        discrepancy="constant")  # fmt: skip
    prep = prepare(data, obs, discrepancy="constant")
    got = cont.continued_starts(emu, prep.problem, prep.K, obs, 2)
    for name in ("betaV", "lamVz", "theta"):
        np.testing.assert_array_equal(got[name], emu.calibration[name][[2, 5]])
    without, added = prepare(data, obs), prep
    for source, prep in ((emu, without), (_tiny(), added)):  # either way: another model
        with pytest.raises(GPMSAError) as err:
            cont.continued_starts(source, prep.problem, prep.K, obs, 2)
        assert str(err.value) == (
            "init=emulator was another model: its discrepancy differ from this fit's; continue "
            "it with the same settings, or start afresh"
        )
