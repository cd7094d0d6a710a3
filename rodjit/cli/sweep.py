"""``rodjit sweep``: a configuration run at every point of a grid, into one sweep file."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Any, Callable

import click

from . import options
from .exits import EXIT_FAILED, EXIT_SIGNAL, UsageError, disk_failed, one_line
from .options import close, command_line, overrides, progress, sweep_bar
from .wording import output_exists, word

__all__ = ["sweep_command", "failed_points", "sweep_and_print", "sweep_exit"]


@click.command("sweep")
@options.config_argument()
@click.option("--grid", "grids", multiple=True, metavar="KEY=VALUES",
              help="A swept key and its values: a list (rod.mu=0,1,10,100), "
                   "linspace(a,b,n) or logspace(a,b,n) (10^a to 10^b); repeat for more "
                   "keys (the grid is their Cartesian product).")
@options.output_option("Sweep file to write [default: PRESET_sweep.h5, CONFIG_sweep.h5 or "
                       "sweep.h5].")
@options.jobs_option()
@options.scheduler_option(
    "Run the points on Dask: 'local' starts a LocalCluster of --jobs workers, "
    "tcp://HOST:PORT uses an existing cluster [default: a local process pool; also "
    "'inline': this process].")
@click.option("--save-runs", type=click.Path(file_okay=False),
              help="Also write one full run file per point into this directory.")
@options.set_option()
@click.option("--resume", is_flag=True, help="Run only the points of the sweep file that are "
                                             "missing or failed.")
@options.overwrite_option("Replace an existing sweep file (and run files in --save-runs).")
@options.force_jobs_option()
@options.quiet_option()
@options.progress_option()
@options.max_output_option("a sweep whose sweep file, or (with --save-runs) any run file,")
@options.max_steps_option("a point whose fixed time.dt")
@options.max_points_option()
@click.option("--dry-run", is_flag=True,
              help="Check everything (configuration, every point, output paths, limits), "
                   "print the points, the swept keys and the files' estimated sizes, and "
                   "write nothing.")
@click.option("--device", type=click.Choice(["cpu", "cuda", "auto"]), default="cpu",
              show_default=True,
              help="Where the points run: the CPU cores, the GPU engine (one CUDA thread per "
                   "point; needs rodjit[cuda] and a GPU), or the GPU if there is one.")
@click.option("--batch-size", type=int, default=None, metavar="N",
              help="Points per compiled call of the ensemble engine [default: about 0.3 s "
                   "of work, from the measured cost per point].")
def sweep_command(config: str | None, grids: tuple[str, ...], output: str | None,
                  jobs: int | None, scheduler: str | None, save_runs: str | None,
                  sets: tuple[str, ...], resume: bool, overwrite: bool, force_jobs: bool,
                  quiet: bool, show_progress: bool | None, max_output: str, max_steps: float,
                  max_points: float, dry_run: bool, device: str,
                  batch_size: int | None) -> None:
    """Run CONFIG.toml, a preset or the built-in default at every point of a grid, on every
    core (or a Dask cluster), into one sweep file with a summary row per point.

    Exit codes: 0 every point completed, 1 some points failed (the file lists them; --resume
    reruns them), 2 usage or configuration error (nothing written), 130/143 interrupted
    (every finished point is kept; --resume continues).
    """
    from ..sweeps.start_method import POOL_SCHEDULERS, start_server

    if scheduler in POOL_SCHEDULERS and device != "cuda" and not dry_run:
        # the workers' fork server imports rodjit on another core while this process
        # imports what the sweep needs below (``sweeps.start_method``)
        start_server()

    from ..output.h5files import OutputExists
    from ..sweeps import plan_sweep

    if dry_run and resume:
        raise UsageError("--dry-run checks a new sweep; it cannot be used with --resume")
    command = command_line(
        "sweep", config, [("--grid", grids), ("--set", sets), ("-o", output), ("--jobs", jobs),
                          ("--scheduler", scheduler), ("--save-runs", save_runs)],
        [("--resume", resume), ("--overwrite", overwrite), ("--quiet", quiet)])
    bar = progress(show_progress, quiet, sweep_bar)
    if quiet:
        quiet_dask()
    try:
        if resume:
            if overwrite:
                raise ValueError("--overwrite cannot be used with --resume")
            if config and Path(config).suffix == ".h5":
                if output and output != config:
                    raise ValueError(f"--resume continues one file; got both {config!r} and "
                                     f"-o {output!r}")
                output, config = config, None
            if not output:
                raise ValueError("--resume needs the sweep file: rodjit sweep --resume -o "
                                 "SWEEP.h5")
            cfg = grid = None
            if config or sets:          # given again: must match the file
                cfg, _ = options.load_config(config)
                cfg = cfg.override(overrides(sets)) if sets else cfg
            if grids:
                grid = make_grid(grids, max_points)
            from ..sweeps import load_sweep

            done = load_sweep(output)       # (a file whose writer was killed: recovered)
            if done.counts["completed"] == len(done.grid) and done.status == "completed":
                raise ValueError(f"{output!r} is already complete ({len(done.grid)} points); "
                                 f"nothing to resume")
        else:
            cfg, default_name = options.load_config(config)
            changes = overrides(sets)
            if changes:
                cfg = cfg.override(changes)
            grid = make_grid(grids, max_points)
            if not output:
                output = ("sweep.h5" if default_name == options.DEFAULT_OUTPUT
                          else default_name[:-3] + "_sweep.h5")
        from ..output.estimate import parse_size

        limits: dict[str, Any] = {"max_output": parse_size(max_output), "max_steps": max_steps,
                  "max_points": max_points}
        if dry_run:
            from ..sweeps.executors import check_scheduler
            from ..sweeps.run_sweep import check_batch_size, check_jobs

            check_jobs(jobs)
            check_batch_size(batch_size)
            check_scheduler(scheduler)
            plan = plan_sweep(cfg, grid, output=output, save_runs=save_runs,
                              overwrite=overwrite, **limits)
            click.echo(plan.report())
            return
        jobs = options.cap_jobs(jobs, scheduler, grid, force_jobs, quiet)
    except OutputExists as exc:
        raise UsageError(output_exists(exc, "--resume")) from None
    except ValueError as exc:
        raise UsageError(exc) from None
    table = sweep_and_print(cfg, grid, output, jobs=jobs, scheduler=scheduler,
                            save_runs=save_runs, resume=resume, overwrite=overwrite, bar=bar,
                            quiet=quiet, command=command, device=device,
                            batch_size=batch_size, limits=limits)
    sweep_exit(table, output)


def sweep_and_print(cfg: Any, grid: Any, output: str, *, jobs: int | None,
                    scheduler: str | None, bar: Any, quiet: bool, command: str,
                    device: str | None, limits: dict[str, Any], save_runs: str | None = None,
                    resume: bool = False, overwrite: bool = False,
                    batch_size: int | None = None,
                    report: Callable[[Any], str] | None = None) -> Any:
    """Run a sweep as the command line does (``rodjit sweep``, ``rodjit restitution``):
    signals held from its end on, an interruption or a failure printed with the table and
    its exit code, a bad argument a usage error; then print the headline and
    ``report(table)`` (default: the sweep's table) unless ``quiet``, and return the table.
    ``sweep_exit`` ends the command."""
    from ..driver.signals import hold_on_exit
    from ..output.h5files import OutputExists
    from ..sweeps import SweepFailed, SweepInterrupted, sweep

    text = report or (lambda t: t.report(max_rows=40))
    try:
        with hold_on_exit():      # from the end of the sweep on, signals wait (see below)
            table = sweep(cfg, grid, output=output, jobs=jobs, scheduler=scheduler,
                          save_runs=save_runs, resume=resume, overwrite=overwrite,
                          progress=bar, command=command, device=device,
                          batch_size=batch_size, **limits)
    except OutputExists as exc:
        raise UsageError(output_exists(exc, "--resume")) from None
    except SweepInterrupted as exc:
        close(bar)
        if not quiet:
            click.echo(exc.table.headline())
            if exc.table.status == "completed":
                click.echo(text(exc.table))
        click.echo(word(exc), err=True)
        sys.exit(EXIT_SIGNAL + (exc.signum or 2))
    except SweepFailed as exc:
        close(bar)
        if not quiet:
            click.echo(exc.table.headline())
            click.echo(text(exc.table))
        click.echo(f"error: {exc}", err=True)
        sys.exit(EXIT_FAILED)
    except ValueError as exc:
        raise UsageError(exc) from None
    except OSError as exc:          # the disk refused a write (the sweep file, a run file)
        close(bar)
        disk_failed(exc)
    close(bar)
    if not quiet:
        click.echo(table.headline())
        click.echo(text(table))
    return table


def sweep_exit(table: Any, output: str) -> None:
    """End a sweep's command: a signal that came after the file was closed, while the table
    was printed, exits with its code; failed points exit 1 with one line on them."""
    import signal

    from ..driver.signals import pending_signal

    late = pending_signal()
    if late is not None:
        click.echo(f"interrupted by {signal.Signals(late).name} after the last point; "
                   f"{output!r} is complete", err=True)
        sys.exit(EXIT_SIGNAL + late)
    if table.counts["failed"]:
        click.echo(f"Error: {failed_points(table, output)}", err=True)   # even with -q
        sys.exit(EXIT_FAILED)


def failed_points(table: Any, output: str) -> str:
    """One line on the failed points of a sweep: how many, the first one's message.

    Parameters
    ----------
    table : SweepTable
        The sweep's table.
    output : str
        The sweep file, for the command that runs them again.

    Returns
    -------
    str
        The line, without ``Error:``.
    """
    status = table.columns["status"]
    failed = [i for i, s in enumerate(status) if s == "failed"]
    first = str(table.columns.get("message", [""] * len(status))[failed[0]]) if failed else ""
    return one_line(f"{len(failed)} of {len(status)} points failed (point {failed[0]}: "
                    f"{first or 'no message'}); 'rodjit sweep --resume -o {output}' runs them "
                    f"again")


def quiet_dask() -> None:
    """--quiet: Dask's and distributed's own log lines stay off stderr (here and in the
    processes they start, which read the environment)."""
    import logging
    import os

    os.environ["DASK_LOGGING__DISTRIBUTED"] = "critical"
    for name in ("distributed", "dask", "tornado", "bokeh"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def make_grid(grid_options: tuple[str, ...], max_points: float) -> Any:
    """The Grid of the --grid options, sized (--max-points) before it is made."""
    from ..sweeps.grid import Grid, parse_grid_option

    return Grid.from_spec(parse_grid_option(grid_options), max_points=max_points)
