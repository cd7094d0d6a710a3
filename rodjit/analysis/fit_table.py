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
from typing import TYPE_CHECKING, Any, Mapping, Sequence

import numpy as np

from .evaluate import evaluate

if TYPE_CHECKING:
    from ..config import Config

__all__ = ["fit_table", "TableFit", "read_measurements"]


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
        raise ValueError(f"{len(targets)} measurements cannot determine {len(keys)} keys")
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
                       max_output=max_output, max_steps=max_steps)
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
                    cov.tolist(), res_rows, chi2, it, runs_total, converged, notes)
