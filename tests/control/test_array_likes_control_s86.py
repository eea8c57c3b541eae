"""The online side given array-likes of other libraries and numpy scalars of other widths.

A torch tensor that records gradients stopped ``BCR.update`` with torch's RuntimeError "Can't
call numpy() on Tensor that requires grad"; the BCR reads only the values, so it now gives the
plain arrays' estimates. An ``Estimate`` built with a numpy float32 (or float16, longdouble)
``gd_mean`` made the Simplex's law compute in that type (NEP 50): GD 320 commanded 1.2 m/s, its
float64 twin 1.3 m/s; an Estimate now stores numpy scalars as Python numbers, as the settings
do."""

import dataclasses

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

from control import BCR, Estimate, Simplex


@pytest.fixture
def torch():
    """torch, imported by the tests that use it: without the torch extra they skip alone."""
    return pytest.importorskip("torch")


def _key(e: Estimate) -> str:
    return repr((e.status, e.reason, e.gd_mean, e.gd_sd, e.interval, e.data_time, e.speed))


def _feed(samples, chunk=240) -> list[str]:
    bcr = BCR(FakeBlockModel())
    n = len(samples[0])
    return [_key(bcr.update(*(x[i : i + chunk] for x in samples))) for i in range(0, n, chunk)]


def test_tensors_that_require_grad_give_the_plain_arrays_estimates(torch):
    samples = stream(lambda s: np.where(s < 8.0, 300.0, 500.0), 1.2, 10.0, seed=86)
    grad = [torch.tensor(x, requires_grad=True) for x in samples]
    assert _feed(grad) == _feed(samples)


@pytest.mark.parametrize("kind", [np.float16, np.float32, np.longdouble, np.int16])
def test_an_estimate_of_numpy_scalars_commands_as_its_float64_twin(kind):
    def estimate(convert):
        return Estimate(convert(1.0), convert(1.0), "ok", gd_mean=convert(320.0),
                        gd_sd=convert(5.0), interval=(convert(310.0), convert(330.0)),
                        speed=convert(1.0))  # fmt: skip

    odd, ref = estimate(kind), estimate(float)
    for name in ("time", "position", "gd_mean", "gd_sd", "speed"):
        assert type(getattr(odd, name)) in (float, int), name
    assert all(type(v) in (float, int) for v in odd.interval)
    for simplex in (Simplex(), Simplex(speed_step_mps=0.0), Simplex(risk=0.1)):
        assert _same(simplex.command(odd), simplex.command(ref))


def _same(a, b) -> bool:
    """Commands equal field by field, NaN equal to NaN (Python >= 3.13's dataclass == compares
    fields, where a filling estimate's gd_used NaN differs from itself)."""
    pairs = zip(dataclasses.astuple(a), dataclasses.astuple(b), strict=True)
    return all(x == y or (x != x and y != y) for x, y in pairs)
