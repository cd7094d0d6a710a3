"""Known answers the convergence machinery is verified against (MODEL.md §4).

- ``free_free_frequencies``: the modes of the semi-discrete rod (γ = 0, lumped masses)
  about its natural state, ω_k(h) = (2/h)·√E·sin(kπh/2), whose continuum limit is kπ√E
  (second order in h).
- ``spring_wall_impact``: a linear elastic bar (length 1, mass 1, wave speed c, E = c²)
  hitting a linear spring of stiffness k at speed V, gravity off — the classical
  Saint-Venant problem with an elastic wall, solved by d'Alembert's method.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["free_free_frequencies", "spring_wall_impact"]


def free_free_frequencies(n: int, E: float, k: int | np.ndarray) -> np.ndarray:
    """Angular frequencies of modes ``k`` (1..N) of the semi-discrete free-free rod,
    m_i u_i'' = E((u_{i+1} − u_i) − (u_i − u_{i−1}))/h with end masses h/2: the
    eigenvalues of M⁻¹K are (4E/h²) sin²(kπh/2).

    Parameters
    ----------
    n : int
        Number of segments N (h = 1/N).
    E : float
        The linearised modulus f'(0) = c² [N].
    k : int or numpy.ndarray
        Mode numbers, 1..N (0 is the rigid-body mode).

    Returns
    -------
    numpy.ndarray
        ω_k [rad s⁻¹], the shape of ``k``.
    """
    h = 1.0 / n
    return 2.0 / h * math.sqrt(E) * np.sin(np.asarray(k) * math.pi * h / 2.0)


def spring_wall_impact(alpha: float, steps_per_transit: int = 20000) -> tuple[float, float]:
    """``(c·T_contact, restitution)`` of a linear bar hitting a linear spring, as functions
    of the stiffness ratio ``alpha = k/E`` (k·L/(EA) with L = A = 1) alone.

    d'Alembert: the displacement is F(t − x/c) + G(t + x/c); the free top reflects the
    outgoing wave, G'(s) = F'(s − 2/c).  In units of V and of the transit time 1/c
    (s = c t, W = c w_0/V, B = G'/V), the bottom's displacement w_0 obeys the delay
    equation  dW/ds = −α W + 2B(s),  B(s) = −½ for s < 2 (the incoming half of the
    uniform velocity −V),  B(s) = B(s − 2) − α W(s − 2)  after, while the spring is
    compressed (W < 0).  Contact ends at the first s > 0 with W = 0; the momentum the
    spring gave, α∫(−W) ds, makes the restitution e = α∫(−W) ds − 1.  Integrated with
    the trapezoidal rule on a grid that holds the delay exactly (second order;
    ``steps_per_transit`` = 20000 leaves errors below 1e-8).

    Parameters
    ----------
    alpha : float
        The stiffness ratio k/E, > 0.
    steps_per_transit : int
        Trapezoidal steps per transit time 1/c.

    Returns
    -------
    tuple of float
        ``(c·T_contact, restitution)``.

    Raises
    ------
    ValueError
        ``alpha`` <= 0.
    RuntimeError
        The contact does not end within 1000 delays (not reached for alpha > 0).
    """
    if not alpha > 0:
        raise ValueError(f"alpha = {alpha!r} is out of range (> 0)")
    m = 2 * int(steps_per_transit)          # steps per delay 2
    ds = 2.0 / m
    a = 0.5 * alpha * ds
    cap = 1000 * m                          # a bound far beyond any contact
    W = np.zeros(cap + 1)
    B = np.empty(cap + 1)
    B[:m + 1] = -0.5
    impulse = 0.0
    for n in range(cap):
        if n + 1 > m:
            B[n + 1] = B[n + 1 - m] - alpha * W[n + 1 - m]
        W[n + 1] = (W[n] * (1.0 - a) + ds * (B[n] + B[n + 1])) / (1.0 + a)
        if n > 0 and W[n + 1] >= 0.0:
            frac = W[n] / (W[n] - W[n + 1])        # linear root in the last step
            s_end = (n + frac) * ds
            impulse += 0.5 * (-W[n]) * frac * ds
            return float(s_end), float(alpha * impulse - 1.0)
        impulse += 0.5 * (-(W[n] + W[n + 1])) * ds
    raise RuntimeError(f"the contact did not end within s = {cap * ds:g}")
