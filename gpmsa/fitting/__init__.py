"""Fitting the emulator: ``fit`` (MCMC over the emulator's parameters) and the ``Emulator``."""
