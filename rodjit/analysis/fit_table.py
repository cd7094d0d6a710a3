"""Least squares of several configuration keys against a table of measurements.

Each row of the table is a drop condition (any configuration keys, e.g.
``initial.height`` or ``initial.velocity``) and measured observables (columns named as
``rodjit.analysis.OBSERVABLES``, e.g. ``restitution_first``, ``contact_time_first``), with
optional uncertainties in ``sigma_<observable>`` columns.  Levenberg–Marquardt on the
weighted residuals (model − measured)/σ, the Jacobian by forward differences with every
run of one iteration evaluated in one parallel batch; the parameter covariance is
(JᵀJ)⁻¹, scaled by the residual variance χ²/(m − p) when no σ is given.
"""
from __future__ import annotations

import csv
import math
import os
from dataclasses import asdict, dataclass, field
from statistics import NormalDist
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from .evaluate import evaluate
from .roots import increasing_root

if TYPE_CHECKING:
    from ..config import Config

__all__ = ["fit_table", "TableFit", "read_measurements", "compare_laws", "LawComparison",
           "t_quantile"]


def t_quantile(level: float, dof: int) -> float:
    """The two-sided quantile q of Student's t with ``dof`` degrees of freedom:
    P(|T| ≤ q) = ``level``.  The distribution function by the finite series of Abramowitz
    & Stegun 26.7.3 (exact for a whole number of degrees of freedom), inverted by
    bisection; tests/test_calibration.py compares it with SciPy's.

    Parameters
    ----------
    level : float
        In (0, 1).
    dof : int
        At least 1.

    Returns
    -------
    float
    """
    def inside(t: float) -> float:          # P(|T| <= t)
        theta = math.atan(t / math.sqrt(dof))
        c, sn = math.cos(theta), math.sin(theta)
        if dof % 2:
            term, total = c, (c if dof > 1 else 0.0)
            for k in range(3, dof - 1, 2):
                term *= (k - 1) / k * c * c
                total += term
            return 2.0 / math.pi * (theta + sn * total)
        term = total = 1.0
        for k in range(2, dof - 1, 2):
            term *= (k - 1) / k * c * c
            total += term
        return sn * total

    hi = 1.0
    while inside(hi) < level:
        hi *= 2.0
    return increasing_root(inside, level, 0.0, hi, rtol=1e-13)


def read_measurements(path) -> list[dict]:
    """Rows of a CSV file: configuration keys and observables as floats.

    Parameters
    ----------
    path : str or os.PathLike
        A CSV file whose header names configuration keys, observables and
        ``sigma_<observable>`` columns; empty cells are left out of their row.

    Returns
    -------
    list of dict
        One dict per row, column name -> float.

    Raises
    ------
    ValueError
        The file is missing or empty, a column is unknown, a row has more cells than the
        header has columns, or a cell is not a number (naming the line and column).
    """
    from ..config import MissingFile, valid_keys
    from .observables import OBSERVABLES

    try:
        with open(path, newline="") as fh:
            reader = csv.DictReader(fh)
            rows = list(reader)
            header = reader.fieldnames or []
    except FileNotFoundError:
        raise MissingFile(path, "measurement table ") from None
    keys = set(valid_keys())
    known = set(OBSERVABLES) | {f"sigma_{o}" for o in OBSERVABLES} | keys
    bad = [h for h in header if h.strip() not in known]
    if bad:
        raise ValueError(f"measurement table {str(path)!r}: unknown column {bad[0]!r} "
                         f"(configuration keys, observables, sigma_<observable>)")
    if not rows:
        raise ValueError(f"measurement table {str(path)!r} has no rows")
    out = []
    for n, row in enumerate(rows, start=2):
        if None in row:       # csv.DictReader's key for the cells past the header's columns
            raise ValueError(f"measurement table {str(path)!r} line {n}: "
                             f"{len(header) + len(row[None])} cells, more than the "
                             f"{len(header)} columns of the header")
        parsed = {}
        for k, v in row.items():
            k = k.strip()
            if v is None or v.strip() == "":
                continue
            try:
                parsed[k] = float(v)
            except ValueError:
                raise ValueError(f"measurement table {str(path)!r} line {n}: {k} = {v!r} "
                                 f"is not a number") from None
        out.append(parsed)
    return out


@dataclass
class TableFit:
    """The answer of ``fit_table``: fitted ``values`` of ``keys`` with standard ``errors``.

    Attributes
    ----------
    keys : list of str
        The fitted configuration keys.
    values : list of float
        Their fitted values, in the order of ``keys``.
    errors : list of float
        Standard errors, the square roots of the covariance's diagonal.
    covariance : list of list of float
        (JᵀJ)⁻¹, scaled by χ²/(m − p) when the table gives no σ.
    residuals : list of dict
        Per row and observable: ``row`` (from 1), ``observable``, ``measured``, ``model``
        and ``residual`` (model − measured).
    chi2 : float
        Sum of the squared weighted residuals at the answer.
    iterations : int
        Levenberg–Marquardt iterations.
    evaluations : int
        Runs made (every row at every parameter vector tried, Jacobians included).
    converged : bool
        Whether the relative change of χ² or of the parameters fell below ``rtol`` (or no
        step reduced χ² further).
    notes : list of str
        What the caller should know (a singular Jacobian, no residual variance).
    weighted : bool
        Whether the table gave the measurements' σ (the errors then follow from them;
        else from the scatter of the residuals).
    dof : int
        Degrees of freedom m − p: measurements less fitted keys.
    """

    keys: list
    values: list
    errors: list
    covariance: list
    residuals: list
    chi2: float
    iterations: int
    evaluations: int
    converged: bool
    notes: list = field(default_factory=list)
    weighted: bool = True
    dof: int = 0

    def intervals(self, level: float = 0.95) -> dict[str, tuple[float, float]]:
        """Confidence intervals of the fitted keys: value ± q·error, from the Jacobian's
        covariance (the linearisation of the model at the answer: exact for a model
        linear in the keys, and what the coverage tests measure for rodjit's models at
        the measurement errors of a drop test).  q is the normal quantile where the table
        gave σ (known errors), Student's t quantile with ``dof`` degrees of freedom where
        the errors come from the residuals' scatter.

        Parameters
        ----------
        level : float
            The confidence level, in (0, 1).

        Returns
        -------
        dict
            Key -> ``(low, high)``.
        """
        if not 0.0 < level < 1.0:
            raise ValueError(f"level = {level!r} is out of range (0 < level < 1)")
        q = (NormalDist().inv_cdf(0.5 + level / 2) if self.weighted or self.dof < 1
             else t_quantile(level, self.dof))
        return {k: (v - q * e, v + q * e) for k, v, e in zip(self.keys, self.values,
                                                             self.errors)}

    def __repr__(self) -> str:
        parts = ", ".join(f"{k} = {v:.6g} ± {e:.2g}" for k, v, e in
                          zip(self.keys, self.values, self.errors))
        return f"TableFit({parts}; chi2 = {self.chi2:.3g}, {self.evaluations} runs)"

    def to_dict(self) -> dict:
        """Every attribute as plain values (``dataclasses.asdict``; JSON-ready).

        Returns
        -------
        dict
        """
        return asdict(self)


def fit_table(keys: Sequence[str], table: str | os.PathLike[str] | Sequence[Mapping[str, Any]],
              config: Config | None = None, *, start: Mapping[str, float] | None = None,
              bounds: Mapping[str, tuple[float, float]] | None = None,
              jobs: int | None = None, scheduler: str | None = None, max_iter: int = 20,
              rtol: float = 1e-6, step: float = 1e-3,
              merge_time: float | None = None,
              max_output: float | None = None, max_steps: float | None = None) -> TableFit:
    """Least-squares values of ``keys`` that reproduce a table of measurements.

    Levenberg–Marquardt on the weighted residuals (model − measured)/σ; each iteration's
    runs (every row, at the trial point and its Jacobian's steps) go to the executors as
    one parallel batch.

    Parameters
    ----------
    keys : sequence of str
        Real-valued configuration keys to fit, e.g. ``["rod.mu", "floor.kappa_b"]``.
    table : str, os.PathLike or list of dict
        A CSV path (read by ``read_measurements``) or rows already read: per row the drop
        condition (configuration keys), measured observables and optional
        ``sigma_<observable>`` uncertainties.
    config : Config or None
        The base configuration; None is ``Config()``.
    start : dict, optional
        Key -> starting value (default: the values in ``config``).
    bounds : dict, optional
        Key -> ``(lo, hi)`` (default ``(0, inf)``).
    jobs : int, optional
        Worker processes, as for ``rodjit.sweep``.
    scheduler : str, optional
        Executor, as for ``rodjit.sweep``.
    max_iter : int
        Most Levenberg–Marquardt iterations.
    rtol : float
        Converged when χ² or the parameters change by less than this, relatively.
    step : float
        Relative forward-difference step of the Jacobian.
    merge_time : float, optional
        The flight time τ [s] that ends a bounce (``records.observables.flight_groups``;
        default π h/c, the bounce table's).
    max_output, max_steps : float, optional
        The limits of a new run (``rodjit.run_to_file``), checked on every run before it
        runs (default: the same defaults).

    Returns
    -------
    TableFit

    Raises
    ------
    ValueError
        No keys, a key that is not real-valued, fewer measurements than keys, a σ <= 0,
        a bad table, or an observable undefined for a row (naming the row).
    """
    from ..config import Config
    from .observables import OBSERVABLES

    base = Config() if config is None else config
    rows = read_measurements(table) if not isinstance(table, list) else table
    keys = list(keys)
    if not keys:
        raise ValueError("fit_table needs at least one key to fit")
    for k in keys:
        base.override({k: base.get(k)})
        if not isinstance(base.get(k), float):
            raise ValueError(f"{k} is not a real-valued key; fit needs continuous parameters")
    targets = [(i, o) for i, r in enumerate(rows) for o in OBSERVABLES if o in r]
    if len(targets) < len(keys):
        raise ValueError(f"the measurement table holds {len(targets)} measurement"
                         f"{'' if len(targets) == 1 else 's'} for {len(keys)} keys "
                         f"({', '.join(keys)}): it needs at least {len(keys)} (one per key "
                         f"fitted)")
    for i, o in targets:
        for name in (o, f"sigma_{o}"):
            if name in rows[i] and not math.isfinite(float(rows[i][name])):
                raise ValueError(f"measurement table row {i + 1}: {name} = {rows[i][name]!r} "
                                 f"is out of range (a finite number)")
    sigma = np.array([rows[i].get(f"sigma_{o}", 1.0) for i, o in targets])
    if np.any(sigma <= 0):
        raise ValueError("sigma_<observable> columns must be > 0")
    weighted = any(f"sigma_{o}" in rows[i] for i, o in targets)
    measured = np.array([rows[i][o] for i, o in targets])
    x = np.array([float((start or {}).get(k, base.get(k))) for k in keys])
    lo = np.array([(bounds or {}).get(k, (0.0, math.inf))[0] for k in keys], float)
    hi = np.array([(bounds or {}).get(k, (0.0, math.inf))[1] for k in keys], float)
    conds = [{k: v for k, v in r.items() if k not in OBSERVABLES and not k.startswith("sigma_")}
             for r in rows]
    runs_total = 0

    def configs(theta):
        over = dict(zip(keys, (float(t) for t in theta)))
        return [base.override({**c, **over}) for c in conds]

    def residual(results):
        model = np.array([results[i].get(o, math.nan) for i, o in targets])
        return (model - measured) / sigma

    def batch(thetas):
        nonlocal runs_total
        cfgs = [c for th in thetas for c in configs(th)]
        res = evaluate(cfgs, jobs=jobs, scheduler=scheduler, merge_time=merge_time,
                       max_output=max_output, max_steps=max_steps,
                       columns=sorted({o for _, o in targets}))
        runs_total += len(cfgs)
        n = len(rows)
        out = [residual(res[j * n:(j + 1) * n]) for j in range(len(thetas))]
        for j, r in enumerate(out):
            if not np.all(np.isfinite(r)):
                k = int(np.flatnonzero(~np.isfinite(r))[0])
                i, o = targets[k]
                raise ValueError(f"{o} is undefined for row {i + 1} at "
                                 f"{dict(zip(keys, thetas[j]))}: "
                                 f"{res[j * n + i].get('reason', '')}")
        return out

    def with_jacobian(theta):
        hs = step * np.maximum(np.abs(theta), 1e-3)
        hs = np.where(theta + hs > hi, -hs, hs)          # stay inside the bounds
        thetas = [theta] + [theta + h * e for h, e in zip(hs, np.eye(len(theta)))]
        r = batch(thetas)
        J = np.column_stack([(r[j + 1] - r[0]) / hs[j] for j in range(len(theta))])
        return r[0], J

    lam = 1e-3
    r, J = with_jacobian(x)
    chi2 = float(r @ r)
    it, converged, notes = 0, False, []
    while it < max_iter:
        it += 1
        A = J.T @ J
        g = J.T @ r
        accepted = False
        for _ in range(8):
            try:
                dx = -np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-300), g)
            except np.linalg.LinAlgError:
                lam *= 10
                continue
            x_new = np.clip(x + dx, lo, hi)
            r_new, J_new = with_jacobian(x_new)
            chi2_new = float(r_new @ r_new)
            if chi2_new < chi2:
                step_rel = np.max(np.abs(x_new - x) / np.maximum(np.abs(x), 1e-12))
                x, r, J, lam = x_new, r_new, J_new, max(lam / 10, 1e-12)
                accepted = True
                if chi2 - chi2_new <= rtol * max(chi2, 1e-300) or step_rel <= rtol:
                    converged = True
                chi2 = chi2_new
                break
            lam *= 10
        if not accepted:
            converged = True         # no descent left: at the minimum to the step's accuracy
            notes.append("no step reduced chi2 further")
            break
        if converged:
            break
    m, p = len(measured), len(keys)
    try:
        cov = np.linalg.inv(J.T @ J)
    except np.linalg.LinAlgError:
        cov = np.full((p, p), math.inf)
        notes.append("the Jacobian is singular: the keys are not all determined by the data")
    if not weighted:
        if m > p:
            cov = cov * chi2 / (m - p)
        else:
            notes.append("as many measurements as keys: no residual variance, errors "
                         "assume unit measurement errors")
    errors = np.sqrt(np.clip(np.diag(cov), 0, None))
    res_rows = [{"row": i + 1, "observable": o, "measured": float(measured[k]),
                 "model": float(measured[k] + r[k] * sigma[k]),
                 "residual": float(r[k] * sigma[k])} for k, (i, o) in enumerate(targets)]
    return TableFit(keys, [float(v) for v in x], [float(e) for e in errors],
                    cov.tolist(), res_rows, chi2, it, runs_total, converged, notes,
                    weighted, m - p)


@dataclass
class LawComparison:
    """The answer of ``compare_laws``: each candidate's best fit to one table, ranked.

    The ranking is by Akaike's information criterion: AIC = χ² + 2p for a table with σ
    (χ² is −2 log L up to a constant for Gaussian errors), m·log(χ²/m) + 2p without (σ
    estimated from the residuals); p fitted keys, m measurements.  Lower is better; a
    difference under 2 does not tell two candidates apart.

    Attributes
    ----------
    fits : dict
        Candidate label -> its ``TableFit``.
    """

    fits: dict

    def aic(self, label: str) -> float:
        """The candidate's AIC (class docstring).

        Parameters
        ----------
        label : str
            A candidate.

        Returns
        -------
        float
        """
        f = self.fits[label]
        p = len(f.keys)
        m = f.dof + p
        if f.weighted:
            return f.chi2 + 2 * p
        return m * math.log(max(f.chi2, 1e-300) / m) + 2 * p

    def ranking(self) -> list[str]:
        """The candidates' labels, best (lowest AIC) first."""
        return sorted(self.fits, key=self.aic)

    @property
    def best(self) -> str:
        """The label of the candidate that reproduces the table best."""
        return self.ranking()[0]

    def __repr__(self) -> str:
        rank = self.ranking()
        a0 = self.aic(rank[0])
        lines = ["LawComparison (best first; ΔAIC < 2 does not tell candidates apart)"]
        for label in rank:
            f = self.fits[label]
            values = ", ".join(f"{k} = {v:.6g} ± {e:.2g}" for k, v, e in
                               zip(f.keys, f.values, f.errors))
            lines.append(f"  {label}: chi2 = {f.chi2:.4g}, ΔAIC = {self.aic(label) - a0:.3g}"
                         f"; {values}")
        return "\n".join(lines)


def compare_laws(table: str | os.PathLike[str] | Sequence[Mapping[str, Any]],
                 candidates: Mapping[str, tuple], **options: Any) -> LawComparison:
    """Fit each candidate law to the same table and rank them (``LawComparison``): which
    law, at its best parameters, reproduces the measurements.

    Parameters
    ----------
    table : str, os.PathLike or list of dict
        As for ``fit_table``.
    candidates : mapping
        Label -> ``(config, keys)`` or ``(config, keys, start)``: the configuration that
        selects the law (e.g. ``rod.law``, ``rod.mu``), the keys fitted, and optionally
        their starting values.
    **options
        The other arguments of ``fit_table`` (``bounds``, ``jobs``, ``scheduler``,
        ``max_iter``, ...), for every candidate.

    Returns
    -------
    LawComparison

    Raises
    ------
    ValueError
        No candidates, a candidate that is not ``(config, keys[, start])``, or what
        ``fit_table`` raises (naming the candidate).
    """
    if not candidates:
        raise ValueError("compare_laws needs at least one candidate")
    rows = read_measurements(table) if not isinstance(table, list) else table
    fits = {}
    for label, cand in candidates.items():
        if not isinstance(cand, tuple) or len(cand) not in (2, 3):
            raise ValueError(f"candidate {label!r}: give (config, keys) or (config, keys, "
                             f"start), not {cand!r}")
        config, keys, start = (*cand, None) if len(cand) == 2 else cand
        try:
            fits[label] = fit_table(keys, rows, config, start=start, **options)
        except ValueError as exc:
            raise ValueError(f"candidate {label!r}: {exc}") from None
    return LawComparison(fits)
