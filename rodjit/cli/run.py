"""``rodjit run``: a configuration run, or a run file resumed, streamed to HDF5."""
from __future__ import annotations

import sys
import warnings
from typing import Any

import click

from . import options
from .exits import EXIT_SIGNAL, RunFailed, UsageError, disk_failed
from .options import close, command_line, overrides, progress, run_bar
from .say import say_warning
from .wording import output_exists, word

__all__ = ["run_command", "say_run"]


@click.command("run", cls=options.verb_saying_where({
    "--device": "devices are for sweeps: 'rodjit sweep --device cuda' runs a grid's points "
                "on the GPU; a run runs on the CPU"}))
@options.config_argument()
@options.output_option(f"HDF5 file to write [default: PRESET.h5, CONFIG.h5 or "
                       f"{options.DEFAULT_OUTPUT}]")
@options.set_option()
@click.option("--t-end", type=float, help="End time (overrides time.t_end; with --resume it "
                                          "extends the run).")
@options.overwrite_option()
@click.option("--resume", is_flag=True, help="Continue the run in FILE.h5 (given as argument "
                                             "or -o) from its checkpoint.")
@options.quiet_option()
@click.option("--flush-interval", type=float, default=2.0, show_default=True,
              metavar="SECONDS", help="Wall time between checkpoints.")
@options.progress_option()
@options.max_output_option("a run whose file")
@options.max_steps_option("a fixed time.dt that")
@click.option("--dry-run", is_flag=True,
              help="Check everything (configuration, output path, limits), print the rows, "
                   "file size, memory and steps the run would write, and write nothing.")
def run_command(config: str | None, output: str | None, sets: tuple[str, ...],
                t_end: float | None, overwrite: bool, resume: bool, quiet: bool,
                flush_interval: float, show_progress: bool | None, max_output: str,
                max_steps: float, dry_run: bool) -> None:
    """Run CONFIG.toml, a preset (see 'rodjit presets') or the built-in default, streaming
    snapshots, diagnostics, contact episodes and bounces to an HDF5 file.

    Ctrl-C or SIGTERM stops at once with a checkpoint; 'rodjit run --resume FILE.h5'
    continues exactly where the run stopped.
    """
    from ..config import ModelWarning
    from ..driver.files import OutputExists, RunInterrupted, plan_run, resume_file, run_to_file
    from ..driver.run import SimulationError

    if dry_run:
        if resume:
            raise UsageError("--dry-run checks a new run; it cannot be used with --resume")
        try:
            from ..output.estimate import parse_size

            cfg, default_name = options.load_config(config)
            cfg = cfg.override(overrides(sets)) if sets else cfg
            plan = plan_run(cfg, output or default_name, overwrite=overwrite, t_end=t_end,
                            max_output=parse_size(max_output), max_steps=max_steps,
                            flush_interval=flush_interval)
        except OutputExists as exc:
            raise UsageError(output_exists(exc)) from None
        except ValueError as exc:
            raise UsageError(exc) from None
        click.echo(plan.report())
        for text in plan.config.warnings():   # as the run would say them
            say_warning(text)
        return
    command = command_line(
        "run", config, [("-o", output), ("--set", sets),
                        ("--t-end", repr(t_end) if t_end is not None else None)],
        [("--resume", resume), ("--overwrite", overwrite), ("--quiet", quiet)])
    bar = None
    try:
        if resume:
            bar = progress(show_progress, quiet, run_bar)
            if sets:
                raise ValueError("--set cannot be used with --resume: the configuration is in "
                                 "the file (only --t-end can change)")
            if overwrite:
                raise ValueError("--overwrite cannot be used with --resume")
            if config and output and config != output:
                raise ValueError(f"--resume continues one file; got both {config!r} and "
                                 f"-o {output!r}")
            target = config or output
            if not target:
                raise ValueError("--resume needs the file to continue: rodjit run --resume "
                                 "FILE.h5")
            from ..output.estimate import parse_size

            summary = resume_file(target, t_end=t_end, command=command, progress=bar,
                                  flush_interval=flush_interval,
                                  max_output=parse_size(max_output), max_steps=max_steps)
        else:
            cfg, default_name = options.load_config(config)
            changes = overrides(sets)
            if changes:
                cfg = cfg.override(changes)
            bar = progress(show_progress, quiet, run_bar, cfg)
            from ..output.estimate import parse_size

            with warnings.catch_warnings():   # said below as one line each on stderr
                warnings.simplefilter("ignore", ModelWarning)
                summary = run_to_file(cfg, output or default_name, overwrite=overwrite,
                                      command=command, progress=bar, t_end=t_end,
                                      flush_interval=flush_interval,
                                      max_output=parse_size(max_output), max_steps=max_steps)
    except OutputExists as exc:
        raise UsageError(output_exists(exc)) from None
    except RunInterrupted as exc:
        close(bar)
        if not quiet:           # its warnings in the report: stderr is the one line below
            click.echo(exc.summary.report())
        click.echo(word(exc), err=True)
        sys.exit(EXIT_SIGNAL + exc.signum)
    except SimulationError as exc:
        close(bar)
        failed_summary = getattr(exc, "summary", None)
        if not quiet and failed_summary is not None:
            click.echo(failed_summary.report())   # (as above)
        raise RunFailed(exc) from None
    except ValueError as exc:       # configuration, path and file errors: nothing written
        raise UsageError(exc) from None
    except OSError as exc:          # the disk failed us during the run (full, removed, ...)
        close(bar)
        disk_failed(exc)
    close(bar)
    say_run(summary, quiet)


def say_run(summary: Any, quiet: bool) -> None:
    """A run's warnings on stderr, once each (what the results do not mean); then its
    report on stdout without them (said once).  With --quiet, neither.

    Parameters
    ----------
    summary : RunSummary
        What the run (or its resumption) returned.
    quiet : bool
        --quiet: nothing (``say_warning`` says no warning under it).
    """
    for text in summary.warnings:
        say_warning(text)
    if not quiet:
        if not hasattr(summary, "facts"):
            click.echo(summary.report())
            return
        facts = summary.facts()
        facts.warnings = ()
        click.echo(facts.report())
