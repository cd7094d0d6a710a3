"""The configuration's physical numbers the observables of a run need (docs/MODEL.md §3).

The elastic wave speed c (``wave_speed``), the flight time τ = π h/c that separates two
bounces (``flight_time``), the least energy of a state with its bottom off the floor
(``lift_energy``), and the ``Physics`` tuple that carries them, with the end of the run,
to the contact and first-impact functions (``physics_of`` for a Result, ``physics_for``
for a run known by its arrays: a sweep point, a run file's summary).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import python_function

__all__ = ["Physics", "wave_speed", "flight_time", "lift_energy", "physics_of", "physics_for"]


class Physics(NamedTuple):
    """Numbers of the configuration the observables need (``physics_of``).

    Attributes
    ----------
    g : float
        Signed gravity along +u [m s⁻²].
    wave_speed : float
        c = sqrt(f'(0)) [m s⁻¹].
    lift_energy : float
        Least energy of a state with u_0 >= 0 [J] (−inf: no bound).
    t_final : float
        End of the run [s].
    flight_time : float
        τ [s]: a release followed by this long off the floor, with the centre of mass
        turning over, ends a macroscopic contact (a bounce).
    in_contact : bool
        u_0 < 0 at ``t_final``.
    contact_start : float
        Start of the episode still running at ``t_final`` [s] (NaN: none).
    """

    g: float              # signed gravity along +u
    wave_speed: float     # c = sqrt(f'(0))
    lift_energy: float    # least energy of a state with u_0 >= 0 (-inf: no bound)
    t_final: float        # end of the run
    flight_time: float    # τ: a flight is this long off the floor (and a turn-over)
    in_contact: bool      # u_0 < 0 at t_final
    contact_start: float  # start of the episode still running at t_final (NaN: none)


def wave_speed(config) -> float:
    """Elastic wave speed c = sqrt(f'(0)) of the rod law (sqrt(5κ/4) for Aiki–Kosugi).

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` section).

    Returns
    -------
    float
        c [m s⁻¹] in the reference length of the rod (length 1, mass 1).
    """
    from ..model.laws import get_law

    law = get_law("rod", config.rod.law)
    return math.sqrt(float(python_function(law.deriv)(0.0, law.from_config(config.rod))))


def flight_time(config) -> float:
    """τ = π h/c, the period of the highest mode of the semi-discrete rod (ω_max = 2c/h,
    c the ``wave_speed``, h = 1/N): the shortest time the discretisation resolves.  A
    release ends a bounce only if the bottom then stays off the floor at least this long
    and the centre of mass turns over (MODEL.md §3).

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` section).

    Returns
    -------
    float
        τ [s].
    """
    return math.pi / (config.rod.N * wave_speed(config))


def lift_energy(config) -> float:
    """min V(u) over the states with u_0 >= 0 (no kinetic energy), for g < 0: the rod
    standing on the floor at u_0 = 0 under its weight, each segment compressed by the
    weight above it, f(ε_{j+½}) = g Σ_{i>j} m_i.  The energy never increases, so a run
    whose energy falls below this can never have its bottom leave the floor again.
    ``-inf`` for g > 0 (no such bound), 0 for g = 0.

    Parameters
    ----------
    config : Config
        The configuration (its ``rod`` and ``gravity`` sections).

    Returns
    -------
    float
        The energy [J].
    """
    from ..model.laws import get_law, lower
    from ..model.system import masses

    g = float(config.gravity.g)
    if g > 0:
        return -math.inf
    if g == 0:
        return 0.0
    law = get_law("rod", config.rod.law)
    p = law.from_config(config.rod)
    value, primitive = python_function(law.value), python_function(law.primitive)
    n = config.rod.N
    m = masses(n)
    load = g * (1.0 - np.cumsum(m))[:-1]        # g · (mass above segment j), j = 0..N-1
    lo = float(lower(p))
    eps = np.empty(n)
    for j, s in enumerate(load):
        a, b = lo, 0.0                          # f(a) < s <= f(0) = 0: bisection to rounding
        if s == 0.0:
            eps[j] = 0.0
            continue
        for _ in range(200):
            mid = 0.5 * (a + b)
            if mid in (a, b):
                break
            if value(mid, p) < s:
                a = mid
            else:
                b = mid
        eps[j] = 0.5 * (a + b)
    h = 1.0 / n
    u = np.concatenate([[0.0], np.cumsum(h * (1.0 + eps))])
    stretch = sum(h * float(primitive(e, p)) for e in eps)
    return stretch - g * float(m @ u)


def physics_of(result, merge_time: float | None = None) -> Physics:
    """The Physics of a Result.

    Parameters
    ----------
    result : Result
        A run, from ``simulate`` or ``load_file``.
    merge_time : float, optional
        The flight time τ [s] that ends a macroscopic contact (``flight_groups``);
        default ``flight_time(config)`` = π h/c, the one the bounce table uses.

    Returns
    -------
    Physics

    Raises
    ------
    ValueError
        ``merge_time`` <= 0.
    """
    return physics_for(result.config, float(result.t_final), result.u_final,
                       result.diagnostics, result.episodes, result.bounces, merge_time)


def physics_for(config, t_final: float, u_final, diag, episodes, bounces,
                merge_time: float | None = None) -> Physics:
    """The Physics of a run of ``config`` that reached ``t_final`` in state ``u_final``
    (``physics_of`` without a Result: a sweep point, a run file's summary)."""
    c = wave_speed(config)
    tau = flight_time(config) if merge_time is None else float(merge_time)
    if not tau > 0:
        raise ValueError(f"merge_time = {merge_time!r} is out of range (seconds > 0)")
    u_final = np.asarray(u_final)
    in_contact = bool(u_final.size and u_final[0] < 0)
    start = math.nan
    if in_contact:
        start = _open_episode_start(diag, episodes, bounces)
    return Physics(float(config.gravity.g), c, lift_energy(config), float(t_final),
                   tau, in_contact, start)


def _open_episode_start(diag, episodes, bounces) -> float:
    """Start of the contact episode still running at the end of the run: the first
    diagnostics sample with u_0 < 0 after the last finished episode, back to the linear
    root of u_0 between it and the sample before (the first bounce's impact if no episode
    finished)."""
    t_ends = episodes["t_end"]
    if t_ends.size == 0 and bounces["t_impact"].size:
        return float(bounces["t_impact"][0])
    after = t_ends[-1] if t_ends.size else -math.inf
    t, u = diag["t"], diag["u_bottom"]
    idx = np.flatnonzero((t > after) & (u < 0))
    if idx.size == 0:
        return float(after) if math.isfinite(after) else 0.0
    k = int(idx[0])
    if k == 0 or t[k - 1] <= after:
        return float(t[k])
    return float(t[k - 1] + (t[k] - t[k - 1]) * u[k - 1] / (u[k - 1] - u[k]))
