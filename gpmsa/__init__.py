"""GPM/SA-style Bayesian calibration.

An emulator fitted offline by MCMC, shared as a file, calibrated online.
"""

from gpmsa import backends, limits, plots, predictive
from gpmsa._version import __version__ as __version__
from gpmsa.calibration.calibrate import calibrate
from gpmsa.calibration.calibrator import Calibrator
from gpmsa.calibration.posterior import Posterior
from gpmsa.errors import (
    AtBoundWarning,
    BackendUnavailableError,
    BasisWarning,
    ChainError,
    ChainRetryWarning,
    ConvergenceWarning,
    DomainWarning,
    EmulatorFileError,
    ExtrapolationWarning,
    FewDrawsWarning,
    GPMSAError,
    GPMSAWarning,
    GridResolutionWarning,
    NuggetWarning,
    OutlierRunWarning,
    OutsideEmulatorWarning,
    ReductionWarning,
    ResourceLimitError,
    StartRejectedError,
    UnusedSettingWarning,
)
from gpmsa.fitting.emulator import Emulator, LooResult, load
from gpmsa.fitting.fit import fit
from gpmsa.mcmc.sampler import Chains
from gpmsa.model.data import ObsData, SimData
from gpmsa.model.priors import GammaPrior, Priors
from gpmsa.model.problem import ObsProblem, Problem, prepare
from gpmsa.predictive import (
    calibrated_predict,
    calibration_posterior,
    cross_validate,
    emulator_prediction,
    full_prediction,
    sensitivity,
)
from gpmsa.studies.layout import HyperPriors
from gpmsa.studies.run import calibrate_study, fit_study
from gpmsa.studies.study import Study, load_study

__all__ = [
    "AtBoundWarning",
    "BackendUnavailableError",
    "BasisWarning",
    "Calibrator",
    "ChainError",
    "ChainRetryWarning",
    "Chains",
    "ConvergenceWarning",
    "DomainWarning",
    "Emulator",
    "EmulatorFileError",
    "ExtrapolationWarning",
    "FewDrawsWarning",
    "GPMSAError",
    "GPMSAWarning",
    "GammaPrior",
    "GridResolutionWarning",
    "HyperPriors",
    "LooResult",
    "NuggetWarning",
    "ObsData",
    "ObsProblem",
    "OutlierRunWarning",
    "OutsideEmulatorWarning",
    "Posterior",
    "Priors",
    "Problem",
    "ReductionWarning",
    "ResourceLimitError",
    "StartRejectedError",
    "UnusedSettingWarning",
    "SimData",
    "Study",
    "backends",
    "calibrate",
    "calibrate_study",
    "calibration_posterior",
    "cross_validate",
    "emulator_prediction",
    "fit",
    "fit_study",
    "full_prediction",
    "calibrated_predict",
    "limits",
    "load",
    "load_study",
    "plots",
    "predictive",
    "prepare",
    "sensitivity",
]
