"""GPM/SA-style Bayesian calibration.

An emulator fitted offline by MCMC, shared as a file, calibrated online.
"""

from gpmsa import backends, predictive
from gpmsa.calibration import calibrate
from gpmsa.calibrator import Calibrator
from gpmsa.data import ObsData, SimData
from gpmsa.emulator import Emulator, LooResult
from gpmsa.errors import BackendUnavailableError, EmulatorFileError, GPMSAError
from gpmsa.fileformat import load
from gpmsa.fitting import fit
from gpmsa.mcmc import Chains
from gpmsa.posterior import Posterior
from gpmsa.priors import GammaPrior, Priors
from gpmsa.problem import ObsProblem, Problem, prepare

__version__ = "0.1.0"

__all__ = [
    "BackendUnavailableError",
    "Calibrator",
    "Chains",
    "Emulator",
    "EmulatorFileError",
    "GPMSAError",
    "GammaPrior",
    "LooResult",
    "ObsData",
    "ObsProblem",
    "Posterior",
    "Priors",
    "Problem",
    "SimData",
    "backends",
    "calibrate",
    "fit",
    "load",
    "predictive",
    "prepare",
]
