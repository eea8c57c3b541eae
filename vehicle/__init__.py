"""Exudyn vehicle models (half-car, Jackal), the 120 Hz accelerometer and the training campaign."""
