"""The predictability time of a chaotic run: when the runs of a time ladder stop agreeing
in the heights within their own error bar (docs/MODEL.md §5)."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["predictability_time", "PREDICTABILITY_CONVERGENCE", "PREDICTABILITY_NOISE",
           "PREDICTABILITY_FRACTION"]

# The runs along the time ladder disagree in the heights by more than their own error bar
# once the two finest differ by at least this share of what the two coarsest differ by (a
# refinement that no longer halves the runs' difference: the trajectory is then no longer
# one trajectory; docs/MODEL.md §5), counted above PREDICTABILITY_NOISE of the heights'
# range (the rounding and tolerance noise of runs that agree).
PREDICTABILITY_CONVERGENCE = 0.5
PREDICTABILITY_NOISE = 1e-6
# The former rule's fixed error bar (1 % of the heights' range); kept for callers that name
# it, no longer used by ``predictability_time``.
PREDICTABILITY_FRACTION = 0.01


def predictability_time(histories, t_end: float,
                        convergence: float = PREDICTABILITY_CONVERGENCE,
                        noise: float = PREDICTABILITY_NOISE) -> float:
    """The simulated time after which the runs of a time ladder disagree in the heights
    by more than their own error bar.

    The error bar of the two finest runs is what the ladder itself says: a refinement that
    converges shrinks the runs' difference (by the ratio of the errors, 4 to 16 for a
    refinement by 4), so the two finest differ by less than the two coarsest.  With D_c(t)
    and D_f(t) the largest difference (max over nodes, and over the output times up to t)
    of the coarsest and of the finest pair of the last three runs, the trajectory is lost
    at the first common output time with D_f ≥ ``convergence``·D_c and D_f above
    ``noise`` of the heights' range: the refinement no longer halves the difference, as
    when the runs have become unrelated trajectories of a chaotic motion.  inf if that
    never happens before ``t_end``; NaN without three runs with common output times (no
    snapshots, a failed run, a ladder of two).

    Parameters
    ----------
    histories : sequence of (t, u) or None
        Each run's snapshot times and heights, coarse to fine.
    t_end : float
        The runs' end [s].
    convergence : float
        The share of the coarse pair's difference at which the fine pair disagrees.
    noise : float
        Differences below this fraction of the heights' range are not counted.
    """
    hs = [h for h in histories if h is not None]
    if len(hs) < 3 or len(hs) != len(histories):
        return math.nan
    (t0, u0), (t1, u1), (t2, u2) = hs[-3:]
    n = min(len(t0), len(t1), len(t2))
    tol = 1e-9 * max(1.0, t_end)
    if (n < 2 or not np.allclose(t0[:n], t2[:n], rtol=0, atol=tol)
            or not np.allclose(t1[:n], t2[:n], rtol=0, atol=tol)):
        return math.nan
    scale = float(np.max(u2[:n]) - np.min(u2[:n]))
    if not scale > 0:
        return math.nan
    # running maxima: a difference that passes through 0 (the runs cross) is not agreement
    # (NaN counts as a disagreement: it propagates through the maxima)
    d_c = np.maximum.accumulate(np.max(np.abs(u1[:n] - u0[:n]), axis=1))
    d_f = np.maximum.accumulate(np.max(np.abs(u2[:n] - u1[:n]), axis=1))
    lost = ~((d_f < convergence * d_c) | (d_f <= noise * scale))
    bad = np.flatnonzero(lost)
    return float(t2[bad[0]]) if bad.size else math.inf
