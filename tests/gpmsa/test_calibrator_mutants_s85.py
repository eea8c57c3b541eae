"""Calibrator grid-update laws that mutation testing (session 85) found unchecked: successive
default-seeded updates draw afresh and a failed update is not counted; the observation digests
are recorded where the data are this window's alone; the nearest of the emulator's parameter
draws decides the outside-the-emulator warning, in ``update`` and ``log_likelihood_grid``."""

from __future__ import annotations

import warnings
from itertools import cycle

import numpy as np
import pytest
from _calib_cases import one_t_emulator, with_draws

from gpmsa import Calibrator, GPMSAError, OutsideEmulatorWarning
from gpmsa.calibration import calibrator as calibrator_module


def test_successive_updates_draw_afresh_and_a_failed_update_is_not_counted():
    emu, x, y = one_t_emulator()
    a = Calibrator(emu, method="grid", n_grid=33, seed=5)
    first, second = a.update(x, y), a.update(x, y)
    assert not np.array_equal(first.samples["t"], second.samples["t"])  # a fresh key each
    assert "updates=2" in repr(a)
    b = Calibrator(emu, method="grid", n_grid=33, seed=5)
    np.testing.assert_array_equal(b.update(x, y).samples["t"], first.samples["t"])
    with pytest.raises(GPMSAError):
        b.update(x, [[1.0, 2.0]])  # two outputs for a scalar emulator
    assert "updates=1" in repr(b)
    np.testing.assert_array_equal(b.update(x, y).samples["t"], second.samples["t"])


@pytest.mark.parametrize("prior", [None, "callable"])
def test_the_observation_digests_are_recorded_unless_the_prior_is_a_table(prior):
    emu, x, y = one_t_emulator()
    cal = Calibrator(emu, method="grid", n_grid=33)
    given = None if prior is None else (lambda t: -0.5 * ((t - 0.5) / 0.3) ** 2)
    info = cal.update(x, y, prior=given).info
    assert len(info["obs_values_sha256"]) == 64 and len(info["obs_layout_sha256"]) == 64
    table = cal.update(x, y, prior=np.zeros(33)).info  # maybe other windows' log-likelihood
    assert "obs_values_sha256" not in table and "obs_layout_sha256" not in table


def test_the_nearest_emulator_draw_decides_the_outside_warning(monkeypatch):
    emu, x, y = one_t_emulator()
    cal = Calibrator(with_draws(emu), method="grid", n_grid=33, emulator_params="draws")
    far = cycle([40.0, 1.0])  # one draw of each pair explains the data, the other does not
    monkeypatch.setattr(calibrator_module, "outside_sds", lambda *args: next(far))
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideEmulatorWarning)
        post = cal.update(x, y)
        cal.log_likelihood_grid(x, y)
    assert post.info["outside_sds"] == 1.0
