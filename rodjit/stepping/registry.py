"""The integrators ``time.integrator`` may name: one line per scheme, nothing compiled.

Each ``Scheme`` says where its compiled ``initial``/``step`` live (a dotted module path,
imported only when a run uses the scheme), the NamedTuple class of its parameters in that
module, how the parameters are built from a ``TimeConfig``, the counters its step keeps in
``sstats``, the rows of scratch space it needs, whether the loop limits how fast its
steps approach the barriers, and whether it has a dense output (a continuous extension the
loop evaluates at the output times inside a step instead of landing on them).  It also
holds the facts a study needs about the scheme's steps: its order, which configuration
keys set its steps under each ``time.control`` (``step_keys``), what caps them and which
keys scale that cap, and the error norm its tolerance is measured in.  ``config`` takes
the allowed names from here, so adding an integrator is one new module plus one line in
``SCHEMES``; ``analysis.converge`` takes the time ladder's key from here.

This module imports no Numba code: ``config`` imports it to validate names.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable

from . import workspace

__all__ = ["Scheme", "SCHEMES", "NAMES", "SCHEME_STATS", "TIME_KEYS", "get", "entry_of",
           "VISCOUS_STEPS_MAX", "AUTO", "AUTO_TABLE", "AUTO_SPAN", "AUTO_RTOL_MIN", "Choice", "choose",
           "load", "make_scheme", "counter_index", "register"]

# An explicit scheme capped by the viscous stiffness above this many steps per simulated
# second is refused (``Scheme.viscous_steps``): dop853 at μ = 100, N = 200 would take 3.5e6
# steps and 156 s of compiled loop per simulated second where radau5 takes about 1,400
# steps (0.05 s)
VISCOUS_STEPS_MAX = 1e6

# the configuration keys that can set the length of a step
TIME_KEYS = ("time.rtol", "time.atol", "time.cfl", "time.dt")


@dataclass(frozen=True)
class Scheme:
    """One integrator.

    ``build(time_config, params)`` returns an instance of the class ``params``.
    ``counters`` name the entries of ``sstats`` the step increments (see ``SCHEME_STATS``).
    ``gap_control``: explicit schemes need the loop's barrier-gap limit; a scheme that is
    admissible by construction turns it off.
    ``viscous_steps``: an explicit scheme whose steps the viscous stability cap sets takes
    about ``viscous_steps``·μN² steps per simulated second under tolerance control
    (measured: the count is that multiple to three digits at μ = 100…1000, N = 20…200); a
    run that would take more than ``VISCOUS_STEPS_MAX`` of them is refused
    (``Config.check_runnable``).  0: the scheme has no such cap.
    ``step_rules`` names the loop's step-size rules for the scheme (``control.RULES``).
    ``dense``: the scheme's module also provides ``dense_setup`` and ``dense`` (its
    continuous extension, see ``schemes``); with ``output.interpolate`` on and adaptive
    steps the loop then steps toward ``time.t_end`` only and interpolates every output
    time inside a step (``loop.advance``).
    ``aot``: the install compiles the scheme's loop ahead of time for the default run's
    other types (``stepping.aot``), so that a run of it compiles nothing.
    """

    name: str
    module: str
    params: str
    build: Callable[[Any, type], Any]
    work_rows: int
    counters: tuple[str, ...] = ()
    gap_control: bool = True
    step_rules: str = "second-order"
    dense: bool = False
    order: int = 2
    cfl_control: bool = False
    cap: str = ""
    cap_keys: tuple[str, ...] = ()
    error_norm: str = ""
    viscous_mu_max: float = float("inf")
    viscous_steps: float = 0.0
    aot: bool = False

    def step_keys(self, control: str, fixed: bool = False) -> tuple[str, ...]:
        """The configuration keys that set the steps under ``time.control = control``
        (``fixed``: ``time.dt`` is set, which fixes the steps of every scheme)."""
        if fixed:
            return ("time.dt",)
        if control == "cfl" and self.cfl_control:
            return ("time.cfl",)
        return ("time.rtol", "time.atol")

    def steps_of(self, time_config) -> tuple[str, ...]:
        """``step_keys`` of a ``TimeConfig``."""
        return self.step_keys(time_config.control, time_config.dt is not None)


def _kdk(tc, P):
    """Kick–drift–kick parameters: cfl, tolerances, and whether the tolerances choose (not
    under fixed steps, ``time.dt``: the step then skips the error estimate)."""
    return P(float(tc.cfl), float(tc.rtol), float(tc.atol),
             tc.control == "tolerance" and tc.dt is None)


_ENERGY_WORK_ROWS = 17   # rows S … D of stepping/energy.py (tests check it)

# the one error norm (control.height_scale, velocity_scale; docs/integrators.md): each
# scheme's module docstring derives the estimate it measures in it
_NORM = ("max over the estimated components of |e| / (atol + rtol·max(|y|, |y⁺|)), atol in m "
         "for heights and atol·control.VELOCITY_SCALE (1/s) in m/s for velocities")
_KDK_NORM = _NORM + ("; estimated: heights |dt²/6·(a⁺ − a)| and velocities "
                     "|dt/6·(a⁺ − a − dt·ȧ)| (kick acceleration a, its jerk ȧ at the start)")
_ENERGY_NORM = _NORM + "; estimated: heights and velocities (predictor–corrector)"
_PAIR_NORM = _NORM + "; estimated: heights and velocities (embedded pair)"
_RADAU_NORM = _NORM + "; estimated: heights and velocities (Hairer's filtered estimate)"
_KDK_CAP = ("control.STABILITY_CFL × the stability limit 2/ω under tolerance control; the "
            "barrier approach: at most time.cfl (≤ control.GAP_MAX) of the gap per step")

SCHEMES: tuple[Scheme, ...] = (
    # verlet's Crank–Nicolson viscous sub-step is split off the kicks: measured 2.8e-4 on
    # the first-bounce restitution at μ = 100 (N = 5) at every rtol, 1e-5 at μ = 1
    Scheme("verlet", "rodjit.stepping.integrators.kdk", "Verlet", _kdk,
           workspace.WORK_ROWS,
           order=2, cfl_control=True, error_norm=_KDK_NORM, cap_keys=("time.cfl",),
           viscous_mu_max=1.0,
           cap=_KDK_CAP + "; the viscous sub-step's limit time.cfl·h²/(2μ) (μ > 0)"),
    Scheme("semi-implicit", "rodjit.stepping.integrators.kdk", "SemiImplicit", _kdk,
           workspace.WORK_ROWS,
           order=2, cfl_control=True, error_norm=_KDK_NORM, cap_keys=("time.cfl",),
           cap=_KDK_CAP),
    Scheme("energy", "rodjit.stepping.integrators.energy", "Energy",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), _ENERGY_WORK_ROWS,
           counters=("newton_iterations", "newton_failures"), gap_control=False,
           order=2, error_norm=_ENERGY_NORM),
    Scheme("dp54", "rodjit.stepping.integrators.erk", "DP54",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 16, gap_control=False,
           step_rules="pair-dp54", dense=True, order=5, error_norm=_PAIR_NORM,
           viscous_steps=1.36,
           cap="erk.STABILITY_CAP / ω and erk.VISCOUS_CAP·h²/(4μ) (constants of the pair; they bind in contact and at large μ)"),
    Scheme("dop853", "rodjit.stepping.integrators.erk", "DOP853",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 40, gap_control=False,
           step_rules="pair-dop853", dense=True, order=8, error_norm=_PAIR_NORM,
           viscous_steps=0.88, aot=True,
           cap="erk.STABILITY_CAP / ω and erk.VISCOUS_CAP·h²/(4μ) (constants of the pair; they bind in contact and at large μ)"),
    Scheme("radau5", "rodjit.stepping.integrators.radau", "Radau5",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 50,
           counters=("newton_iterations", "newton_failures"), gap_control=False,
           dense=True, order=5, error_norm=_RADAU_NORM, aot=True),
)

NAMES: tuple[str, ...] = tuple(s.name for s in SCHEMES)

# The names of the int64 ``sstats`` array, in order: every scheme's counters, each name
# once.  Every run carries the whole array (a scheme leaves the others' entries at 0), so
# ``Result.stats`` and the run file's checkpoint have the same layout whatever the scheme.
SCHEME_STATS: tuple[str, ...] = tuple(dict.fromkeys(c for s in SCHEMES for c in s.counters))


def counter_index(name: str) -> int:
    """Position of a counter in ``sstats`` (a compile-time constant for the scheme's step)."""
    return SCHEME_STATS.index(name)


def register(scheme: Scheme) -> Scheme:
    """Make ``scheme`` selectable as ``time.integrator``, as ``rodjit.laws.register`` makes
    a law selectable: from a module of one's own, with no line added here.

    Its ``module`` (imported on first use) provides ``initial`` and ``step`` (``schemes``)
    and the parameter class ``params``; the registry's facts (``step_keys``, ``cap_keys``,
    ``order``, ``error_norm``) then tell ``converge`` how to study it.  Its parameter class
    is renamed into ``registered`` (so a process without the module finds only a cache
    miss in the compiled-code cache, not an import error).  Its ``counters``
    must be among ``SCHEME_STATS`` (the compiled steps index ``sstats`` by constants, and
    the run file names its entries): a new counter is a line of this module.

    Returns
    -------
    Scheme
        ``scheme``.

    Raises
    ------
    TypeError
        ``scheme`` is not a ``Scheme``.
    ValueError
        Its name is taken, or a counter is not among ``SCHEME_STATS``.
    """
    global SCHEMES, NAMES
    if not isinstance(scheme, Scheme):
        raise TypeError(f"register takes a registry.Scheme, not {type(scheme).__name__}")
    if scheme.name in NAMES:
        raise ValueError(f"time.integrator = {scheme.name!r} is already registered")
    unknown = [c for c in scheme.counters if c not in SCHEME_STATS]
    if unknown:
        raise ValueError(f"scheme {scheme.name!r}: counters {unknown} are not among "
                         f"{list(SCHEME_STATS)}")
    module, params = load(scheme)      # imports the scheme's module (nothing compiled)
    from . import registered           # how the compiled-code cache names its type
    registered.adopt(params, scheme.name,
                     (getattr(module, "initial", None), getattr(module, "step", None)))
    SCHEMES = SCHEMES + (scheme,)
    NAMES = NAMES + (scheme.name,)
    return scheme


def get(name: str) -> Scheme:
    for s in SCHEMES:
        if s.name == name:
            return s
    raise ValueError(f"time.integrator = {name!r} is not available; choose one of "
                     f"{sorted(NAMES)}")


_LOADED: dict[type, Scheme] = {}
# ``load``'s answer by module and class name: every run asks, and the import machinery's
# lookup of a module already imported costs more than the rest of building the scheme
_MODULES: dict[tuple[str, str], tuple] = {}


def load(scheme: Scheme):
    """``(module, parameter class)`` of a scheme, importing its module on first use."""
    k = (scheme.module, scheme.params)
    found = _MODULES.get(k)
    if found is None:
        module = importlib.import_module(scheme.module)
        params = getattr(module, scheme.params)
        _LOADED.setdefault(params, scheme)
        found = _MODULES[k] = (module, params)
    return found


def entry_of(params_type: type) -> Scheme:
    """The registry entry whose parameter class is ``params_type`` (a loaded scheme)."""
    if params_type not in _LOADED:
        for s in SCHEMES:
            load(s)
    try:
        return _LOADED[params_type]
    except KeyError:
        raise TypeError(f"{params_type} is not the parameter type of a registered "
                        f"integrator") from None


def make_scheme(time_config):
    """The scheme parameters for a ``TimeConfig`` (its module is imported here)."""
    entry = get(time_config.integrator)
    _, params = load(entry)
    return entry.build(time_config, params)


# ---- time.integrator = "auto" ---------------------------------------------------------
AUTO = "auto"

# A conservative rod (μ = γ = 0) keeps its energy only as well as its steps do: the drift
# of a local tolerance grows with the run (dop853 at rtol 1e-6 drifts 3.2e-4 of the energy
# over 200 s of the default run), so ``auto`` divides the tolerances by the run's length in
# units of AUTO_SPAN (at 200 s: 5e-9, drift 4e-7; benchmarks/energy_drift.py).
AUTO_SPAN = 1.0          # s: about one bounce period of the paper's drop from 1 m
AUTO_RTOL_MIN = 1e-12    # not below: the pairs' error estimates drown in round-off there


@dataclass(frozen=True)
class Choice:
    """One row of the table ``time.integrator = "auto"`` reads (``AUTO_TABLE``): the
    integrator it picks in a regime, and the measurement that justifies the row."""

    when: str                                       # the regime, in configuration keys
    integrator: str
    evidence: str                                   # the benchmark that measured it
    test: Callable[[float, float, int], bool]       # (rod.mu, rod.gamma, rod.N)


AUTO_TABLE: tuple[Choice, ...] = (
    Choice("rod.mu = 0 and rod.gamma = 0", "dop853",
           "work_precision.py: the explicit pairs are fastest at every N and floor measured "
           "(dop853, or dp54 within 1.2–1.7× of it)",
           lambda mu, gamma, n: mu == 0.0 and gamma == 0.0),
    Choice("rod.mu ≤ 1, rod.gamma = 0 and rod.N ≤ 5", "dop853",
           "work_precision.py: at μ = 1, N = 5 the pairs beat radau5 (within 1.0–1.4× of "
           "each other)",
           lambda mu, gamma, n: mu <= 1.0 and gamma == 0.0 and n <= 5),
    Choice("the other rods (rod.mu > 0 or rod.gamma > 0)", "radau5",
           "work_precision.py: radau5 is fastest at μ = 1 (N ≥ 20) and μ = 100 at every N "
           "and floor (the runner-up 1.4–33× dearer); the pairs' steps are capped by the "
           "viscous and γ/h⁴ stiffness",
           lambda mu, gamma, n: True),
)


def choose(mu: float, gamma: float, n: int, t_end: float, rtol: float,
           atol: float) -> tuple[str, float, float, str]:
    """What ``time.integrator = "auto"`` runs: ``(integrator, rtol, atol, why)``.

    The first row of ``AUTO_TABLE`` whose regime holds picks the integrator; on a
    conservative rod (μ = γ = 0) the tolerances are divided by ``t_end / AUTO_SPAN``
    when the run is longer than that (not below ``AUTO_RTOL_MIN``), so the energy's drift
    stays bounded over long runs.
    ``why`` is one line for the summary and the file.
    """
    row = next(c for c in AUTO_TABLE if c.test(mu, gamma, n))
    why = f"chosen by 'auto' for {row.when}"
    if mu == 0.0 and gamma == 0.0 and t_end > AUTO_SPAN:
        factor = min(t_end / AUTO_SPAN, max(1.0, rtol / AUTO_RTOL_MIN))
        rtol, atol = rtol / factor, atol / factor
        why += f"; tolerances / {factor:.3g} to hold the energy over {t_end:g} s"
    return row.integrator, rtol, atol, why
