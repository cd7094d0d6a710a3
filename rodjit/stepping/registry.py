"""The integrators ``time.integrator`` may name: one line per scheme, nothing compiled.

Each ``Scheme`` says where its compiled ``initial``/``step`` live (a dotted module path,
imported only when a run uses the scheme), the NamedTuple class of its parameters in that
module, how the parameters are built from a ``TimeConfig``, the counters its step keeps in
``sstats``, the rows of scratch space it needs, whether the loop limits how fast its
steps approach the barriers, and whether it has a dense output (a continuous extension the
loop evaluates at the output times inside a step instead of landing on them).  ``config`` takes the allowed names from here, so adding an
integrator is one new module plus one line in ``SCHEMES``.

This module imports no Numba code: ``config`` imports it to validate names.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any, Callable

from . import workspace

__all__ = ["Scheme", "SCHEMES", "NAMES", "SCHEME_STATS", "get", "entry_of", "load",
           "make_scheme", "counter_index"]


@dataclass(frozen=True)
class Scheme:
    """One integrator.

    ``build(time_config, params)`` returns an instance of the class ``params``.
    ``counters`` name the entries of ``sstats`` the step increments (see ``SCHEME_STATS``).
    ``gap_control``: explicit schemes need the loop's barrier-gap limit; a scheme that is
    admissible by construction turns it off.
    ``step_rules`` names the loop's step-size rules for the scheme (``control.RULES``).
    ``dense``: the scheme's module also provides ``dense_setup`` and ``dense`` (its
    continuous extension, see ``schemes``); with ``output.interpolate`` on and adaptive
    steps the loop then steps toward ``time.t_end`` only and interpolates every output
    time inside a step (``loop.advance``).
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


def _kdk(tc, P):
    """Kick–drift–kick parameters: cfl, tolerances, and whether the tolerances choose (not
    under fixed steps, ``time.dt``: the step then skips the error estimate)."""
    return P(float(tc.cfl), float(tc.rtol), float(tc.atol),
             tc.control == "tolerance" and tc.dt is None)


_ENERGY_WORK_ROWS = 17   # rows S … D of stepping/energy.py (tests check it)

SCHEMES: tuple[Scheme, ...] = (
    Scheme("verlet", "rodjit.stepping.kdk", "Verlet", _kdk, workspace.WORK_ROWS),
    Scheme("semi-implicit", "rodjit.stepping.kdk", "SemiImplicit", _kdk, workspace.WORK_ROWS),
    Scheme("energy", "rodjit.stepping.energy", "Energy",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), _ENERGY_WORK_ROWS,
           counters=("newton_iterations", "newton_failures"), gap_control=False),
    Scheme("dp54", "rodjit.stepping.erk", "DP54",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 16, gap_control=False,
           step_rules="pair-dp54", dense=True),
    Scheme("dop853", "rodjit.stepping.erk", "DOP853",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 40, gap_control=False,
           step_rules="pair-dop853", dense=True),
    Scheme("radau5", "rodjit.stepping.radau", "Radau5",
           lambda tc, P: P(float(tc.rtol), float(tc.atol)), 50,
           counters=("newton_iterations", "newton_failures"), gap_control=False,
           dense=True),
)

NAMES: tuple[str, ...] = tuple(s.name for s in SCHEMES)

# The names of the int64 ``sstats`` array, in order: every scheme's counters, each name
# once.  Every run carries the whole array (a scheme leaves the others' entries at 0), so
# ``Result.stats`` and the run file's checkpoint have the same layout whatever the scheme.
SCHEME_STATS: tuple[str, ...] = tuple(dict.fromkeys(c for s in SCHEMES for c in s.counters))


def counter_index(name: str) -> int:
    """Position of a counter in ``sstats`` (a compile-time constant for the scheme's step)."""
    return SCHEME_STATS.index(name)


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
