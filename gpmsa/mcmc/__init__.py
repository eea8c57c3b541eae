"""GPM/SA's Metropolis-within-Gibbs sampler and its ``Chains``, step-size tuning, and the MCMC
diagnostics (ESS, R-hat, ArviZ).
"""
