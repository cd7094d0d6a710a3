"""``rodjit fit``: the value of a key that gives an observable a target, or several keys
fitted to a table of measurements."""
from __future__ import annotations

from typing import Any

import click

from . import options
from .exits import RunFailed, UsageError
from .options import key_values

__all__ = ["fit_command"]


@click.command("fit")
@click.argument("key", metavar="KEY[,KEY...]")
@options.config_argument()
@click.option("--target", metavar="OBSERVABLE=VALUE",
              help="The observable and the value to reach, e.g. restitution_first=0.8.")
@click.option("--bracket", default="0,1000", show_default=True, metavar="LO,HI",
              help="The range of KEY searched.")
@click.option("--points", type=int, help="Values scanning the bracket in parallel [default 8].")
@click.option("--ftol", type=float, default=1e-4, show_default=True,
              help="Stop when the observable is this close to the target.")
@click.option("--converged", is_flag=True,
              help="Fit the extrapolated continuum value along --ladder.")
@click.option("--ladder", metavar="KEY=VALUES",
              help="With --converged: the resolution ladder [default rod.N = N/2, N, 2N].")
@click.option("--table", type=click.Path(dir_okay=False),
              help="Least squares of the comma-separated KEYs against a CSV of measurements "
                   "(a drop condition per row, e.g. initial.height, and measured "
                   "restitution_first and/or contact_time_first, optional sigma_<name>).")
@click.option("--compare", metavar="KEY=VALUES",
              help="With --table: fit the KEYs once per value of this key (e.g. "
                   "rod.law=aiki-kosugi,my-law) and rank the candidates by AIC.")
@options.jobs_option()
@options.force_jobs_option()
@options.scheduler_option()
@options.set_option()
@options.max_output_option("a run whose output")
@options.max_steps_option("a fixed time.dt that")
def fit_command(key: str, config: str | None, target: str | None, bracket: str,
                points: int | None, ftol: float, converged: bool, ladder: str | None,
                table: str | None, compare: str | None, jobs: int | None, force_jobs: bool,
                scheduler: str | None,
                sets: tuple[str, ...], max_output: str, max_steps: float) -> None:
    """Find the value of KEY for which an observable takes a target (--target), or fit
    several KEYs to a table of measurements (--table), with their 95 % intervals; with
    --compare, once per candidate, ranked.

    Exit codes: 0 done, 1 the target cannot be fitted (unreachable, or crossed more than
    once in the bracket: the message says where), 2 usage or configuration error.
    """
    from ..analysis.fit import FitError, fit
    from ..analysis.fit_table import compare_laws, fit_table
    from ..output.estimate import parse_size
    from ..sweeps.grid import MAX_POINTS, format_value
    from .sweep import make_grid

    result: Any
    try:
        cfg = options.base_config(config, sets)
        jobs = options.cap_jobs(jobs, scheduler, None, force_jobs)
        limits: dict[str, Any] = {"max_output": parse_size(max_output), "max_steps": max_steps}
        keys = [k.strip() for k in key.split(",") if k.strip()]
        if compare and not table:
            raise ValueError("--compare ranks fits to a table: give --table FILE.csv")
        if table:
            if target:
                raise ValueError("--target and --table exclude each other")
            if compare:       # the values as --grid and --compare of restitution read them
                grid = make_grid((compare,), max_points=MAX_POINTS)
                ckey = grid.keys[0]
                result = compare_laws(table, {f"{ckey} = {format_value(v)}":
                                              (cfg.override({ckey: v}), keys)
                                              for v in grid.values[0]},
                                      jobs=jobs, scheduler=scheduler, **limits)
            else:
                result = fit_table(keys, table, cfg, jobs=jobs, scheduler=scheduler,
                                   **limits)
        else:
            if not target:
                raise ValueError("fit needs --target OBSERVABLE=VALUE (or --table FILE.csv)")
            if len(keys) != 1:
                raise ValueError("--target fits one KEY; several keys need --table")
            name, _, value = target.partition("=")
            try:
                goal = {name.strip(): float(value)}
            except ValueError:
                raise ValueError(f"--target expects OBSERVABLE=NUMBER, got {target!r}") from None
            try:
                lo, hi = (float(b) for b in bracket.split(","))
            except ValueError:
                raise ValueError(f"--bracket expects LO,HI, got {bracket!r}") from None
            result = fit(keys[0], goal, cfg, bracket=(lo, hi), points=points, ftol=ftol,
                         converged=converged,
                         ladder=key_values("--ladder", ladder) if ladder else None,
                         jobs=jobs, scheduler=scheduler, **limits)
    except FitError as exc:
        raise RunFailed(exc) from None
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(repr(result))
    fits = getattr(result, "fits", None)
    for label, one in (fits.items() if fits else [(None, result)]):
        _fit_lines(one, label)


def _fit_lines(result: Any, label: str | None) -> None:
    """A fit's notes; a table fit's 95 % intervals and residuals too."""
    head = f"{label}: " if label else ""
    if hasattr(result, "intervals"):
        spans = ", ".join(f"{k} in [{lo:.6g}, {hi:.6g}]"
                          for k, (lo, hi) in result.intervals(0.95).items())
        click.echo(f"{head}95 % intervals: {spans}")
    for note in getattr(result, "notes", []):
        click.echo(f"{head}note: {note}")
    for row in getattr(result, "residuals", []):
        click.echo(f"  {head}row {row['row']} {row['observable']}: measured "
                   f"{row['measured']:.6g}, model {row['model']:.6g}, residual "
                   f"{row['residual']:+.3g}")
