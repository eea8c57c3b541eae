"""The GPM/SA model: data, transforms, output bases, priors, the GP correlation, the sampling
problem and its likelihood (unit-scale inputs and standardised outputs inside).
"""
