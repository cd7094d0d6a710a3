"""The semi-discrete rod of MODEL.md §2 as plain data: grid, masses, parameters, initial state."""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .laws import get_law, lower

__all__ = ["RodSystem", "build_system", "rod_system", "law_params", "grid", "masses",
           "initial_state", "start_velocity", "check_admissible"]


class RodSystem(NamedTuple):
    """Scalars every kernel needs; passed as one argument so a sweep compiles once."""

    n: int          # segments N
    h: float        # 1/N
    gamma: float    # beam regularisation
    mu: float       # viscosity
    g: float        # signed gravity along +u
    alpha: float = 0.0   # Hunt–Crossley floor damping α [s/m] (MODEL.md §1): 0 is none


def build_system(config):
    """``(RodSystem, rod law params, floor law params)`` for a Config."""
    return (rod_system(config.rod, config.gravity, config.floor),
            law_params("rod", config.rod), law_params("floor", config.floor))


def rod_system(rod, gravity, floor=None) -> RodSystem:
    """The RodSystem of a configuration's ``rod``, ``gravity`` and ``floor`` sections (the
    floor's damping α; none without ``floor``)."""
    n = rod.N
    alpha = 0.0 if floor is None else float(floor.damping)
    return RodSystem(int(n), 1.0 / n, float(rod.gamma), float(rod.mu), float(gravity.g),
                     alpha)


def law_params(kind: str, section):
    """The parameters of the ``kind`` ("rod" or "floor") law of a configuration's section of
    that name."""
    return get_law(kind, section.law).from_config(section)


def grid(n: int) -> np.ndarray:
    """Natural positions x_i = i h of the nodes."""
    return np.arange(n + 1, dtype=np.float64) / n


def masses(n: int) -> np.ndarray:
    """Lumped masses: h/2 at the ends, h inside (total 1)."""
    m = np.full(n + 1, 1.0 / n)
    m[0] = m[-1] = 0.5 / n
    return m


def initial_state(config, u0=None, v0=None) -> tuple[np.ndarray, np.ndarray]:
    """Initial heights and velocities: from the config, or the given profiles (checked)."""
    n = config.rod.N
    if u0 is None:
        ini = config.initial
        stretch = 1.0 + ini.strain
        u = grid(n)                    # u = height + (1 + strain) x, in place
        u *= stretch
        u += ini.height
        _check_resolved(ini.height, u, stretch / n)
    else:
        u = _profile("u0", u0, n)
    if v0 is None:
        v = np.empty(n + 1)
        ini = config.initial
        v.fill(start_velocity(ini.height, ini.velocity, ini.impact_speed, config.gravity.g))
    else:
        v = _profile("v0", v0, n)
    return u, v


def start_velocity(height: float, velocity: float, impact_speed: float | None,
                   g: float) -> float:
    """The uniform initial velocity of the nodes: ``initial.velocity``, or with
    ``initial.impact_speed`` = V set, the velocity w₀ < 0 at which a free fall from
    ``initial.height`` = h brings the bottom to the floor at speed V: w² − 2g·u is constant
    in free flight (u'' = g), so w₀ = −√(V² + 2g·h) (g signed along +u).  Started a little
    above the floor, the rod meets it as one dropped from rest from V²/(2|g|) does (g < 0;
    the free fall does not deform it), without the fall's steps: a restitution curve's
    points (``analysis.restitution``).  NaN where no such w₀ exists (V below the speed a
    fall from h already gives, which ``Config`` refuses)."""
    if impact_speed is None:
        return float(velocity)
    v2 = impact_speed * impact_speed
    w2 = v2 + 2.0 * g * height
    if w2 < 0.0 and w2 >= -1e-12 * v2:     # a start at the drop height itself, but for
        w2 = 0.0                           # rounding: from rest
    return -math.sqrt(w2) if w2 >= 0.0 else math.nan


def _check_resolved(height: float, u: np.ndarray, spacing: float) -> None:
    """The node spacing must survive adding ``height`` (else strains are cancellation)."""
    # ndarray methods and slices rather than np.diff / np.max, and the largest
    # |d_i - spacing| from the extreme differences alone (a subtraction is monotone in
    # floating point too, so the extremes commute with it exactly): the same value in
    # fewer NumPy calls, whose overhead at a few nodes is most of a short run's setup
    d = u[1:] - u[:-1]
    if max(d.max() - spacing, spacing - d.min()) > 1e-9 * abs(spacing):
        bound = 1e-9 * abs(spacing) / np.finfo(float).eps
        raise ValueError(f"initial.height = {height!r} is out of range: the rod's node "
                         f"spacing {spacing:.3g} is lost in rounding above |height| ~ "
                         f"{bound:.3g}")


def _profile(name: str, values, n: int) -> np.ndarray:
    try:
        arr = np.array(values, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be an array of numbers of length rod.N + 1 = {n + 1} "
                         f"({type(exc).__name__}: {exc})") from None
    if arr.ndim != 1 or arr.size != n + 1:
        raise ValueError(f"{name} must be a 1-D array of length rod.N + 1 = {n + 1}, "
                         f"got shape {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"{name}[{bad[0]}] = {float(arr[bad[0]])!r} is not finite")
    return arr


def check_admissible(u: np.ndarray, rod, floor, name: str = "u0") -> None:
    """Raise ValueError unless every segment strain and the bottom height are admissible."""
    n = u.size - 1
    d = u[1:] - u[:-1]
    lo = lower(rod)
    # the smallest strain d_i n - 1 is that of the smallest difference: x -> x n - 1 is
    # monotone in floating point too, so the minimum commutes with it exactly
    if not d.min() * n - 1.0 > lo:        # NaN fails too
        eps = d * n - 1.0
        i = np.flatnonzero(~(eps > lo))[0]
        raise ValueError(f"{name} is not admissible: strain of segment {i} is {float(eps[i])!r}, "
                         f"must be > {float(lo)!r} (the rod's compression limit; u must increase "
                         f"along the rod)")
    lo_b = lower(floor)
    if not u[0] > lo_b:
        raise ValueError(f"{name} is not admissible: bottom height u0[0] = {float(u[0])!r}, must be "
                         f"> {float(lo_b)!r} (the floor's bending limit -beta)")
