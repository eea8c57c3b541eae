"""gpmsa under a caller's ``np.seterr(all="raise")`` (session 86): cautious scripts set it
before their imports, and ``import gpmsa`` raised FloatingPointError (a module constant, 1 / the
largest float64, is a subnormal: an underflow); a grid posterior's far tails underflow as
intended; ArviZ's R-hat of chains stuck apart is inf (its 0 / 0), not an error."""

import subprocess
import sys
from pathlib import Path

import numpy as np

from gpmsa.calibration.posterior import GridMarginal
from gpmsa.mcmc.diagnostics import ess, rhat

ROOT = Path(__file__).resolve().parents[2]


def test_the_packages_import_under_raise(tmp_path) -> None:
    code = (
        "import numpy as np\n"
        "np.seterr(all='raise')\n"
        "import control, gpmsa, roadgen, vehicle\n"
        "from gpmsa.fitting.validation import SMALLEST_PRECISION\n"
        "assert np.geterr() == dict.fromkeys(('divide', 'over', 'under', 'invalid'), 'raise')\n"
        "print(repr(SMALLEST_PRECISION))"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path,
        env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert float(done.stdout) == 1.0 / 1.7976931348623157e308 > 0.0


def test_a_grid_marginal_with_far_tails_reads_alike_under_raise() -> None:
    nodes = np.linspace(200.0, 600.0, 121)
    log_density = -0.5 * ((nodes - 300.0) / 3.0) ** 2  # down to ~ -4,400: exp underflows

    def read():
        m = GridMarginal.from_log_density(nodes, log_density)
        return (m.density.tolist(), m.mean(), m.sd(), m.cdf(nodes).tolist(),
                m.ppf([0.05, 0.5, 0.95]).tolist(), m.hdi(0.9),
                m.sample(np.random.default_rng(0), 50).tolist(), repr(m))  # fmt: skip

    default = read()
    with np.errstate(all="raise"):
        assert read() == default
    assert 0.0 in default[0] and min(d for d in default[0] if d > 0) < 1e-300  # (subnormals)


def test_rhat_of_chains_stuck_apart_is_inf_under_raise() -> None:
    stuck_apart = np.repeat([[1.0], [2.0]], 20, axis=1)
    default = ess(stuck_apart)
    with np.errstate(all="raise"):
        assert rhat(stuck_apart) == np.inf
        assert ess(stuck_apart) == default > 0  # the default state's number
