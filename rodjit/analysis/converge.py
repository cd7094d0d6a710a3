"""``rodjit.converge``: observables along a resolution ladder, with observed orders,
Richardson-extrapolated continuum values and error estimates, the time-discretisation
contribution measured separately on a tolerance ladder."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .evaluate import evaluate
from .richardson import Study, study

__all__ = ["converge", "Convergence", "DEFAULT_OBSERVABLES", "load_convergence",
           "FORMAT_VERSION", "default_time_ladder"]

DEFAULT_OBSERVABLES = ("restitution_first", "contact_time_first", "min_u0",
                       "max_floor_force")
FORMAT_VERSION = 1
# the resolution keys whose level is a mesh width (1/value); any other key's value is used
# as the level itself (time.rtol, time.dt, time.cfl: smaller is finer)
_INVERSE_KEYS = ("rod.N",)


def _levels(key: str, values) -> list[float]:
    return [1.0 / v for v in values] if key in _INVERSE_KEYS else [float(v) for v in values]


def _check_ladder(name: str, ladder, base) -> tuple[str, list]:
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
    lv = _levels(key, values)
    if any(b >= a for a, b in zip(lv, lv[1:])):
        raise ValueError(f"{name} {key}: the levels must refine monotonically "
                         f"({'increasing' if key in _INVERSE_KEYS else 'decreasing'}), "
                         f"got {values}")
    return key, values


@dataclass
class ObservableConvergence:
    """One observable: the space ladder study, the time ladder study and the time
    contribution to the error (|value at the base tolerance − tolerance-converged value|)."""

    name: str
    space: Study
    time: Study | None = None
    time_error: float = math.nan
    statuses: list = field(default_factory=list)

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
                "time_error": self.time_error, "statuses": list(self.statuses)}


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
    time_at : object
        The ``key`` value the tolerance ladder ran at (None without one).
    observables : dict
        Observable name -> its study (``ObservableConvergence``).
    warnings : list of str
        Failed runs, the model's own limits, ladders outside the asymptotic range and
        values that do not settle.
    runs, time_runs : list of dict
        Each level's observables and status (space ladder, tolerance ladder).
    """

    base: object
    key: str
    levels: list
    time_key: str | None
    time_levels: list
    time_at: object
    observables: dict
    warnings: list
    runs: list
    time_runs: list

    def __getitem__(self, name: str) -> ObservableConvergence:
        return self.observables[name]

    def __repr__(self) -> str:
        lines = [f"Convergence({self.key} = {', '.join(map(str, self.levels))}"
                 + (f"; {self.time_key} = {', '.join(map(str, self.time_levels))} at "
                    f"{self.key} = {self.time_at}" if self.time_key else "") + ")"]
        for name, oc in self.observables.items():
            s = oc.space
            order = f"p={s.order:.2f}" if math.isfinite(s.order) else "p=—"
            t = (f" (time {oc.time_error:.2g})" if math.isfinite(oc.time_error) else "")
            lines.append(f"  {name}: {oc.value:.6g} ± {oc.error:.2g}{t}  {order}  {s.status}")
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
                "warnings": list(self.warnings)}

    def save(self, path, overwrite: bool = False) -> None:
        """Write an HDF5 file (root attribute ``rodjit_kind = "convergence"``): root
        attributes key, levels, time key/levels, config (TOML), warnings; one group per
        observable with datasets ``h``, ``values``, ``orders`` (and ``time_h``,
        ``time_values``) and attributes value, error, order, status, message, time_error.

        Parameters
        ----------
        path : str or os.PathLike
            The file to write (written to ``path.part``, then renamed).
        overwrite : bool
            Replace an existing file.

        Raises
        ------
        ValueError
            ``path`` exists and ``overwrite`` is false.
        """
        import os

        from importlib.metadata import PackageNotFoundError, version

        import h5py

        try:
            rodjit_version = version("rodjit")
        except PackageNotFoundError:
            rodjit_version = "0.0.0+unknown"
        if os.path.exists(path) and not overwrite:
            raise ValueError(f"{str(path)!r} exists; use --overwrite to replace it")
        tmp = f"{path}.part"
        with h5py.File(tmp, "w") as f:
            f.attrs.update({"rodjit_kind": "convergence", "format_version": FORMAT_VERSION,
                            "rodjit_version": rodjit_version, "key": self.key,
                            "levels": np.asarray(self.levels, float),
                            "time_key": self.time_key or "",
                            "time_levels": np.asarray(self.time_levels, float),
                            "time_at": float(self.time_at) if self.time_at is not None
                            else math.nan,
                            "config": self.base.to_toml(),
                            "warnings": "\n".join(self.warnings)})
            for name, oc in self.observables.items():
                g = f.create_group(f"observables/{name}")
                s = oc.space
                g["h"], g["values"] = np.asarray(s.h), np.asarray(s.values)
                g["orders"] = np.asarray(s.orders, float)
                g["statuses"] = np.asarray(oc.statuses, dtype=h5py.string_dtype())
                g.attrs.update({"value": oc.value, "error": oc.error, "order": s.order,
                                "space_error": s.error, "status": s.status,
                                "message": s.message, "time_error": oc.time_error})
                if oc.time is not None:
                    g["time_h"], g["time_values"] = np.asarray(oc.time.h), np.asarray(
                        oc.time.values)
                    g.attrs.update({"time_status": oc.time.status,
                                    "time_message": oc.time.message})
        os.replace(tmp, path)


def load_convergence(path) -> dict:
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
        if f.attrs.get("rodjit_kind") != "convergence":
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


def converge(config=None, ladder=None, *, also=None, observables=DEFAULT_OBSERVABLES,
             extra=None, time_at=None, jobs=None, scheduler=None,
             merge_time=None) -> Convergence:
    """Observables of ``config`` along a resolution ladder: observed orders, the
    Richardson-extrapolated continuum value and an error estimate for each.

    All runs go to the sweep engine's executors at once.  With a tolerance ladder
    (``also``), the time contribution |value at the base tolerance − the tolerance ladder's
    converged value| at ``time_at`` is added to each error.

    Parameters
    ----------
    config : Config or None
        The base configuration; None is ``Config()``.
    ladder : dict, optional
        One key and its levels, coarse to fine (lists, or ``"linspace(...)"`` text as on
        the command line); default ``{"rod.N": [25, 50, 100, 200, 400]}``.
    also : dict, optional
        A tolerance ladder, e.g. ``{"time.rtol": [1e-5, 1e-6, 1e-7]}``; its key must be
        what chooses the integrator's steps (``time.rtol``/``time.atol`` under tolerance
        control, ``time.cfl`` under ``time.control = "cfl"``, ``time.dt``).
    observables : sequence of str
        Names of ``rodjit.analysis.OBSERVABLES`` or of ``extra`` to study.
    extra : dict, optional
        Further observables: name -> function(Result) -> float.
    time_at : optional
        The ``ladder`` level the tolerance ladder runs at (default: the second finest).
    jobs : int, optional
        Worker processes, as for ``rodjit.sweep`` (default: every core).
    scheduler : str, optional
        Executor, as for ``rodjit.sweep`` (``"processes"``, ``"local"``,
        ``"tcp://HOST:PORT"``, ``"inline"``).
    merge_time : float, optional
        Contact episodes closer than this [s] are one macroscopic contact (default: a few
        periods of the rod's highest mode).

    Returns
    -------
    Convergence

    Raises
    ------
    TypeError
        ``config`` is not a ``rodjit.Config``.
    ValueError
        A ladder that is not one key with at least two monotonically refining levels, an
        unknown observable, or a tolerance key that does not choose the steps.
    """
    from ..config import Config
    from .observables import OBSERVABLES

    base = Config() if config is None else config
    if not isinstance(base, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(base).__name__}")
    ladder = {"rod.N": [25, 50, 100, 200, 400]} if ladder is None else ladder
    key, values = _check_ladder("ladder", ladder, base)
    extra = dict(extra or {})
    observables = list(observables)
    unknown = [o for o in observables if o not in OBSERVABLES and o not in extra]
    if unknown:
        raise ValueError(f"unknown observable {unknown[0]!r}; choose from "
                         f"{', '.join([*OBSERVABLES, *extra])}")
    configs = [base.override({key: v}) for v in values]
    t_key, t_values, t_configs = None, [], []
    if also is not None:
        t_key, t_values = _check_ladder("also", also, base)
        _check_time_key(t_key, base)
        if t_key == key:
            raise ValueError(f"also: {t_key} is already the ladder's key")
        time_at = values[-2] if time_at is None else time_at
        at = base.override({key: time_at})
        t_configs = [at.override({t_key: v}) for v in t_values]
        base_t = base.get(t_key)
    runs = evaluate(configs + t_configs, jobs=jobs, scheduler=scheduler,
                    merge_time=merge_time, extra=extra)
    runs, t_runs = runs[:len(configs)], runs[len(configs):]
    warnings = []
    failed = [f"{key} = {v}: {r['reason']}" for v, r in zip(values, runs)
              if r["status"] == "failed"]
    warnings += [f"run failed at {x}" for x in failed]
    # the model's own limits (the shock-forming μ = γ = 0 rod), once each along the ladder
    warnings += list(dict.fromkeys(w for c in configs for w in c.warnings()))
    out = {}
    for name in observables:
        s = study(name, _levels(key, values), _values_of(runs, name))
        statuses = [r.get("status", "") for r in runs]
        if len(set(statuses)) > 1 and name in OBSERVABLES:
            s.message = (s.message + "; " if s.message else "") + (
                "the first contact changes kind along the ladder (" +
                ", ".join(f"{v}: {st}" for v, st in zip(values, statuses)) + ")")
            if s.status == "converged":
                s.status = "pre-asymptotic"
        oc = ObservableConvergence(name, s, statuses=statuses)
        if t_key is not None:
            ts = study(name, _levels(t_key, t_values), _values_of(t_runs, name))
            oc.time = ts
            ref = ts.extrapolated if math.isfinite(ts.extrapolated) else ts.values[-1]
            here = _at_base(base_t, t_values, ts.values, runs, values, time_at, name)
            oc.time_error = abs(here - ref) if math.isfinite(here) else math.nan
            if ts.status not in ("converged", "exact", "oscillating"):
                warnings.append(f"{name}: {t_key} ladder {ts.status}: {ts.message}")
        if s.status not in ("converged", "exact"):
            warnings.append(f"{name}: {s.status}: {s.message}")
        out[name] = oc
    return Convergence(base, key, values, t_key, t_values, time_at, out, warnings, runs,
                       t_runs)


def _by_tolerance(base) -> bool:
    """Whether time.rtol/atol choose the steps (energy, or time.control = "tolerance")."""
    return base.time.integrator == "energy" or base.time.control == "tolerance"


def _check_time_key(key: str, base) -> None:
    """The tolerance ladder must vary what controls the integrator's steps."""
    integ = base.time.integrator
    if key in ("time.rtol", "time.atol") and not _by_tolerance(base):
        raise ValueError(f"also: {key} does not choose the steps of time.integrator = "
                         f"{integ!r} with time.control = 'cfl': use --also time.cfl=...")
    if key == "time.cfl" and _by_tolerance(base):
        raise ValueError(f"also: time.cfl does not choose the steps of time.integrator = "
                         f"{integ!r} under tolerance control: use --also time.rtol=... "
                         f"(or set time.control = 'cfl')")
    if key == "time.cfl" and base.time.dt is not None:
        raise ValueError("also: time.cfl has no effect with a fixed step time.dt; ladder "
                         "time.dt instead")


def default_time_ladder(base) -> dict:
    """The tolerance ladder of the base config's integrator: time.rtol (energy, or any
    integrator under tolerance control) or time.cfl (time.control = "cfl"), the base value
    and two refinements by 4."""
    if base.time.dt is not None:
        return {"time.dt": [base.time.dt, base.time.dt / 4, base.time.dt / 16]}
    if _by_tolerance(base):
        r = base.time.rtol
        return {"time.rtol": [r, r / 4, r / 16]}
    c = base.time.cfl
    return {"time.cfl": [c, c / 4, c / 16]}


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
