"""``rodjit.converge``: observables along a resolution ladder, with observed orders,
Richardson-extrapolated continuum values and error estimates, the time-discretisation
contribution measured separately on a time ladder over the key that sets the integrator's
steps (``stepping.registry``), and the predictability time of the heights along it."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Literal, Mapping, Sequence

import numpy as np

from ..config.checks import SHOCK_WARNING
from ..records.observables import OBSERVABLES
from .evaluate import evaluate
from .ladders import (TIME_KEYS, cap_key, cap_text, check_ladder, check_time_key,
                      default_time_ladder, levels, same_steps, step_keys, steps_text)
from .predictability import (PREDICTABILITY_CONVERGENCE, PREDICTABILITY_FRACTION,
                             PREDICTABILITY_NOISE, predictability_time)
from .richardson import Study, study

if TYPE_CHECKING:
    from ..config import Config
    from ..records.result import Result

__all__ = ["converge", "Convergence", "DEFAULT_OBSERVABLES", "load_convergence",
           "FORMAT_VERSION", "default_time_ladder", "step_keys", "predictability_time",
           "PREDICTABILITY_FRACTION", "PREDICTABILITY_CONVERGENCE",
           "PREDICTABILITY_NOISE", "NOT_MEASURED", "NO_LIMIT"]

DEFAULT_OBSERVABLES = ("restitution_first", "contact_time_first", "min_u0",
                       "max_floor_force")
FORMAT_VERSION = 2     # 2: time_status, predictability_time, time_steps
CONVERGENCE_KIND = "convergence"   # root attribute rodjit_kind of a convergence file
# The status of a time study whose runs all took the same number of steps: the ladder did
# not change the steps, so the spread of its values says nothing about the time error.
NOT_MEASURED = "not measured"
# The status of a first-bounce observable on a rod.N ladder of a rod whose model warns of
# no continuum limit (``config.checks.SHOCK_WARNING``: μ = γ = 0) where three levels would
# have given a value and a bar that no fourth level checks: its values along the ladder are
# printed, not an extrapolation with a bar (four levels whose orders agree, as in the
# linear limit of a slow impact, are extrapolated; a ladder that does not settle says so).
NO_LIMIT = "no limit"
@dataclass
class ObservableConvergence:
    """One observable: the space ladder study, the time ladder study and the time
    contribution to the error (|value at the base tolerance − tolerance-converged value|)."""

    name: str
    space: Study
    time: Study | None = None
    time_error: float = math.nan
    statuses: list = field(default_factory=list)
    time_status: str = ""     # NOT_MEASURED when the ladder did not change the steps

    @property
    def value(self) -> float:
        return self.space.extrapolated

    @property
    def error(self) -> float:
        """Space error estimate plus the time contribution (when measured)."""
        t = self.time_error if math.isfinite(self.time_error) else 0.0
        return self.space.error + t

    def to_dict(self) -> dict:
        return {"name": self.name, "value": self.value, "error": self.error,
                "space": self.space.to_dict(),
                "time": self.time.to_dict() if self.time is not None else None,
                "time_error": self.time_error, "time_status": self.time_status,
                "statuses": list(self.statuses)}


@dataclass
class Convergence:
    """Result of ``converge``: per observable the values along the ladder, observed orders,
    the extrapolated continuum value and its error.

    ``conv["restitution_first"]`` is one observable's study (``.value``, ``.error``,
    ``.space.orders``, ``.space.status``); ``repr`` prints the table ``rodjit converge``
    prints.

    Attributes
    ----------
    base : Config
        The configuration every level starts from.
    key : str
        The ladder's key (e.g. ``"rod.N"``).
    levels : list
        The ladder's values, coarse to fine.
    time_key : str or None
        The tolerance ladder's key (``"time.rtol"``, ``"time.cfl"``, ``"time.dt"``), None
        without one.
    time_levels : list
        The tolerance ladder's values (empty without one).
    time_at : float or None
        The ``key`` value the tolerance ladder ran at (None without one).
    observables : dict
        Observable name -> its study (``ObservableConvergence``).
    warnings : list of str
        Failed runs, the model's own limits, ladders outside the asymptotic range, values
        that do not settle and time ladders that did not change the steps.
    runs, time_runs : list of dict
        Each level's observables, status and ``steps`` (space ladder, time ladder).
    predictability_time : float
        The simulated time [s] after which the runs along the time ladder (or along the
        ladder itself, when its key is a time key) disagree in the heights by more than
        their error bar (``predictability_time``); inf if they never do before
        ``time.t_end``, NaN when not measured (no time ladder of three levels with
        snapshots, or one that did not change the steps).
    time_steps : list of int
        The accepted steps of each run of the time ladder.
    """

    base: Config
    key: str
    levels: list
    time_key: str | None
    time_levels: list
    time_at: float | None
    observables: dict
    warnings: list
    runs: list
    time_runs: list
    predictability_time: float = math.nan
    time_steps: list = field(default_factory=list)

    def __getitem__(self, name: str) -> ObservableConvergence:
        return self.observables[name]

    def __repr__(self) -> str:
        lines = [f"Convergence({self.key} = {', '.join(map(str, self.levels))}"
                 + (f"; {self.time_key} = {', '.join(map(str, self.time_levels))} at "
                    f"{self.key} = {self.time_at}" if self.time_key else "") + ")"]
        for name, oc in self.observables.items():
            s = oc.space
            order = f"p={s.order:.2f}" if math.isfinite(s.order) else "p=—"
            t = (f" (time {oc.time_error:.2g})" if math.isfinite(oc.time_error) else
                 f" (time {oc.time_status})" if oc.time_status else "")
            if s.status == NO_LIMIT:
                along = ", ".join(f"{v:.6g}" for v in s.values)
                lines.append(f"  {name}: {along} along {self.key}  {NO_LIMIT}")
                continue
            lines.append(f"  {name}: {oc.value:.6g} ± {oc.error:.2g}{t}  {order}  {s.status}")
        ladder_key = self.time_key or (self.key if self.key in TIME_KEYS else None)
        if ladder_key:
            p = self.predictability_time
            lines.append("  predictability_time: " + (
                "not measured" if math.isnan(p) else
                f"none before t_end = {self.base.time.t_end:g} s" if p == math.inf else
                f"{p:.4g} s (the heights along the {ladder_key} ladder disagree beyond "
                f"it: trajectory-level outputs after it are not reproducible)"))
        for w in self.warnings:
            lines.append(f"  warning: {w}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The study as plain values (what ``save`` writes, ``load_convergence`` reads).

        Returns
        -------
        dict
            ``key``, ``levels``, ``time_key``, ``time_levels``, ``time_at``, ``config``
            (nested, as ``Config.to_dict``), ``observables`` (name -> value, error and the
            space and time studies) and ``warnings``.
        """
        return {"key": self.key, "levels": list(self.levels), "time_key": self.time_key,
                "time_levels": list(self.time_levels), "time_at": self.time_at,
                "config": self.base.to_dict(),
                "observables": {k: v.to_dict() for k, v in self.observables.items()},
                "warnings": list(self.warnings),
                "predictability_time": self.predictability_time,
                "time_steps": list(self.time_steps)}

    def save(self, path: str | os.PathLike[str], overwrite: bool = False,
             command: str | None = None) -> None:
        """Write an HDF5 file (root attribute ``rodjit_kind = "convergence"``; ``rodjit
        info`` and ``rodjit plot`` read it): root attributes created, command, key,
        levels, time key/levels, config (TOML), warnings,
        predictability_time and time_steps (format 2); one group per observable with
        datasets ``h``, ``values``, ``orders`` (and ``time_h``, ``time_values``) and
        attributes value, error, order, status, message, time_error and
        time_error_status (``"not measured"`` where the time ladder did not move it).

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (written to ``path.part``, then renamed; through a symbolic
            link, its target).
        overwrite : bool
            Replace an existing convergence file.
        command : str, optional
            The command line recorded in the file (root attribute ``command``; default:
            this call).

        Raises
        ------
        ValueError
            As every writer's output (``output.h5files.check_output``): ``path`` exists
            and ``overwrite`` is false (``OutputExists``), or it is not a rodjit
            convergence file, whatever ``overwrite`` (``OutputOtherKind``: a configuration,
            a text file, a run or sweep file), or not a regular file (a FIFO, a device),
            or its directory is missing or not writable.
        """
        from importlib.metadata import PackageNotFoundError, version

        import h5py

        from ..output.h5files import check_output, now

        try:
            rodjit_version = version("rodjit")
        except PackageNotFoundError:
            rodjit_version = "0.0.0+unknown"
        check_output(path, overwrite, CONVERGENCE_KIND)
        target = os.path.realpath(path)      # a link is written through, as by every writer
        tmp = f"{target}.part"
        with h5py.File(tmp, "w") as f:
            f.attrs.update({"rodjit_kind": CONVERGENCE_KIND, "format_version": FORMAT_VERSION,
                            "rodjit_version": rodjit_version, "created": now(),
                            "command": command or f"rodjit.converge(...).save({str(path)!r})",
                            "key": self.key,
                            "levels": np.asarray(self.levels, float),
                            "time_key": self.time_key or "",
                            "time_levels": np.asarray(self.time_levels, float),
                            "time_at": float(self.time_at) if self.time_at is not None
                            else math.nan,
                            "config": self.base.to_toml(),
                            "warnings": "\n".join(self.warnings),
                            "predictability_time": float(self.predictability_time),
                            "time_steps": np.asarray(self.time_steps, np.int64)})
            for name, oc in self.observables.items():
                g = f.create_group(f"observables/{name}")
                s = oc.space
                g["h"], g["values"] = np.asarray(s.h), np.asarray(s.values)
                g["orders"] = np.asarray(s.orders, float)
                g["statuses"] = np.asarray(oc.statuses, dtype=h5py.string_dtype())
                g.attrs.update({"value": oc.value, "error": oc.error, "order": s.order,
                                "space_error": s.error, "status": s.status,
                                "message": s.message, "time_error": oc.time_error,
                                "time_error_status": oc.time_status})
                if oc.time is not None:
                    g["time_h"], g["time_values"] = np.asarray(oc.time.h), np.asarray(
                        oc.time.values)
                    g.attrs.update({"time_status": oc.time.status,
                                    "time_message": oc.time.message})
        os.replace(tmp, target)


def load_convergence(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a convergence file back as the dictionary of ``Convergence.to_dict`` (config
    as TOML text).

    Parameters
    ----------
    path : str or os.PathLike
        A file written by ``Convergence.save`` or ``rodjit converge``.

    Returns
    -------
    dict
        The root attributes, and ``observables``: name -> its datasets and attributes.

    Raises
    ------
    ValueError
        The file is not a rodjit convergence file.
    """
    import h5py

    with h5py.File(path, "r") as f:
        if f.attrs.get("rodjit_kind") != CONVERGENCE_KIND:
            raise ValueError(f"{str(path)!r} is not a rodjit convergence file")
        out = {k: (v.item() if hasattr(v, "item") and np.ndim(v) == 0 else v)
               for k, v in f.attrs.items()}
        out["observables"] = {}
        for name, g in f["observables"].items():
            d = {k: g[k][()] for k in g}
            d.update(g.attrs)
            out["observables"][name] = d
    return out


def _values_of(runs, name):
    return [r.get(name, math.nan) for r in runs]


def converge(config: Config | None = None, ladder: Mapping[str, Any] | None = None, *,
             also: Mapping[str, Any] | Literal[False] | None = None,
             observables: Sequence[str] = DEFAULT_OBSERVABLES,
             extra: Mapping[str, Callable[[Result], float]] | None = None,
             time_at: float | None = None, jobs: int | None = None,
             scheduler: str | None = None, merge_time: float | None = None,
             max_output: float | None = None, max_steps: float | None = None) -> Convergence:
    """Observables of ``config`` along a resolution ladder: observed orders, the
    Richardson-extrapolated continuum value and an error estimate for each, the time
    error measured on a time ladder, and the predictability time of the heights.

    All runs go to the sweep engine's executors at once.  The time ladder (``also``, by
    default ``default_time_ladder``: the key that sets the integrator's steps, from
    ``stepping.registry``) runs at ``time_at``; its contribution |value at the base
    setting − the ladder's converged value| is added to each error.  Where every run of
    the time ladder took the same number of steps (its key does not change the steps, e.g.
    a cap binds) and the registry names a key that scales the cap, the same ladder is run
    over that key instead; if the steps still do not change, the time error is
    ``NOT_MEASURED`` (never 0) and a warning says so.

    Parameters
    ----------
    config : Config or None
        The base configuration; None is ``Config()``.
    ladder : dict, optional
        One key and its levels, coarse to fine (lists, or ``"linspace(...)"`` text as on
        the command line); default ``{"rod.N": [25, 50, 100, 200, 400]}``.
    also : dict or False, optional
        A time ladder, e.g. ``{"time.rtol": [1e-5, 1e-6, 1e-7]}``; its key must set the
        integrator's steps (``step_keys``: ``time.rtol``/``time.atol`` under tolerance
        control and for the integrators without cfl control, ``time.cfl`` for ``verlet``
        and ``semi-implicit`` under ``time.control = "cfl"``, ``time.dt`` with fixed
        steps).  None: ``default_time_ladder``; False: no time ladder.
    observables : sequence of str
        Names of ``rodjit.analysis.OBSERVABLES`` or of ``extra`` to study.
    extra : dict, optional
        Further observables: name -> function(Result) -> float.
    time_at : optional
        The ``ladder`` level the time ladder runs at (default: the second finest).
    jobs : int, optional
        Worker processes, as for ``rodjit.sweep`` (default: every core).
    scheduler : str, optional
        Executor, as for ``rodjit.sweep`` (``"processes"``, ``"local"``,
        ``"tcp://HOST:PORT"``, ``"inline"``).
    merge_time : float, optional
        The flight time τ [s] after which a release ends a bounce (``flight_groups``;
        default: π h/c, the period of the rod's highest mode, as the bounce table).
    max_output, max_steps : float, optional
        The limits of a new run (``rodjit.run_to_file``), checked on every run of the
        study before any runs (default: the same defaults).

    Returns
    -------
    Convergence

    Raises
    ------
    TypeError
        ``config`` is not a ``rodjit.Config``.
    ValueError
        A ladder that is not one key with at least two monotonically refining levels, an
        unknown observable, a time key that does not set the integrator's steps (the
        message names the key that does), or a level whose run would refuse to run
        (``Config.check_runnable``: verlet under tolerance control above its viscous
        limit, naming time.cfl).
    """
    from ..config import Config
    from .observables import OBSERVABLES

    base = Config() if config is None else config
    if not isinstance(base, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(base).__name__}")
    # "auto" chooses once: every rung runs the base's integrator
    base = base.resolve()
    ladder = {"rod.N": [25, 50, 100, 200, 400]} if ladder is None else ladder
    key, values = check_ladder("ladder", ladder, base)
    check_time_key("ladder", key, base)
    extra = dict(extra or {})
    observables = list(observables)
    unknown = [o for o in observables if o not in OBSERVABLES and o not in extra]
    if unknown:
        raise ValueError(f"unknown observable {unknown[0]!r}; choose from "
                         f"{', '.join([*OBSERVABLES, *extra])}")
    configs = [base.override({key: v}) for v in values]
    t_key: str | None = None
    t_values: list[Any] = []
    t_configs: list[Config] = []
    if also is None and key not in TIME_KEYS:
        also = default_time_ladder(base)
    if also:
        t_key, t_values = check_ladder("also", also, base)
        check_time_key("also", t_key, base)
        if t_key == key:
            raise ValueError(f"also: {t_key} is already the ladder's key")
        time_at = values[-2] if time_at is None else time_at
        at = base.override({key: time_at})
        t_configs = [at.override({t_key: v}) for v in t_values]
    for c in configs + t_configs:        # what a run would refuse: before any runs
        c.check_runnable()
    limits: dict[str, Any] = {"max_output": max_output, "max_steps": max_steps}
    # a ladder over a time key is itself a time ladder: its heights give the
    # predictability time
    on_time = key in TIME_KEYS
    runs = evaluate(configs + t_configs, jobs=jobs, scheduler=scheduler,
                    merge_time=merge_time, extra=extra,
                    histories=bool(t_configs) or on_time, **limits)
    runs, t_runs = runs[:len(configs)], runs[len(configs):]
    warnings = []
    failed = [f"{key} = {v}: {r['reason']}" for v, r in zip(values, runs)
              if r["status"] == "failed"]
    warnings += [f"run failed at {x}" for x in failed]
    # the model's own limits (the shock-forming μ = γ = 0 rod), once each along the ladder
    warnings += list(dict.fromkeys(w for c in configs for w in c.warnings()))
    # no continuum limit of the first-bounce observables along rod.N (shock-forming rod)
    no_limit = key == "rod.N" and any(SHOCK_WARNING in c.warnings() for c in configs)
    measured = True
    if t_key is not None:
        if same_steps(t_runs):
            cap = cap_key(base, t_key)
            if cap is not None:
                # the tolerance does not change the steps: the cap binds; refine what
                # scales the cap by the same factors
                c0 = base.get(cap)
                c_values = [c0 * v / t_values[0] for v in t_values]
                c_configs = [at.override({cap: v}) for v in c_values]
                for c in c_configs:
                    c.check_runnable()
                c_runs = evaluate(c_configs, jobs=jobs,
                                  scheduler=scheduler, merge_time=merge_time, extra=extra,
                                  histories=True, **limits)
                warnings.append(
                    f"{t_key} does not change the steps of time.integrator = "
                    f"{base.time.integrator!r} here ({steps_text(t_runs)} steps at every "
                    f"level: its step cap, which scales with {cap}, binds); the time "
                    f"error is measured on "
                    f"{cap} = {', '.join(f'{v:g}' for v in c_values)} instead "
                    f"(registry: {cap_text(base)})")
                t_key, t_values, t_runs = cap, c_values, c_runs
            if same_steps(t_runs):
                measured = False
                warnings.append(
                    f"time error not measured: {t_key} = "
                    f"{', '.join(f'{v:g}' for v in t_values)} did not change the steps "
                    f"({steps_text(t_runs)} at every level)")
        base_t = base.get(t_key)
    histories = [r.pop("history", None) for r in t_runs]
    main_histories = [r.pop("history", None) for r in runs]
    out = {}
    for name in observables:
        s = study(name, levels(key, values), _values_of(runs, name))
        statuses = [r.get("status", "") for r in runs]
        if len(set(statuses)) > 1 and name in OBSERVABLES:
            s.message = (s.message + "; " if s.message else "") + (
                "the first contact changes kind along the ladder (" +
                ", ".join(f"{v}: {st}" for v, st in zip(values, statuses)) + ")")
            if s.status == "converged":
                s.status = "pre-asymptotic"
        unchecked = (len(s.orders) < 2 and s.status in ("converged", "oscillating",
                                                         "pre-asymptotic"))
        if no_limit and name in OBSERVABLES and unchecked:
            # the model warns of no limit and no fourth level checks what three levels
            # seem to show: a bar here would rest on nothing
            s.status, s.order = NO_LIMIT, math.nan
            s.extrapolated, s.error = math.nan, math.nan
            s.message = ("the model has no continuum limit as rod.N grows (rod.mu = "
                         "rod.gamma = 0): the values along the ladder estimate none")
        oc = ObservableConvergence(name, s, statuses=statuses)
        if t_key is not None:
            ts = study(name, levels(t_key, t_values), _values_of(t_runs, name))
            oc.time = ts
            if not measured:
                ts.status, ts.message = NOT_MEASURED, "the ladder did not change the steps"
                ts.extrapolated, ts.error = math.nan, math.nan
                oc.time_status = NOT_MEASURED
            elif ts.status == "exact" and all(math.isfinite(x) for x in ts.values):
                # identical at every level although the steps changed: the steps that set
                # this value (e.g. a maximum reached where a step cap binds) did not
                ts.status = NOT_MEASURED
                ts.message = ("identical at every level: the steps that set it did not "
                              "change")
                ts.extrapolated, ts.error = math.nan, math.nan
                oc.time_status = NOT_MEASURED
                warnings.append(f"{name}: time error not measured: the same value at every "
                                f"level of the {t_key} ladder (the steps that set it did "
                                f"not change)")
            else:
                ref = ts.extrapolated if math.isfinite(ts.extrapolated) else ts.values[-1]
                here = _at_base(base_t, t_values, ts.values, runs, values, time_at, name)
                oc.time_error = abs(here - ref) if math.isfinite(here) else math.nan
                if ts.status in ("oscillating", "pre-asymptotic") and math.isfinite(ts.error):
                    # not extrapolated: the finest level is itself uncertain by the
                    # ladder's own error (an observable past the predictability time
                    # scatters along a tolerance ladder)
                    oc.time_error += ts.error
                if ts.status not in ("converged", "exact", "oscillating"):
                    warnings.append(f"{name}: {t_key} ladder {ts.status}: {ts.message}")
        if s.status not in ("converged", "exact", NO_LIMIT):
            warnings.append(f"{name}: {s.status}: {s.message}")
        out[name] = oc
    p_time = math.nan
    if t_key is not None and measured:
        p_time = predictability_time(histories, base.time.t_end)
    elif on_time and not same_steps(runs):
        p_time = predictability_time(main_histories, base.time.t_end)
    if math.isfinite(p_time):
        for name, oc in out.items():
            study_t = oc.space if on_time else oc.time
            if study_t is not None and study_t.status in ("not converging", "oscillating"):
                warnings.append(
                    f"{name}: the runs along the {t_key or key} ladder disagree after "
                    f"t = {p_time:.4g} s (the predictability time): a value set after it "
                    f"is not reproducible: only its spread along the ladder is known")
    return Convergence(base, key, values, t_key, t_values, time_at, out, warnings, runs,
                       t_runs, p_time, [r.get("steps", -1) for r in t_runs])


def _at_base(base_t, t_values, t_obs, runs, values, time_at, name) -> float:
    """The observable at the base tolerance and ``time_at``: from the tolerance ladder if
    it holds the base tolerance, else from the space ladder's run at ``time_at``."""
    for v, x in zip(t_values, t_obs):
        if v == base_t:
            return x
    for v, r in zip(values, runs):
        if v == time_at:
            return r.get(name, math.nan)
    return math.nan
