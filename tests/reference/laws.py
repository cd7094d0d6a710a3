"""The stress laws of MODEL.md §1, written out again in NumPy for the reference solvers.

Deliberately independent of rodjit's code: the reference solvers check rodjit, so they must
not share its formulas.  Rod stress f(ε), its derivative and primitive f̂ (f̂(0) = 0);
floor stress σ_b(h) ≥ 0 (pushes up), its derivative and primitive σ̂_b (σ̂_b(0) = 0).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def f(eps, kappa):
    return 0.5 * kappa * (eps + 0.5 - 0.5 / (1.0 + eps) ** 3)


def df(eps, kappa):
    return 0.5 * kappa * (1.0 + 1.5 / (1.0 + eps) ** 4)


def f_hat(eps, kappa):
    return 0.5 * kappa * (0.5 * eps**2 + 0.5 * eps + 0.25 / (1.0 + eps) ** 2 - 0.25)


def sigma_b(h, kappa_b, beta):
    h = np.minimum(h, 0.0)
    return kappa_b * (beta**3 / (h + beta) ** 3 - 1.0)


def dsigma_b(h, kappa_b, beta):
    return np.where(h <= 0.0, -3.0 * kappa_b * beta**3 / (np.minimum(h, 0.0) + beta) ** 4, 0.0)


def sigma_b_hat(h, kappa_b, beta):
    hm = np.minimum(h, 0.0)
    return kappa_b * (-(beta**3) / (2.0 * (hm + beta) ** 2) - hm + 0.5 * beta)


@dataclass(frozen=True)
class Params:
    """The physical parameters of MODEL.md §1 (defaults: the paper's μ = 100 setting)."""

    kappa: float = 100.0
    gamma: float = 0.0
    mu: float = 100.0
    kappa_b: float = 1000.0
    beta: float = 0.05
    g: float = -9.81
