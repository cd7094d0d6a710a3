"""``rodjit.fit``: the value of one configuration key at which an observable takes a
target, by a parallel bracket scan and a safeguarded root finder (Illinois false position
with bisection); ``fit_table``: least squares of several keys against measurements."""
from __future__ import annotations

import math
import numbers
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any, Iterable, Mapping

import numpy as np

from .evaluate import evaluate

if TYPE_CHECKING:
    from ..config import Config

__all__ = ["fit", "FitResult", "FitError", "scan_points"]

SCAN_POINTS = 8


class FitError(ValueError):
    """The target cannot be fitted in the bracket (unreachable, crossed more than once, or
    the observable undefined at a scanned value).

    A ``ValueError``, so the command line reports it as bad input.

    Parameters
    ----------
    message : str
        Why, naming the range the bracket reaches or where the target is crossed.
    samples : sequence of (float, float)
        The scanned ``(value, observable)`` pairs, kept as the ``samples`` attribute.
    """

    def __init__(self, message: str, samples: Iterable[tuple[float, Any]] = ()) -> None:
        super().__init__(message)
        self.samples = list(samples)


@dataclass
class FitResult:
    """The answer of ``fit``: the ``value`` of ``key`` where ``observable`` = ``target``.

    Attributes
    ----------
    key : str
        The fitted configuration key.
    observable : str
        The observable matched (a name of ``rodjit.analysis.OBSERVABLES``).
    target : float
        Its target value.
    value : float
        The fitted value of ``key``.
    achieved : float
        The observable at ``value``.
    sensitivity : float
        d(observable)/d(key) at the answer (from the final bracket).
    bracket : tuple of float
        The ``(lo, hi)`` searched.
    resolution_shift : float
        How far the answer moves from the coarser resolution ``coarse`` to the one fitted,
        estimated by linearisation at the answer (NaN when not measured).
    coarse : str
        That coarser resolution, e.g. ``"rod.N = 2"``.
    converged : bool
        Whether the Richardson-extrapolated continuum value was fitted.
    evaluations : int
        Runs made (a ladder counts as one).
    iterations : int
        Root-finder iterations after the scan.
    samples : list of (float, float)
        Every ``(value, observable)`` evaluated, sorted by value.
    notes : list of str
        What the caller should know (a non-monotone observable, an iteration limit).
    """

    key: str
    observable: str
    target: float
    value: float
    achieved: float
    sensitivity: float
    bracket: tuple
    resolution_shift: float = math.nan
    coarse: str = ""
    converged: bool = False
    evaluations: int = 0
    iterations: int = 0
    samples: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def __repr__(self) -> str:
        shift = (f", moves {self.resolution_shift:+.3g} from {self.coarse}"
                 if math.isfinite(self.resolution_shift) else "")
        return (f"FitResult({self.key} = {self.value:.6g}: {self.observable} = "
                f"{self.achieved:.6g} (target {self.target:g}), d/d{self.key.split('.')[-1]}"
                f" = {self.sensitivity:.3g}{shift}; {self.evaluations} evaluations)")

    def to_dict(self) -> dict:
        """Every attribute as plain values (``dataclasses.asdict``; JSON-ready).

        Returns
        -------
        dict
        """
        return asdict(self)


MAX_SCAN = 10**4     # values one scan of the bracket may take


def scan_points(lo: float, hi: float, n: int) -> list[float]:
    """``n`` values spanning [lo, hi]: geometric when the bracket spans two decades or more
    (0 kept as the first point), else even."""
    if isinstance(n, bool) or not isinstance(n, int) or not 2 <= n <= MAX_SCAN:
        shown = repr(n) if len(repr(n)) <= 24 else repr(n)[:12] + "..."
        raise ValueError(f"points = {shown} is out of range (a whole number in [2, "
                         f"{MAX_SCAN}])")
    if lo >= 0 and hi > 0 and (lo == 0 or hi / lo >= 100):
        if lo == 0:
            return [0.0] + [float(x) for x in np.geomspace(hi * 1e-3, hi, n - 1)]
        return [float(x) for x in np.geomspace(lo, hi, n)]
    return [float(x) for x in np.linspace(lo, hi, n)]


class _Objective:
    """observable(key = x) at the given resolution, or its extrapolated continuum value
    along ``ladder``; cached, evaluated in parallel batches."""

    def __init__(self, base, key, name, ladder, jobs, scheduler, merge_time, limits=None):
        self.base, self.key, self.name = base, key, name
        self.limits = limits or {}      # max_output, max_steps for ``evaluate``
        self.ladder, self.jobs, self.scheduler = ladder, jobs, scheduler
        self.merge_time = merge_time
        self.cache: dict[float, tuple[float, str]] = {}
        self.evaluations = 0

    def config(self, x):
        cfg = self.base.override({self.key: x})
        return cfg

    def batch(self, xs) -> list[float]:
        todo = [x for x in dict.fromkeys(xs) if x not in self.cache]
        if todo:
            if self.ladder is None:
                runs = evaluate([self.config(x) for x in todo], jobs=self.jobs,
                                scheduler=self.scheduler, merge_time=self.merge_time,
                                columns=[self.name], **self.limits)
                for x, r in zip(todo, runs):
                    self.cache[x] = (float(r.get(self.name, math.nan)), r.get("reason", ""))
            else:
                from .ladders import check_ladder
                from .ladders import levels as mesh_levels
                from .richardson import study

                lkey, levels = check_ladder("ladder", self.ladder, self.base)
                cfgs = [self.config(x).override({lkey: v}) for x in todo for v in levels]
                runs = evaluate(cfgs, jobs=self.jobs, scheduler=self.scheduler,
                                merge_time=self.merge_time, columns=[self.name],
                                **self.limits)
                n = len(levels)
                for i, x in enumerate(todo):
                    part = runs[i * n:(i + 1) * n]
                    s = study(self.name, mesh_levels(lkey, levels),
                              [r.get(self.name, math.nan) for r in part])
                    value = s.extrapolated if s.status in ("converged", "exact",
                                                           "pre-asymptotic") else math.nan
                    self.cache[x] = (float(value), s.message or part[-1].get("reason", ""))
            self.evaluations += len(todo)
        return [self.cache[x][0] for x in xs]

    def reason(self, x) -> str:
        return self.cache.get(x, (math.nan, ""))[1]


def _check_target(target) -> tuple[str, float]:
    from .observables import OBSERVABLES

    if not isinstance(target, dict) or len(target) != 1:
        raise ValueError(f"target must be one observable and its value, e.g. "
                         f"{{'restitution_first': 0.8}}, not {target!r}")
    (name, value), = target.items()
    if name not in OBSERVABLES:
        raise ValueError(f"unknown observable {name!r}; choose from {', '.join(OBSERVABLES)}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"target {name} = {value!r} is not finite")
    return name, value


def fit(key: str, target: Mapping[str, float], config: Config | None = None, *,
        bracket: tuple[float, float] = (0.0, 1000.0), points: int | None = None,
        ftol: float = 1e-4, xtol: float | None = None, max_iter: int = 60,
        converged: bool = False, ladder: Mapping[str, Any] | None = None,
        coarse: Mapping[str, Any] | None = None, jobs: int | None = None,
        scheduler: str | None = None, merge_time: float | None = None,
        max_output: float | None = None, max_steps: float | None = None) -> FitResult:
    """The value of ``key`` in ``bracket`` at which ``target``'s observable (e.g.
    ``{"restitution_first": 0.8}``) takes its value, at the resolution of ``config``.

    ``points`` values scan the bracket in parallel; exactly one crossing of the target must
    be found, then Illinois false position, safeguarded by bisection, narrows it until the
    observable is within ``ftol`` of the target or the bracket is narrower than ``xtol``.

    Parameters
    ----------
    key : str
        A real-valued configuration key, e.g. ``"rod.mu"``.
    target : dict
        One observable and its value, e.g. ``{"restitution_first": 0.8}``.
    config : Config or None
        The base configuration; None is ``Config()``.
    bracket : tuple of float
        ``(lo, hi)``, finite, lo < hi, both valid values of ``key``.
    points : int, optional
        Values scanning the bracket, >= 2 (default 8; geometric when the bracket spans two
        decades or more).
    ftol : float
        Stop when the observable is this close to the target (finite, > 0).
    xtol : float, optional
        Stop when the bracket is this narrow (default 1e-9 of the bracket).
    max_iter : int
        Most root-finder iterations after the scan.
    converged : bool
        Fit the Richardson-extrapolated continuum value along ``ladder`` instead of the
        value at ``config``'s resolution.
    ladder : dict, optional
        The resolution ladder for ``converged`` (default ``rod.N`` = N/2, N, 2N).
    coarse : dict, optional
        The resolution (``{"rod.N": n}``) the answer is compared with for
        ``resolution_shift`` (default N/2, or the ladder's finest level alone).
    jobs : int, optional
        Worker processes, as for ``rodjit.sweep``.
    scheduler : str, optional
        Executor, as for ``rodjit.sweep``.
    merge_time : float, optional
        The flight time τ [s] that ends a bounce (``records.observables.flight_groups``;
        default π h/c, the bounce table's).
    max_output, max_steps : float, optional
        The limits of a new run (``rodjit.run_to_file``), checked on every run before it
        runs (default: the same defaults).

    Returns
    -------
    FitResult

    Raises
    ------
    FitError
        The target is outside the range the bracket reaches (naming that range), is
        crossed more than once (naming where), or the observable is undefined at a scanned
        value.
    ValueError
        An unknown observable, a bad bracket, a key that is not real-valued, or an
        ``ftol`` or ``xtol`` that is not a finite number > 0.
    TypeError
        ``config`` is not a ``rodjit.Config``.
    """
    from ..config import Config

    base = Config() if config is None else config
    if not isinstance(base, Config):
        raise TypeError(f"config must be a rodjit.Config, not {type(base).__name__}")
    # "auto" chooses once: every trial runs the base's integrator
    base = base.resolve()
    name, goal = _check_target(target)
    try:
        lo, hi = (float(b) for b in bracket)
    except (TypeError, ValueError):
        raise ValueError(f"bracket must be two numbers (lo, hi), not {bracket!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"bracket = {bracket!r} is out of range (finite lo < hi)")
    for name_, tol in (("ftol", ftol), ("xtol", xtol)):
        if name_ == "xtol" and tol is None:
            continue
        if isinstance(tol, bool) or not isinstance(tol, numbers.Real) or not (
                0 < tol < math.inf):
            raise ValueError(f"{name_} = {tol!r} is out of range (a finite number > 0: "
                             f"the search stops within it)")
    base.override({key: lo}), base.override({key: hi})       # key and range valid
    if isinstance(base.get(key), int) or isinstance(base.get(key), str):
        raise ValueError(f"{key} is not a real-valued key; fit needs a continuous parameter")
    n_scan = points if points is not None else SCAN_POINTS
    if converged and ladder is None:
        n = base.rod.N
        ladder = {"rod.N": [max(1, n // 2), n, 2 * n]}
    obj = _Objective(base, key, name, ladder if converged else None, jobs, scheduler,
                     merge_time, {"max_output": max_output, "max_steps": max_steps})
    xs = scan_points(lo, hi, n_scan)
    fs = obj.batch(xs)
    bad = [(x, obj.reason(x)) for x, f in zip(xs, fs) if not math.isfinite(f)]
    if bad:
        x, why = bad[0]
        raise FitError(f"{name} is undefined at {key} = {x:g} ({why or 'no value'}); narrow "
                       f"the bracket or lengthen the run", list(zip(xs, fs)))
    g = [f - goal for f in fs]
    cross = [i for i in range(len(xs) - 1) if g[i] == 0 or g[i] * g[i + 1] < 0]
    if g[-1] == 0:
        cross.append(len(xs) - 1)
    samples = list(zip(xs, fs))
    if not cross:
        raise FitError(f"target {name} = {goal:g} is outside the range {min(fs):.6g} .. "
                       f"{max(fs):.6g} that {key} in [{lo:g}, {hi:g}] reaches (sampled at "
                       f"{', '.join(f'{x:.4g}' for x in xs)})", samples)
    if len(cross) > 1:
        where = ", ".join(f"[{xs[i]:.4g}, {xs[min(i + 1, len(xs) - 1)]:.4g}]" for i in cross)
        raise FitError(f"{name} is not monotone in {key}: it crosses {goal:g} in {where}; "
                       f"narrow the bracket to one of them", samples)
    notes = []
    d = np.diff(fs)
    nz = [i for i in range(len(d)) if d[i] != 0]          # plateaus do not turn
    turns = [xs[j] for i, j in zip(nz, nz[1:]) if d[i] * d[j] < 0]
    if turns:
        notes.append(f"{name} is not monotone in {key} (turns near "
                     f"{', '.join(f'{x:.4g}' for x in turns)}); one crossing of the target")
    i = cross[0]
    if g[i] == 0:
        a = b = xs[i]
        fa = fb = g[i]
    else:
        a, b, fa, fb = xs[i], xs[i + 1], g[i], g[i + 1]
    xtol = (1e-9 * (hi - lo)) if xtol is None else float(xtol)
    x, fx, it, side = a, fa, 0, 0
    while a != b and it < max_iter:
        it += 1
        x = b - fb * (b - a) / (fb - fa)                 # false position
        if not (min(a, b) < x < max(a, b)) or it % 6 == 0:
            x = 0.5 * (a + b)                            # safeguard: bisect now and then
        fx = obj.batch([x])[0] - goal
        if not math.isfinite(fx):
            raise FitError(f"{name} is undefined at {key} = {x:g} ({obj.reason(x)})",
                           samples + list(obj.cache.items()))
        if fx * fb < 0:
            a, fa = b, fb
            b, fb = x, fx
            side = 0
        else:
            b, fb = x, fx
            side += 1
            if side >= 1:
                fa *= 0.5                                # Illinois: halve the stale end
        if abs(fx) <= ftol or abs(b - a) <= xtol:
            break
    x_best = b if abs(fb) <= abs(fa) else a
    f_best = (fb if x_best == b else fa) + goal
    f_near = obj.batch([a, b])
    slope = (f_near[1] - f_near[0]) / (b - a) if a != b else math.nan
    if abs(f_best - goal) > ftol and abs(b - a) > xtol:
        notes.append(f"stopped after {max_iter} iterations, {name} within "
                     f"{abs(f_best - goal):.3g} of the target")
    out = FitResult(key, name, goal, float(x_best), float(f_best), float(slope), (lo, hi),
                    converged=converged, evaluations=obj.evaluations, iterations=it,
                    samples=sorted((float(k), float(v[0])) for k, v in obj.cache.items()),
                    notes=notes)
    _resolution_shift(out, obj, base, key, name, coarse, ladder if converged else None,
                      jobs, scheduler, merge_time)
    return out


def _resolution_shift(out: FitResult, obj, base, key, name, coarse, ladder, jobs, scheduler,
                      merge_time) -> None:
    """The answer at a coarser resolution, by linearisation at the fitted value:
    x_coarse ≈ x − (f_coarse(x) − target)/slope, one run (or ladder) more."""
    if not math.isfinite(out.sensitivity) or out.sensitivity == 0:
        return
    if ladder is not None:
        from .ladders import check_ladder

        lkey, levels = check_ladder("ladder", ladder, base)
        if coarse is None:
            coarse = {lkey: levels[-1]}        # the finest level alone vs the continuum
    if coarse is None:
        coarse = {"rod.N": max(1, base.rod.N // 2)}
    cfg = base.override({key: out.value}).override(coarse)
    r = evaluate([cfg], jobs=1, merge_time=merge_time, columns=[name], **obj.limits)[0]
    f_c = float(r.get(name, math.nan))
    if math.isfinite(f_c):
        out.resolution_shift = float((f_c - out.target) / out.sensitivity)
        out.coarse = ", ".join(f"{k} = {v}" for k, v in coarse.items())
        out.evaluations += 1
