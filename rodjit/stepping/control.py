"""Step-size control: every constant and rule that sets the length of a step.

The scheme suggests the next step (``StepResult.dt_suggest``: cfl × its stability limit, or
the step its error ratio allows); the rules here cap it (``dt_max``, growth per step, the
approach to the barriers), cut it to land on the output times, shrink it after a rejected
trial, and end it on a floor crossing.  ``build`` makes the loop's ``Control`` from a
``TimeConfig``; the compiled loop (``loop.advance``) calls the kernels below.

The rules are per scheme (``registry.Scheme.step_rules`` names a set in ``RULES``): the
second-order schemes grow their steps gently and split a short remainder before an output
time in two; the embedded pairs follow Hairer's controller for explicit Runge–Kutta codes
(growth up to ``PAIR_GROWTH`` per step, none right after a rejection) and stretch a step by
up to ``PAIR_STRETCH`` to land on an output time in one step.

A scheme with a dense output (``registry.Scheme.dense``: ``dp54``, ``dop853``) does not land
on the output times at all under adaptive steps with ``output.interpolate`` on
(``Control.dense``): its steps aim at ``time.t_end`` only (the rules above then land on it)
and the loop evaluates the scheme's continuous extension at the output times inside each
step.  Fixed steps (``time.dt``, which divides every output interval) keep landing.  Every
output of a step is written in the compiled call that takes it (the step's stages live only
until the next step), so a step covers at most ``Control.dense_snapshots`` snapshot and
``Control.dense_diagnostics`` diagnostics times (one that would cover more ends on the last
of them) and the driver's buffers hold at least that many rows: a rule of the run's
configuration, never of how full the buffers are, so the steps stay the same however the
run is cut into calls.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..kernels.forces import OK
from ..kernels.rates import full_accel, jerk
from . import registry
from .step_result import StepResult
from .._jit import kernel, step_kernel

__all__ = ["Control", "Rules", "RULES", "build", "output_tolerance", "propose", "gap_limit", "step_to",
           "gap_keep", "GROWTH", "GAP_MAX", "REJECT_SHRINK", "EVENT_MIN", "OUTPUT_TOL",
           "LAND_FIXED", "LAND_ADAPTIVE", "SPLIT_BELOW", "GAP_REJECT", "GAP_CLOSE_MAX", "retry",
           "STABILITY_CFL", "PAIR_GROWTH", "PAIR_STRETCH", "DENSE_OUTPUTS_MAX", "step_factor",
           "taylor_start", "height_scale", "velocity_scale",
           "VELOCITY_SCALE", "ERROR_TIME", "UNIT_STEP_MAX", "per_unit_step", "unit_step_factor",
           "SAFETY", "FAC_MIN", "FAC_MAX", "ERR_FAC_MAX", "ERR_FAC_MIN"]

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

# The embedded pairs: their error estimate follows the step to a high power (err ∝ dt^(q+1),
# q = 4 or 7), so a proposal may grow by up to this factor per step, the limits of Hairer's
# codes DOPRI5 (10) and DOP853 (6) (a gentle 1.5 costs such a scheme many steps after every
# step cut short by a floor crossing or an output time; DOP853 at 10 loses accuracy at
# tight tolerances through the bounces).  The limit is on the growth over the previous
# proposal, not over the step taken: a step cut short to land says nothing against the
# proposal it was cut from.
PAIR_GROWTH = {"dp54": 10.0, "dop853": 6.0}
# A pair's step is stretched by up to this fraction to land on an output time in one step
# instead of two.  Its proposal aims at an error 0.9^(q+1) ≈ 0.43–0.59 of the tolerance, so
# a 10 % longer step (error × 1.1^(q+1) ≈ 1.6–2.1) still passes.
PAIR_STRETCH = 0.1
# A dense-output step covers at most this many output times of each grid (snapshots: fewer
# where the snapshot buffer's memory rule allows fewer rows); one that would cover more ends
# on the last of them.  Far above the outputs per step of any run that is not dominated by
# its output: it only bounds the buffers (the driver allocates at least this many rows).
DENSE_OUTPUTS_MAX = 256

# Under tolerance control (time.control = "tolerance") an explicit scheme's step is the one
# its error estimate allows, capped at this fraction of its stability limit 2/ω (a bound
# from Gershgorin, itself above the true ω): accuracy decides, stability only caps.
STABILITY_CFL = 0.5


class Rules(NamedTuple):
    """A scheme's step-size rules (``RULES``)."""

    growth: float         # a proposal grows at most by this factor per step
    growth_reject: float  # ... and by this factor in the step after a rejected trial
    land: float           # a step within this relative distance of an output time ends on it
    split: float          # a remainder shorter than this many proposals is taken in two
                          # equal steps (after ``land`` did not apply)


RULES = {
    # verlet, semi-implicit, energy: second order, growth-limited after every cut
    "second-order": Rules(growth=GROWTH, growth_reject=GROWTH, land=LAND_ADAPTIVE,
                          split=SPLIT_BELOW),
    # dp54, dop853: Hairer's limits (no growth in the step after a rejection)
    **{f"pair-{name}": Rules(growth=g, growth_reject=1.0, land=PAIR_STRETCH, split=SPLIT_BELOW)
       for name, g in PAIR_GROWTH.items()},
}


class Control(NamedTuple):
    """Step-size control: caps, fixed step (0: adaptive), the scheme's ``Rules`` and the
    barrier-gap limit."""

    dt_max: float     # inf when unset
    dt_min: float
    dt_fixed: float   # > 0: fixed steps
    growth: float     # a proposal grows at most by this factor per step
    growth_reject: float   # ... and by this factor right after a rejected trial
    land: float       # adaptive steps: land on an output time within this relative distance
    split: float      # adaptive steps: a remainder below split × proposal: two equal steps
    gap: float        # a step closes at most this fraction of the distance to a barrier
                      # (ε = −1, u_0 = −β); 0: off (schemes admissible by construction)
    dense: bool = False   # steps aim at t_end only; outputs inside a step are interpolated
    dense_snapshots: int = 0     # ... and a step covers at most this many snapshot times
    dense_diagnostics: int = 0   # ... and diagnostics times (0 when not dense)
    stop_bounces: int = 0        # > 0: the run ends once this many bounces are over
    rest_energy: float = -math.inf   # the run ends in contact with its energy below this


def build(time_config, scheme, interpolate: bool = True,
          snapshot_rows: int = DENSE_OUTPUTS_MAX, rest_energy: float = -math.inf) -> Control:
    """The loop's ``Control`` for a ``TimeConfig`` and the scheme built from it;
    ``interpolate`` (``output.interpolate``): output by the scheme's dense output where it
    has one and the steps are adaptive; ``snapshot_rows``: the most snapshot rows a buffer
    of the run may hold (the driver's memory rule), which bounds ``dense_snapshots``;
    ``rest_energy``: with ``time.stop_at_rest``, the lift-off energy below which the rod
    never leaves the floor again (``records.physics.lift_energy``)."""
    tc = time_config
    entry = registry.entry_of(type(scheme))
    dense = bool(interpolate and entry.dense and tc.dt is None)
    rules = RULES[entry.step_rules]
    return Control(
        dt_max=float(tc.dt_max) if tc.dt_max is not None else math.inf,
        dt_min=float(tc.dt_min),
        dt_fixed=float(tc.dt) if tc.dt is not None else 0.0,
        growth=rules.growth,
        growth_reject=rules.growth_reject,
        land=rules.land,
        split=rules.split,
        gap=min(float(tc.cfl), GAP_MAX) if entry.gap_control else 0.0,
        dense=dense,
        dense_snapshots=max(1, min(DENSE_OUTPUTS_MAX, int(snapshot_rows))) if dense else 0,
        dense_diagnostics=DENSE_OUTPUTS_MAX if dense else 0,
        stop_bounces=int(tc.stop_after_bounces),
        rest_energy=float(rest_energy) if tc.stop_at_rest else -math.inf,
    )


def output_tolerance(spans) -> float:
    """The time below which two output times coincide, from the positive output intervals
    and the remaining run (``spans``)."""
    return OUTPUT_TOL * min(spans)


@step_kernel
def propose(ctrl, dt_suggest, dt_prev, after_reject=False):
    """Next step: the scheme's suggestion, capped by dt_max and by growth over the
    previous proposal (so a step that just recovered from a rejection grows gently)."""
    if ctrl.dt_fixed > 0.0:
        return ctrl.dt_fixed
    growth = ctrl.growth_reject if after_reject else ctrl.growth
    return min(dt_suggest, ctrl.dt_max, growth * dt_prev)


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
def step_to(ctrl, fixed, rem, dtp):
    """The step toward an output time ``rem`` ahead with proposal ``dtp``: ``(dt, land)``,
    land when the step ends on the output time."""
    if fixed:
        if rem <= dtp * (1.0 + LAND_FIXED):
            return rem, True
        return dtp, False
    if rem <= dtp * (1.0 + ctrl.land):
        return rem, True
    if rem < ctrl.split * dtp:
        return 0.5 * rem, False
    return dtp, False


@step_kernel
def retry(inaccurate, dt_suggest, dt):
    """The step to retry after a rejected trial of ``dt``: the scheme's ``dt_suggest`` when
    it rejected the trial for accuracy, else REJECT_SHRINK × dt."""
    return dt_suggest if inaccurate else REJECT_SHRINK * dt


# The error norm of every adaptive integrator (docs/integrators.md, "What the tolerances
# mean"): the largest over the components a scheme estimates of |e_k| / scale_k, where
#   heights:    scale = atol + rtol·max(|u_k|, |u_k⁺|)                   (atol in m)
#   velocities: scale = atol·VELOCITY_SCALE + rtol·max(|v_k|, |v_k⁺|)    (m/s)
# A max, not a root mean square: each component's estimated local error stays within its
# own tolerance, so the bottom node in contact (where the error concentrates) is not
# averaged with N quiet nodes.  VELOCITY_SCALE = 1/s: a velocity error of atol m/s moves a
# height by atol within 1 s, the time scale of a bounce of the 1 m rod (a 1 m drop takes
# 0.45 s; MODEL.md "Units"), so heights and velocities are held to comparable accuracy.
VELOCITY_SCALE = 1.0


@step_kernel
def height_scale(scheme, y, y2):
    """The scale of a height's error between y and y2 (``scheme.atol``, ``scheme.rtol``)."""
    return scheme.atol + scheme.rtol * max(abs(y), abs(y2))


@step_kernel
def velocity_scale(scheme, y, y2):
    """The scale of a velocity's error between y and y2."""
    return scheme.atol * VELOCITY_SCALE + scheme.rtol * max(abs(y), abs(y2))


# The second-order schemes (``kdk``, ``energy``) control the error per unit step: their
# local error estimate, in the norm above, must stay below dt/ERROR_TIME of the tolerance.
# A local error of O(dt³) controlled per step leaves a global error O(dt²) ∝ tol^(2/3),
# which outgrows the tolerance as it tightens (verlet on paper-mu0: 1.8×, 5.6× and 20× tol
# at tol 1e-3, 1e-5, 1e-7); per unit step the steps go as tol^(1/2) and the global error as
# tol.  ERROR_TIME = 1 ms, the time scale on which an impact changes (the paper presets'
# contacts last about 4 ms); it sets the constant: verlet's first restitution on paper-mu0
# is then about the tolerance with an estimate of the heights alone, 0.1–0.25 × tol with
# the heights' and velocities' (at 1 s it was 1.3e-3 × tol, with 30× the steps).  Below
# ERROR_TIME/UNIT_STEP_MAX (the short steps that end on a floor crossing) the factor
# stops growing: a step's estimate has a floor of rounding and of the Newton solve, which
# dt/ERROR_TIME would otherwise magnify without bound.
ERROR_TIME = 1e-3
UNIT_STEP_MAX = 1e3


@step_kernel
def per_unit_step(err, dt):
    """A second-order scheme's error ratio per unit step: ``err`` · ERROR_TIME / dt (at
    most ``err`` · UNIT_STEP_MAX)."""
    return err * min(ERROR_TIME / dt, UNIT_STEP_MAX)


@step_kernel
def unit_step_factor(r):
    """The next step over this one for a ratio ``r`` per unit step (∝ dt²):
    SAFETY·r^(−1/2) in [FAC_MIN, FAC_MAX] (``step_factor`` of r^(3/2))."""
    return step_factor(r * math.sqrt(r))


# The step factor of the second-order schemes (``kdk``, ``energy``): their local error is
# O(dt³), so the next step over this one is SAFETY·err^(−1/3), in [FAC_MIN, FAC_MAX].
SAFETY = 0.9
FAC_MIN = 0.2
FAC_MAX = 5.0
# the range of errors where the step factor SAFETY·err^(−1/3) is not clamped
ERR_FAC_MAX = (SAFETY / FAC_MAX) ** 3
ERR_FAC_MIN = (SAFETY / FAC_MIN) ** 3


@step_kernel
def step_factor(err):
    """SAFETY·err^(−1/3) in [FAC_MIN, FAC_MAX] (the next step over this one).

    err^(−1/3) by Newton's iteration y ← y(4 − x y³)/3 on x = err·8^k ∈ [1, 8), from the
    least-squares quadratic of x^(−1/3) on [1, 8] (7 % off at worst): three iterations
    leave < 1e-7 relative, far below what a step-size heuristic needs, and cost less than
    a libm cbrt call.  Plain arithmetic: the same bits everywhere."""
    if not err > ERR_FAC_MAX:      # also err = 0
        return FAC_MAX
    if err >= ERR_FAC_MIN:
        return FAC_MIN
    x = err
    scale = 1.0
    while x < 1.0:
        x *= 8.0
        scale *= 2.0
    while x >= 8.0:
        x *= 0.125
        scale *= 0.5
    y = 1.07144173 + x * (-0.15170626 + x * 0.01044221)
    for _ in range(3):
        y = y * (4.0 - x * y * y * y) * (1.0 / 3.0)
    return min(FAC_MAX, max(FAC_MIN, SAFETY * scale * y))


@step_kernel
def _error_rate(scheme, u, ad):
    """max_i |ȧ_i|/12 / (atol + rtol|u_i|): the predicted u error per dt³."""
    r = 0.0
    for i in range(u.size):
        r = max(r, abs(ad[i]) / (12.0 * (scheme.atol + scheme.rtol * abs(u[i]))))
    return r


@kernel
def taylor_start(scheme, system, rod, floor, u, v, a, s, k, ad, strains):
    """Full acceleration of the initial state and the first step of an implicit scheme
    (``energy``, ``radau5``): the step whose Taylor error dt³|ȧ|/12 is half the tolerance
    (``scheme.rtol``, ``scheme.atol``), at most the explicit limit 2/ω (the controller
    grows it from there).  ``s``, ``k``, ``ad``, ``strains``: scratch rows."""
    status, val, emin, fl, om2 = full_accel(system, rod, floor, u, v, a, s, k, bool(True))
    if status != OK:
        return StepResult(status, val, emin, fl, 0.0, 0.0, 0.0)
    jerk(system, rod, floor, u, v, a, ad, k, strains)
    dt = 2.0 / math.sqrt(om2) if om2 > 0.0 else np.inf
    rate = _error_rate(scheme, u, ad)
    if rate > 0.0:
        dt = min(dt, 0.5 / np.cbrt(rate))
    return StepResult(OK, 0.0, emin, fl, dt, 0.0, 0.0)
