"""``rodjit converge``: a run along a resolution ladder, with orders, extrapolated values
and the predictability time."""
from __future__ import annotations

from typing import Any

import click

from . import options
from .exits import UsageError
from .options import command_line, key_values

__all__ = ["converge_command"]


@click.command("converge")
@options.config_argument()
@click.option("--ladder", default="rod.N=25,50,100,200,400", show_default=True,
              metavar="KEY=VALUES", help="The resolution ladder, coarse to fine.")
@click.option("--also", metavar="KEY=VALUES|none",
              help="The time ladder, run at the second finest level: its contribution "
                   "to the error is reported on its own, and the predictability time of "
                   "the heights along it.  Its key must set the integrator's steps "
                   "(time.rtol; time.cfl for verlet and semi-implicit under time.control "
                   "= cfl; time.dt with fixed steps).  [default: that key, its value and "
                   "two refinements by 4; 'none': no time ladder]")
@click.option("--observable", "observables",
              default="restitution_first,contact_time_first,min_u0,max_floor_force",
              show_default=True, help="Comma-separated observables to study.")
@options.output_option("Write the study to this HDF5 file (rodjit_kind = convergence).")
@options.overwrite_option("Replace an existing convergence file (never another kind of "
                          "file).")
@options.jobs_option()
@options.force_jobs_option()
@options.scheduler_option()
@options.set_option()
@options.max_output_option("a run whose output")
@options.max_steps_option("a fixed time.dt that")
def converge_command(config: str | None, ladder: str, also: str | None, observables: str,
                     output: str | None, overwrite: bool, jobs: int | None, force_jobs: bool,
                     scheduler: str | None, sets: tuple[str, ...], max_output: str,
                     max_steps: float) -> None:
    """Run CONFIG.toml, a preset or the default along a resolution ladder and report, per
    observable, the values, the observed order of convergence, the Richardson-extrapolated
    continuum value and an error estimate; warns when the ladder is not in the asymptotic
    range and does not extrapolate values that do not settle.  The time error comes from a
    ladder over the key that sets the integrator's steps; where that ladder did not change
    the steps the time error is "not measured".  Prints the predictability time: after it,
    the runs along the time ladder disagree in the heights (chaos), so only energies and
    statistics over bounces stay meaningful.

    Exit codes: 0 done, 2 usage or configuration error (a ladder over a key that does not
    set the integrator's steps names the key that does; nothing run or written).
    """
    from ..analysis.converge import CONVERGENCE_KIND, converge
    from ..output.estimate import parse_size
    from ..output.h5files import check_output

    try:
        cfg = options.base_config(config, sets)
        jobs = options.cap_jobs(jobs, scheduler, None, force_jobs)
        limits: dict[str, Any] = {"max_output": parse_size(max_output), "max_steps": max_steps}
        if output:      # before the study runs: as every writer's output (run -o's rule)
            check_output(output, overwrite, CONVERGENCE_KIND)
        names = [o.strip() for o in observables.split(",") if o.strip()]
        result = converge(cfg, key_values("--ladder", ladder),
                          also=(False if also is not None and also.strip() == "none"
                                else key_values("--also", also) if also else None),
                          observables=names, jobs=jobs, scheduler=scheduler, **limits)
        if output:
            result.save(output, overwrite=True, command=command_line(
                "converge", config, [("--ladder", ladder), ("--also", also),
                                     ("--observable", observables), ("-o", output),
                                     ("--set", sets)], [("--overwrite", overwrite)]))
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(repr(result))
    if output:
        click.echo(f"wrote {output}")
