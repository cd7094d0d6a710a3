"""What a configuration checks beyond each key's own type and range, and what it warns
about: keys whose allowed values depend on each other, law names (looked up in the
registry), configurations a run refuses, and the known limits of the model.
"""
from __future__ import annotations

import math
from typing import Any, Callable

from ..model.system import start_velocity
from ..stepping.registry import AUTO, VISCOUS_STEPS_MAX, get as registry_get
from .errors import ConfigError
from .sections import check_dt_range

__all__ = ["CROSS_CHECKS", "RUN_CHECKS", "SHOCK_WARNING", "VERLET_MU_MAX", "VERLET_WARNING",
           "viscous_warning", "model_warnings", "setup_warnings", "times_warnings",
           "ROD_LENGTH"]

# The texts of ``Config.warnings`` (tests and the convergence tool use them too).
SHOCK_WARNING = (
    "rod.mu = 0 and rod.gamma = 0: compression waves steepen into shocks that this "
    "discretisation does not resolve, so first-bounce observables (restitution, contact "
    "time, penetration, strain) have no continuum limit as rod.N grows; energy and "
    "long-run statistics remain meaningful (set rod.gamma > 0 or rod.mu > 0 for a "
    "convergent first bounce)")
# verlet's Crank–Nicolson viscous sub-step is split off the kicks: above this μ its error
# is set by its viscous step cap, not by its tolerance (``registry.Scheme.viscous_mu_max``)
VERLET_MU_MAX: float = registry_get("verlet").viscous_mu_max


def viscous_warning(name: str, mu_max: float) -> str:
    """The warning for an integrator run above its ``viscous_mu_max``.

    Parameters
    ----------
    name : str
        The integrator.
    mu_max : float
        Its ``viscous_mu_max`` (the registry's).

    Returns
    -------
    str
        One sentence naming the keys.
    """
    return (f"time.integrator = {name!r} with rod.mu > {mu_max:g}: its viscous sub-step, "
            "split off the kicks, limits the step to mu*dt*4/h^2 <= 2*time.cfl (steps grow "
            "like mu*N^2) and still misses 1e-4 on first-bounce observables; use 'energy' "
            "or 'semi-implicit'")


VERLET_WARNING = viscous_warning("verlet", VERLET_MU_MAX)


def model_warnings(mu: float, gamma: float, integrator: str) -> tuple[str, ...]:
    """The known limitations of a configuration (``Config.warnings``): the shock-forming
    μ = γ = 0 model, an integrator above its ``viscous_mu_max``."""
    out = []
    if mu == 0 and gamma == 0:
        out.append(SHOCK_WARNING)
    entry = registry_get(integrator)
    if mu > entry.viscous_mu_max:
        out.append(viscous_warning(entry.name, entry.viscous_mu_max))
    return tuple(out)


ROD_LENGTH = 1.0     # the rod's natural length (nodes at x = i/N; docs/MODEL.md, "Units")


def setup_warnings(g: float, height: float, velocity: float, beta: float) -> tuple[str, ...]:
    """The set-ups that are valid but almost surely not what was meant
    (``Config.warnings``): a gravity that pulls the rod up (``gravity.g > 0``) so that its
    free flight from ``initial.height`` at ``initial.velocity`` never reaches the floor
    (a run without an impact: the sign of g is along +u, -9.81 pulls down); a floor
    whose bending limit ``floor.beta`` is no thin layer but at least the rod's length
    deep.  ``gravity.g = 0`` (a free rod, the verification runs) says nothing."""
    out = []
    comes_down = velocity < 0 and velocity * velocity >= 2.0 * g * height
    if g > 0 and height > 0 and not comes_down:
        out.append(f"gravity.g = {g!r} > 0 pulls the rod up, away from the floor (gravity.g "
                   f"is signed along +u: -9.81 pulls down): from initial.height = "
                   f"{height!r} at initial.velocity = {velocity!r} it never comes down, so "
                   f"the run has no impact")
    if beta >= ROD_LENGTH:
        out.append(f"floor.beta = {beta!r} puts the floor's bending limit (where its stress "
                   f"is infinite) {beta:g} below its surface, at least the rod's length "
                   f"{ROD_LENGTH:g}: the floor law models a thin bending layer (default "
                   f"0.05), not a floor softer than the rod is long")
    return tuple(out)


def times_warnings(times: tuple[float, ...], t_end: float) -> tuple[str, ...]:
    """Listed snapshot times (``output.times``) after ``time.t_end``: this run does not
    reach them (a run extended later, ``resume_file(..., t_end=...)``, does)."""
    late = [t for t in times if t > t_end]
    if not late:
        return ()
    return (f"output.times lists {len(late)} time{'s' if len(late) > 1 else ''} after "
            f"time.t_end = {t_end!r} (from {late[0]!r}): this run writes no snapshot "
            f"there, a run extended past them does",)


def _check_height(height: float, beta: float) -> None:
    if not height > -beta:
        raise ConfigError(
            f"initial.height = {height!r} is out of range (float > -floor.beta "
            f"= {-beta!r}: the bottom must start above the floor's bending limit)")


def _check_impact_speed(impact_speed: float | None, velocity: float, height: float,
                        g: float) -> None:
    if impact_speed is None:
        return
    if velocity != 0.0:
        raise ConfigError(
            f"initial.impact_speed = {impact_speed!r} sets the initial velocity: leave "
            f"initial.velocity unset (0), not {velocity!r}")
    if math.isnan(start_velocity(height, velocity, impact_speed, g)):
        least = math.sqrt(-2.0 * g * height)
        raise ConfigError(
            f"initial.impact_speed = {impact_speed!r} is out of range (>= {least:.6g} m/s, "
            f"the speed of a fall from rest from initial.height = {height!r}): lower "
            f"initial.height")


def _check_stop_at_rest(stop: bool, g: float) -> None:
    if stop and not g < 0:
        raise ConfigError(f"time.stop_at_rest needs gravity.g < 0 (a rod that falls back "
                          f"onto the floor can come to rest), not gravity.g = {g!r}")


def _law_check(kind: str) -> Callable[[str], None]:
    def check(name: str) -> None:
        from ..model.laws import get_law  # laws register themselves on import
        get_law(kind, name)      # a ValueError naming the registered laws
    return check


def _observer_check(name: str) -> None:
    from ..stepping.observers import get_observer   # a ValueError naming the registered
    get_observer(name)


# ``Config`` runs every check; a sweep grid checks each key's values once and these only
# over the combinations of the swept keys they name, not over every point.
CROSS_CHECKS: tuple[tuple[tuple[str, ...], Callable[..., None]], ...] = (
    (("rod.law",), _law_check("rod")),
    (("floor.law",), _law_check("floor")),
    (("initial.height", "floor.beta"), _check_height),
    (("initial.impact_speed", "initial.velocity", "initial.height", "gravity.g"),
     _check_impact_speed),
    (("time.stop_at_rest", "gravity.g"), _check_stop_at_rest),
    (("time.dt_min", "time.dt_max"), check_dt_range))


def _check_regime(integrator: str, control: str, dt: float | None, mu: float,
                  n: int) -> None:
    """An integrator under tolerance control outside the regime its registry row admits:
    one whose split viscous sub-step caps its step above ``viscous_mu_max`` (the cap, not
    the tolerance, then sets its error), or an explicit scheme whose viscous stability cap
    would take more than ``VISCOUS_STEPS_MAX`` steps per simulated second
    (``viscous_steps``).  "auto" chooses among the integrators that admit the rod."""
    if integrator == AUTO or dt is not None or control != "tolerance":
        return
    entry = registry_get(integrator)
    if mu > entry.viscous_mu_max:
        raise ConfigError(
            f"time.integrator = {integrator!r} cannot honour time.rtol/time.atol at "
            f"rod.mu = {mu:g} > {entry.viscous_mu_max:g}: its split viscous sub-step caps "
            f"the step at time.cfl*h^2/(2*mu), and that cap, not the tolerance, sets its "
            f"error; set time.control = 'cfl' and refine time.cfl, or use "
            f"time.integrator = 'semi-implicit' or 'energy'")
    steps = entry.viscous_steps * mu * n * n
    if steps > VISCOUS_STEPS_MAX:
        raise ConfigError(
            f"time.integrator = {integrator!r} is impractical at rod.mu = {mu:g}, rod.N = "
            f"{n} (rod.mu*rod.N^2 = {mu * n * n:.3g}): its viscous stability cap takes "
            f"about {steps:.2g} steps per simulated second (at most "
            f"{VISCOUS_STEPS_MAX:.0e}); use time.integrator = 'radau5' or 'auto'")


# What a run checks beyond ``CROSS_CHECKS`` before it steps (``Config.check_runnable``):
# configurations that are valid (a file may hold one) but that a run refuses.
RUN_CHECKS: tuple[tuple[tuple[str, ...], Callable[..., Any]], ...] = (
    (("time.integrator", "time.control", "time.dt", "rod.mu", "rod.N"), _check_regime),
    # a run needs its observer registered; a file that names one is read without it (its
    # values are in the file)
    (("output.observer",), _observer_check))
