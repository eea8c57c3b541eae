"""GPM/SA-style Bayesian calibration: emulator fitted offline by MCMC, shared as a file, calibrated online."""
