"""Resolution and time ladders of a convergence study: their levels, the checks that a
ladder refines and that a time ladder varies what sets the integrator's steps (the
registry's facts, ``stepping.registry``), and the texts that say so."""
from __future__ import annotations

__all__ = ["levels", "check_ladder", "step_keys", "check_time_key",
           "same_steps", "steps_text", "cap_key", "cap_text", "default_time_ladder",
           "TIME_KEYS", "INVERSE_KEYS"]

# the resolution keys whose level is a mesh width (1/value); any other key's value is used
# as the level itself (time.rtol, time.dt, time.cfl: smaller is finer)
INVERSE_KEYS = ("rod.N",)


def levels(key: str, values) -> list[float]:
    return [1.0 / v for v in values] if key in INVERSE_KEYS else [float(v) for v in values]


def check_ladder(name: str, ladder, base) -> tuple[str, list]:
    if not isinstance(ladder, dict) or len(ladder) != 1:
        raise ValueError(f"{name} must be one key and its values, e.g. "
                         f"{{'rod.N': [25, 50, 100]}}, not {ladder!r}")
    from ..sweeps.grid import Grid

    grid = Grid.from_spec(ladder)      # lists, or text as on the command line
    key, values = grid.keys[0], list(grid.values[0])
    configs = [base.override({key: v}) for v in values]     # validates key and values
    values = [c.get(key) for c in configs]
    if len(values) < 2:
        raise ValueError(f"{name} {key}: at least two levels, three for an order")
    lv = levels(key, values)
    if any(b >= a for a, b in zip(lv, lv[1:])):
        raise ValueError(f"{name} {key}: the levels must refine monotonically "
                         f"({'increasing' if key in INVERSE_KEYS else 'decreasing'}), "
                         f"got {values}")
    return key, values


TIME_KEYS = ("time.rtol", "time.atol", "time.cfl", "time.dt")


def step_keys(base) -> tuple[str, ...]:
    """The keys that set the steps of the base config's integrator (the registry's
    ``Scheme.step_keys`` under its ``time.control`` and ``time.dt``)."""
    from ..stepping.registry import get

    return get(base.resolve().time.integrator).steps_of(base.time)


def check_time_key(name: str, key: str, base) -> None:
    """A ladder over a time key must vary what sets the integrator's steps."""
    if key not in TIME_KEYS or key == "time.dt":      # time.dt fixes every scheme's steps
        return
    keys = step_keys(base)
    if key in keys:
        return
    tc = base.resolve().time
    why = ("with the fixed step time.dt" if tc.dt is not None else
           f"under time.control = {tc.control!r}")
    raise ValueError(f"{name}: {key} does not set the steps of time.integrator = "
                     f"{tc.integrator!r} {why}: ladder {keys[0]} instead "
                     f"(e.g. --{'also' if name == 'also' else 'ladder'} {keys[0]}=...)")


def same_steps(t_runs) -> bool:
    """Every run of the time ladder ran and took the same number of accepted steps."""
    steps = [r.get("steps", -1) for r in t_runs]
    return len(steps) >= 2 and steps[0] >= 0 and all(n == steps[0] for n in steps)


def steps_text(t_runs) -> str:
    return f"{t_runs[0].get('steps', -1):,}"


def cap_key(base, t_key):
    """The key that scales the integrator's step cap (the registry's ``cap_keys``), when
    the time ladder was over a tolerance and a cap can bind; None otherwise."""
    from ..stepping.registry import get

    entry = get(base.resolve().time.integrator)
    if t_key not in ("time.rtol", "time.atol") or base.time.dt is not None:
        return None
    return next((k for k in entry.cap_keys if k != t_key), None)


def cap_text(base) -> str:
    from ..stepping.registry import get

    return "its step cap (" + get(base.resolve().time.integrator).cap + ")"


def default_time_ladder(base) -> dict:
    """The time ladder of the base config's integrator: the key that sets its steps
    (``step_keys``: time.dt with fixed steps, time.rtol under tolerance control or for an
    integrator without cfl control, time.cfl under cfl control), the base value and two
    refinements by 4."""
    k = step_keys(base)[0]
    v = base.get(k)
    return {k: [v, v / 4, v / 16]}
