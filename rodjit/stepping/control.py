"""Step-size control: every constant and rule that sets the length of a step.

The scheme suggests the next step (``StepResult.dt_suggest``: cfl × its stability limit, or
the step its error ratio allows); the rules here cap it (``dt_max``, growth per step, the
approach to the barriers), cut it to land on the output times, shrink it after a rejected
trial, and end it on a floor crossing.  ``build`` makes the loop's ``Control`` from a
``TimeConfig``; the compiled loop (``loop.advance``) calls the kernels below.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from . import registry
from .._jit import step_kernel

__all__ = ["Control", "build", "output_tolerance", "propose", "gap_limit", "step_to",
           "gap_keep", "GROWTH", "GAP_MAX", "REJECT_SHRINK", "EVENT_MIN", "OUTPUT_TOL",
           "LAND_FIXED", "LAND_ADAPTIVE", "SPLIT_BELOW", "GAP_REJECT", "GAP_CLOSE_MAX", "retry",
           "STABILITY_CFL"]

# A proposal grows at most by this factor per step: after a rejection the step recovers
# over a few steps instead of jumping back to the size that just failed.
GROWTH = 1.5
# The barrier-gap fraction a step may close is time.cfl, but at most this: a step closing
# more than half the gap to ε = −1 or u_0 = −β lands where the stiffness is 16× larger.
GAP_MAX = 0.5
# A failed trial step (not admissible, not finite, no convergence, too close to a barrier)
# is retried at this fraction of its size: a failure means the step was far too long.
REJECT_SHRINK = 0.25
# A step that crosses u_0 = 0 is redone to end on the crossing unless the crossing is this
# close to the step's start (a shorter step would gain nothing and cost a step).
EVENT_MIN = 1e-3
# Two output times closer than this fraction of the shortest output interval (or of the
# remaining run) coincide: rounding in t0 + k·Δ must not emit a row twice or skip one.
OUTPUT_TOL = 1e-9
# A step within this relative distance of the next output time ends on it.  Fixed steps
# land only when rounding is all that separates them from it; adaptive ones also absorb a
# remainder too small to be worth a step of its own.
LAND_FIXED = 1e-9
LAND_ADAPTIVE = 1e-6
# A remainder shorter than this many proposed steps is taken as two equal steps instead of
# one full step and a sliver (a sliver wastes a step and sets a tiny next proposal).
SPLIT_BELOW = 2.0
# The loop rejects a step that closed more than GAP_REJECT × the allowed fraction of a
# barrier gap (the proposal aims at the fraction; twice it means the stiffness rose faster
# than the last step predicted), and any step that closed more than GAP_CLOSE_MAX of it.
GAP_REJECT = 2.0
GAP_CLOSE_MAX = 0.9

# Under tolerance control (time.control = "tolerance") an explicit scheme's step is the one
# its error estimate allows, capped at this fraction of its stability limit 2/ω (a bound
# from Gershgorin, itself above the true ω): accuracy decides, stability only caps.
STABILITY_CFL = 0.5


class Control(NamedTuple):
    """Step-size control: caps, fixed step (0: adaptive), growth and barrier-gap limits."""

    dt_max: float     # inf when unset
    dt_min: float
    dt_fixed: float   # > 0: fixed steps
    growth: float     # a proposal grows at most by this factor per step
    gap: float        # a step closes at most this fraction of the distance to a barrier
                      # (ε = −1, u_0 = −β); 0: off (schemes admissible by construction)


def build(time_config, scheme) -> Control:
    """The loop's ``Control`` for a ``TimeConfig`` and the scheme built from it."""
    tc = time_config
    gap = registry.entry_of(type(scheme)).gap_control
    return Control(
        dt_max=float(tc.dt_max) if tc.dt_max is not None else math.inf,
        dt_min=float(tc.dt_min),
        dt_fixed=float(tc.dt) if tc.dt is not None else 0.0,
        growth=GROWTH,
        gap=min(float(tc.cfl), GAP_MAX) if gap else 0.0,
    )


def output_tolerance(spans) -> float:
    """The time below which two output times coincide, from the positive output intervals
    and the remaining run (``spans``)."""
    return OUTPUT_TOL * min(spans)


@step_kernel
def propose(ctrl, dt_suggest, dt_prev):
    """Next step: the scheme's suggestion, capped by dt_max and by growth over the
    previous proposal (so a step that just recovered from a rejection grows gently)."""
    if ctrl.dt_fixed > 0.0:
        return ctrl.dt_fixed
    return min(dt_suggest, ctrl.dt_max, ctrl.growth * dt_prev)


@step_kernel
def gap_limit(ctrl, dt, g_old, g_new):
    """Largest next step that closes at most ``ctrl.gap`` of the gap ``g_new`` to a barrier,
    at the closing rate of the last step (no limit while the gap opens)."""
    if g_new >= g_old:
        return np.inf
    return ctrl.gap * g_new * dt / (g_old - g_new)


@step_kernel
def gap_keep(ctrl):
    """The fraction of a barrier gap a step must leave open, else it is rejected."""
    return 1.0 - min(GAP_REJECT * ctrl.gap, GAP_CLOSE_MAX)


@step_kernel
def step_to(fixed, rem, dtp):
    """The step toward an output time ``rem`` ahead with proposal ``dtp``: ``(dt, land)``,
    land when the step ends on the output time."""
    if fixed:
        if rem <= dtp * (1.0 + LAND_FIXED):
            return rem, True
        return dtp, False
    if rem <= dtp * (1.0 + LAND_ADAPTIVE):
        return rem, True
    if rem < SPLIT_BELOW * dtp:
        return 0.5 * rem, False
    return dtp, False


@step_kernel
def retry(inaccurate, dt_suggest, dt):
    """The step to retry after a rejected trial of ``dt``: the scheme's ``dt_suggest`` when
    it rejected the trial for accuracy, else REJECT_SHRINK × dt."""
    return dt_suggest if inaccurate else REJECT_SHRINK * dt
