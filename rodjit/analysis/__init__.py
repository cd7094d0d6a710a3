"""Answers about the continuum rod: observables that are always defined, convergence
ladders with Richardson extrapolation, and calibration of parameters to measurements.

Sits above the sweep engine and the driver, below the command line."""

from .converge import Convergence, converge, load_convergence
from .fit import FitError, FitResult, fit
from .fit_table import LawComparison, TableFit, compare_laws, fit_table, read_measurements
from .known import free_free_frequencies, spring_wall_impact
from .observables import (FirstImpact, OBSERVABLES, Physics, energy_vibration, first_impact,
                          lift_energy, macroscopic_contacts, merge_episodes, observables,
                          physics_of, wave_speed)
from .restitution import curve_report, restitution_curve

__all__ = ["observables", "first_impact", "FirstImpact", "macroscopic_contacts",
           "merge_episodes", "energy_vibration", "lift_energy", "wave_speed", "physics_of",
           "Physics", "OBSERVABLES", "converge", "Convergence", "load_convergence",
           "free_free_frequencies", "spring_wall_impact", "fit", "FitResult", "FitError",
           "fit_table", "TableFit", "read_measurements", "restitution_curve", "curve_report", "compare_laws",
           "LawComparison"]
