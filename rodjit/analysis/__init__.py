"""Answers about the continuum rod: observables that are always defined, convergence
ladders with Richardson extrapolation, and calibration of parameters to measurements.

Sits above the sweep engine and the driver, below the command line."""
from .observables import (FirstImpact, OBSERVABLES, Physics, energy_vibration, first_impact,
                          lift_energy, macroscopic_contacts, merge_episodes, observables,
                          physics_of, wave_speed)

__all__ = ["observables", "first_impact", "FirstImpact", "macroscopic_contacts",
           "merge_episodes", "energy_vibration", "lift_energy", "wave_speed", "physics_of",
           "Physics", "OBSERVABLES"]
