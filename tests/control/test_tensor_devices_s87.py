"""A torch tensor on another device than the CPU (a GPU; here torch's "meta" device, which
numpy cannot read either): gpmsa's arrays named the argument but not the device ("x must be a
numeric array, got Tensor"), and ``BCR.update`` raised torch's bare TypeError; both now say
where the tensor is and how to bring it to the CPU, naming the argument."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel

import gpmsa
from control import BCR, ControlError


@pytest.fixture
def torch():
    """torch, imported by the tests that use it: without the torch extra they skip alone."""
    return pytest.importorskip("torch")


@pytest.mark.parametrize("as_list", [False, True])
def test_gpmsa_names_the_device_and_the_way_to_the_cpu(torch, as_list):
    x = torch.ones(5, 1, device="meta")
    given = [x[k] for k in range(5)] if as_list else x
    rng = np.random.default_rng(0)
    with pytest.raises(gpmsa.GPMSAError, match=r"^x must be a numeric array, got .*a torch "
                       r"tensor on device 'meta'.*tensor\.cpu\(\)"):  # fmt: skip
        gpmsa.SimData(x=given, t=rng.uniform(size=(5, 1)), y=rng.normal(size=(5, 1)))


def test_the_bcr_names_the_argument_of_a_tensor_it_cannot_read(torch):
    n = 50
    accel = torch.ones(n, device="meta")
    with pytest.raises(ControlError, match=r"^accel must be a 1-D sequence of numbers: .*cpu"):
        BCR(FakeBlockModel()).update(np.arange(n) / 120.0, 0.01 * np.arange(n), accel,
                                     np.ones(n))  # fmt: skip
