"""``rodjit restitution``: restitution and contact time against impact speed, one line per
compared value, as a sweep file, a table, a CSV file and a figure."""
from __future__ import annotations

import click

from . import options
from .exits import UsageError
from .files import check_picture
from .options import command_line, overrides, progress, sweep_bar
from .sweep import make_grid, quiet_dask, sweep_and_print, sweep_exit

__all__ = ["restitution_command"]


@click.command("restitution")
@options.config_argument()
@click.option("--speeds", metavar="VALUES",
              help="Impact speeds in m/s: a list (2,4,8), linspace(a,b,n) or logspace(a,b,n).")
@click.option("--heights", metavar="VALUES",
              help="Drop heights of the bottom from rest in m, instead of --speeds (impact "
                   "speed sqrt(2|g|h)).")
@click.option("--compare", "compares", multiple=True, metavar="KEY=VALUES",
              help="A key whose values are the curve's lines, e.g. rod.mu=10,100,1000 "
                   "(repeat: one line per combination).")
@click.option("--start-height", type=float, default=0.01, show_default=True,
              help="Where each point's bottom starts, in m: it starts with the velocity a "
                   "free fall needs to meet the floor at its impact speed.")
@options.output_option("Sweep file to write [default: PRESET_restitution.h5, "
                       "CONFIG_restitution.h5 or restitution.h5].")
@click.option("--csv", "csv_path", type=click.Path(dir_okay=False),
              help="Also write the curve's table as CSV.")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False),
              help="Also draw restitution against impact speed into this image (PNG, PDF or "
                   "SVG), a point without lift-off marked as such.")
@options.set_option()
@options.jobs_option()
@options.scheduler_option()
@options.overwrite_option("Replace existing output files (the sweep file, --csv, --plot).")
@options.force_jobs_option()
@options.quiet_option()
@options.progress_option()
@options.max_output_option("a sweep whose sweep file")
@options.max_steps_option("a point whose fixed time.dt")
@options.max_points_option()
@click.option("--device", type=click.Choice(["cpu", "cuda", "auto"]), default="cpu",
              show_default=True, help="Where the points run, as for rodjit sweep.")
def restitution_command(config: str | None, speeds: str | None, heights: str | None,
                        compares: tuple[str, ...], start_height: float, output: str | None,
                        csv_path: str | None, plot_path: str | None, sets: tuple[str, ...],
                        jobs: int | None, scheduler: str | None, overwrite: bool,
                        force_jobs: bool, quiet: bool, show_progress: bool | None,
                        max_output: str, max_steps: float, max_points: float,
                        device: str) -> None:
    """Restitution and contact time of the first bounce against impact speed, for
    CONFIG.toml, a preset or the default, one line per value of each --compare key: a
    sweep over initial.impact_speed (its file reads as any sweep file: rodjit info, rodjit
    plot --x initial.impact_speed, rodjit sweep --resume).  A rod that never leaves the
    floor has restitution 0 and contact time inf ("no lift-off"); a contact still open at
    time.t_end has none ("open": run longer).

    Exit codes: 0 every point completed, 1 some points failed, 2 usage or configuration
    error (nothing written), 130/143 interrupted (--resume of rodjit sweep continues).
    """
    from ..analysis.restitution import CURVE_COLUMNS, SPEED_KEY, curve_grid, curve_report
    from ..output.estimate import parse_size
    from ..sweeps.grid import Grid

    command = command_line(
        "restitution", config,
        [("--speeds", speeds), ("--heights", heights), ("--compare", compares),
         ("--start-height", start_height), ("--set", sets), ("-o", output),
         ("--csv", csv_path), ("--plot", plot_path), ("--jobs", jobs),
         ("--scheduler", scheduler)], [("--overwrite", overwrite), ("--quiet", quiet)])
    bar = progress(show_progress, quiet, sweep_bar)
    if quiet:
        quiet_dask()
    try:
        cfg, default_name = options.load_config(config)
        if sets:
            cfg = cfg.override(overrides(sets))
        compare = make_grid(compares, max_points) if compares else None
        base, spec = curve_grid(cfg, speeds, heights,
                                dict(zip(compare.keys, compare.values)) if compare else None,
                                start_height)
        grid = Grid.from_spec(spec, max_points=max_points)
        if not output:
            output = ("restitution.h5" if default_name == options.DEFAULT_OUTPUT
                      else default_name[:-3] + "_restitution.h5")
        limits = {"max_output": parse_size(max_output), "max_steps": max_steps,
                  "max_points": max_points}
        jobs = options.cap_jobs(jobs, scheduler, grid, force_jobs, quiet)
    except ValueError as exc:
        raise UsageError(exc) from None
    if csv_path:
        check_picture(csv_path, overwrite, output, option="--csv", what="a CSV file")
    if plot_path:
        check_picture(plot_path, overwrite, output, option="--plot")
    table = sweep_and_print(base, grid, output, jobs=jobs, scheduler=scheduler, bar=bar,
                            quiet=quiet, command=command, device=device, limits=limits,
                            overwrite=overwrite, report=curve_report)
    if csv_path:
        keys = [k for k in grid.keys if k != SPEED_KEY]
        table.to_csv(csv_path, [*keys, SPEED_KEY, "status", *CURVE_COLUMNS, "message"],
                     overwrite=overwrite)
        if not quiet:
            click.echo(f"wrote {csv_path}")
    if plot_path:
        from .plot import plot_sweep

        plot_sweep(output, plot_path, "restitution", {"x": SPEED_KEY}, overwrite=overwrite)
    sweep_exit(table, output)
