"""Exudyn vehicle models (half-car, Jackal), the 120 Hz accelerometer and the training campaign.

>>> import vehicle, roadgen
>>> road = roadgen.iso8608_profile(21, gd=400, seed=0, lead_in_m=1)
>>> trace = vehicle.simulate(vehicle.Jackal(), road, speed=1.0, noise_std=1.0, seed=1)  # enveloped
>>> sim = vehicle.Simulation(vehicle.Jackal(), road)          # closed loop: sim.advance(dt, speed)
>>> table = vehicle.run_campaign(vehicle.lhs_design(198, seed=0), seed=0)   # training data
"""

from vehicle.campaign import Campaign, load_campaign, run_campaign
from vehicle.design import lhs_design
from vehicle.errors import (
    CampaignFileError,
    SimulationDivergedError,
    SolverStepWarning,
    VehicleError,
)
from vehicle.linear import linear_model, linear_response
from vehicle.models import HalfCar, Jackal, from_description
from vehicle.simulate import Trace, simulate
from vehicle.simulation import Samples, Simulation

__all__ = [
    "Campaign",
    "CampaignFileError",
    "HalfCar",
    "Jackal",
    "Samples",
    "SimulationDivergedError",
    "Simulation",
    "SolverStepWarning",
    "Trace",
    "VehicleError",
    "from_description",
    "lhs_design",
    "linear_model",
    "linear_response",
    "load_campaign",
    "run_campaign",
    "simulate",
]
