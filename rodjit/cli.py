"""The ``rodjit`` command: a thin layer over ``run_to_file``, ``resume_file``, the summary
and the plots.

``info`` and ``plot`` dispatch on a file's ``rodjit_kind`` root attribute (``run`` or
``sweep``): ``info`` prints ``reports.info`` (one path for both kinds), ``plot`` checks that
the figure asked for belongs to the file's kind.  Each command imports what it runs when it
runs, so ``rodjit --help`` and usage errors do not wait for NumPy, h5py and Numba to load.
Exit codes: 0 done, 1 the run failed (or a sweep point did), 2 usage or configuration error
(nothing written), 130/143 interrupted by SIGINT/SIGTERM (checkpoint written).
"""
from __future__ import annotations

import contextlib
import shlex
import sys
import warnings
from pathlib import Path

import click

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_SIGNAL = 128          # + the signal's number: 130 SIGINT, 143 SIGTERM
# the table of exit codes, as ``rodjit --help`` and docs/reference/cli.md print it
EXIT_CODES = {
    EXIT_OK: "done (every run or point completed)",
    EXIT_FAILED: "a run, a sweep point or a fit failed, or the disk refused a write (the "
                 "file keeps its last checkpoint and says why)",
    EXIT_USAGE: "usage, configuration, path or file error: one line, nothing written",
    EXIT_SIGNAL + 2: "stopped by SIGINT (a checkpoint is written; --resume continues)",
    EXIT_SIGNAL + 15: "stopped by SIGTERM (likewise)",
}
DEFAULT_OUTPUT = "default.h5"


def _quiet_disk_errors() -> None:
    """h5py's reports of releasing files the disk refused say nothing the one-line error
    does not (``output.h5files.quiet_disk_errors``)."""
    from .output.h5files import quiet_disk_errors

    quiet_disk_errors()


_quiet_disk_errors()


class UsageError(click.ClickException):
    """One line on stderr, exit code 2; raised before anything is written."""

    exit_code = EXIT_USAGE

    def __init__(self, message):
        super().__init__(one_line(message))


class RunFailed(click.ClickException):
    exit_code = EXIT_FAILED

    def __init__(self, message):
        super().__init__(one_line(message))


_said: set[str] | None = None     # the warnings said by the running command


def say_warning(text: str) -> None:
    """One line ``warning: TEXT`` on stderr, once per text while a command runs."""
    text = one_line(text)
    if _said is not None:
        if text in _said:
            return
        _said.add(text)
    click.echo(f"warning: {text}", err=True)


@contextlib.contextmanager
def _warnings_as_lines():
    """While a command runs, every warning it issues (its own, a library's, a worker's
    passed on by a sweep) is said by ``say_warning``: one line, once, with neither the file
    and line that issued it nor its source line."""
    global _said
    previous = _said
    _said = set()
    with warnings.catch_warnings():
        warnings.showwarning = lambda message, *_args, **_kw: say_warning(str(message))
        try:
            yield
        finally:
            _said = previous


class _Commands(click.Group):
    """The verbs; an optional dependency a verb needs and does not find (``MissingExtra``:
    the message names the extra to install) is a usage error, exit code 2, like a bad
    option: nothing ran."""

    def invoke(self, ctx):
        from ._extras import MissingExtra

        try:
            return super().invoke(ctx)
        except MissingExtra as exc:
            raise UsageError(str(exc)) from None


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rodjit", prog_name="rodjit")
@click.pass_context
def main(ctx):
    """Simulate an elastic rod bouncing on a floor (Aiki & Kosugi) and inspect the runs.

    \b
    Exit codes (every verb):
      0    done (every run or point completed)
      1    a run, a sweep point or a fit failed, or the disk refused a write
           (the file keeps its last checkpoint and says why)
      2    usage, configuration, path or file error: one line, nothing written
      130  stopped by SIGINT (a checkpoint is written; --resume continues)
      143  stopped by SIGTERM (likewise)
    """
    ctx.with_resource(_warnings_as_lines())


# ---- rodjit run ---------------------------------------------------------------------------
def _load_config(source: str | None):
    """(Config, default output name) from a TOML path, a preset name, or the default."""
    from . import presets
    from .config import Config

    if source is None:
        return Config(), DEFAULT_OUTPUT
    path = Path(source)
    if path.suffix == ".h5":
        raise ValueError(f"{source!r} is not a configuration; to continue a run file use: "
                         f"rodjit run --resume {source}")
    if path.is_file() or path.suffix == ".toml" or path.is_dir():
        return Config.from_toml(path), path.stem + ".h5"
    if source in presets.preset_names():
        return presets.load_preset(source), source + ".h5"
    raise ValueError(f"{source!r} is neither a configuration file nor a preset; presets: "
                     f"{', '.join(presets.preset_names())}")


def _overrides(sets) -> dict[str, str]:
    out = {}
    for item in sets:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--set expects KEY=VALUE (e.g. --set rod.mu=100), got {item!r}")
        out[key.strip()] = value
    return out


def _command_line(verb: str, config, options, flags) -> str:
    """The command line as recorded in a file, in canonical form: ``rodjit VERB [CONFIG]``,
    then ``options`` ((flag, value or tuple of values); None left out), then the ``flags``
    ((flag, on)) that are on."""
    words = ["rodjit", verb] + ([config] if config else [])
    for flag, value in options:
        for v in value if isinstance(value, tuple) else (value,):
            if v is not None:
                words += [flag, str(v)]
    words += [flag for flag, on in flags if on]
    return shlex.join(words)


def _Progress(cold=None):
    """The run bar on stderr (``driver.progress.RunBar``)."""
    from .driver.progress import RunBar

    return RunBar(file=sys.stderr, cold=cold)


def _progress(flag: bool | None, quiet: bool, bar, config=None):
    """The CLI's bar (``driver.progress``): on a terminal unless --no-progress or --quiet;
    says once when the kernels are being compiled (for ``config``'s run, if given)."""
    show = (sys.stderr.isatty() if flag is None else flag) and not quiet
    if not show:
        return None
    from .driver.progress import COMPILING, kernels_cold

    cold = kernels_cold(config)
    if cold:
        click.echo(COMPILING, err=True)
    return bar(cold)


@main.command("run")
@click.argument("config", required=False, metavar="[CONFIG.toml | PRESET]")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help=f"HDF5 file to write [default: PRESET.h5, CONFIG.h5 or {DEFAULT_OUTPUT}]")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="Override a configuration key, e.g. --set rod.mu=100 (repeatable).")
@click.option("--t-end", type=float, help="End time (overrides time.t_end; with --resume it "
                                          "extends the run).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("--resume", is_flag=True, help="Continue the run in FILE.h5 (given as argument "
                                             "or -o) from its checkpoint.")
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
@click.option("--flush-interval", type=float, default=2.0, show_default=True,
              metavar="SECONDS", help="Wall time between checkpoints.")
@click.option("--progress/--no-progress", "show_progress", default=None,
              help="Show a progress bar [default: on a terminal].")
@click.option("--max-output", default="10GiB", show_default=True, metavar="SIZE",
              help="Refuse a run whose file would exceed SIZE (e.g. 500M, 50GiB, inf).")
@click.option("--max-steps", type=float, default=1e10, show_default=True, metavar="N",
              help="Refuse a fixed time.dt that needs more than N steps.")
@click.option("--dry-run", is_flag=True,
              help="Check everything (configuration, output path, limits), print the rows, "
                   "file size, memory and steps the run would write, and write nothing.")
def run_command(config, output, sets, t_end, overwrite, resume, quiet, flush_interval,
                show_progress, max_output, max_steps, dry_run):
    """Run CONFIG.toml, a preset (see 'rodjit presets') or the built-in default, streaming
    snapshots, diagnostics, contact episodes and bounces to an HDF5 file.

    Ctrl-C or SIGTERM stops at once with a checkpoint; 'rodjit run --resume FILE.h5'
    continues exactly where the run stopped.
    """
    from .config import ModelWarning
    from .driver.files import OutputExists, RunInterrupted, plan_run, resume_file, run_to_file
    from .driver.run import SimulationError

    if dry_run:
        if resume:
            raise UsageError("--dry-run checks a new run; it cannot be used with --resume")
        try:
            from .output.estimate import parse_size

            cfg, default_name = _load_config(config)
            cfg = cfg.override(_overrides(sets)) if sets else cfg
            plan = plan_run(cfg, output or default_name, overwrite=overwrite, t_end=t_end,
                            max_output=parse_size(max_output), max_steps=max_steps,
                            flush_interval=flush_interval)
        except OutputExists as exc:
            raise UsageError(str(exc).replace("pass overwrite=True", "use --overwrite")) from None
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        click.echo(plan.report())
        for text in plan.config.warnings():   # as the run would say them
            say_warning(text)
        return
    command = _command_line(
        "run", config, [("-o", output), ("--set", sets),
                        ("--t-end", repr(t_end) if t_end is not None else None)],
        [("--resume", resume), ("--overwrite", overwrite), ("--quiet", quiet)])
    progress = None
    try:
        if resume:
            progress = _progress(show_progress, quiet, _Progress)
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
            from .output.estimate import parse_size

            summary = resume_file(target, t_end=t_end, command=command, progress=progress,
                                  flush_interval=flush_interval,
                                  max_output=parse_size(max_output), max_steps=max_steps)
        else:
            cfg, default_name = _load_config(config)
            overrides = _overrides(sets)
            if overrides:
                cfg = cfg.override(overrides)
            progress = _progress(show_progress, quiet, _Progress, cfg)
            from .output.estimate import parse_size

            with warnings.catch_warnings():   # said below as one line each on stderr
                warnings.simplefilter("ignore", ModelWarning)
                summary = run_to_file(cfg, output or default_name, overwrite=overwrite,
                                      command=command, progress=progress, t_end=t_end,
                                      flush_interval=flush_interval,
                                      max_output=parse_size(max_output), max_steps=max_steps)
    except OutputExists as exc:
        raise UsageError(str(exc).replace("pass overwrite=True", "use --overwrite")) from None
    except RunInterrupted as exc:
        _close(progress)
        if not quiet:           # its warnings in the report: stderr is the one line below
            click.echo(exc.summary.report())
        click.echo(str(exc), err=True)
        sys.exit(EXIT_SIGNAL + exc.signum)
    except SimulationError as exc:
        _close(progress)
        if not quiet and getattr(exc, "summary", None) is not None:
            click.echo(exc.summary.report())      # (as above)
        raise RunFailed(str(exc)) from None
    except ValueError as exc:       # configuration, path and file errors: nothing written
        raise UsageError(str(exc)) from None
    except OSError as exc:          # the disk failed us during the run (full, removed, ...)
        _close(progress)
        _disk_failed(exc)
    _close(progress)
    _say_run(summary, quiet)


def _say_run(summary, quiet: bool) -> None:
    """A run's warnings on stderr, once each, even with --quiet (what the results do not
    mean); then, unless quiet, its report on stdout without them (said once)."""
    for text in summary.warnings:
        say_warning(text)
    if not quiet:
        if not hasattr(summary, "facts"):
            click.echo(summary.report())
            return
        facts = summary.facts()
        facts.warnings = ()
        click.echo(facts.report())


def one_line(message) -> str:
    """``message`` on one line (HDF5's messages embed newlines)."""
    return " ".join(str(message).split())


def _disk_failed(exc: OSError):
    """Exit 1 with one line when the disk failed a write.  The process ends at once
    (``os._exit``): HDF5 would otherwise try to flush the abandoned file again while the
    interpreter shuts down, printing tracebacks or crashing."""
    import os

    from .output.h5files import WriteFailed, disk_cause

    cause = disk_cause(exc)
    text = str(exc) if isinstance(exc, WriteFailed) or cause is None else (
        f"a write failed: {cause} ({exc})")
    click.echo(f"Error: {one_line(text)}", err=True)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(1)


def _close(progress) -> None:
    if progress is not None:
        progress.close()


# ---- rodjit sweep -------------------------------------------------------------------------
def _SweepProgress(cold=None):
    """The sweep bar on stderr (``driver.progress.SweepBar``)."""
    from .driver.progress import SweepBar

    return SweepBar(file=sys.stderr, cold=cold)


@main.command("sweep")
@click.argument("config", required=False, metavar="[CONFIG.toml | PRESET]")
@click.option("--grid", "grids", multiple=True, metavar="KEY=VALUES",
              help="A swept key and its values: a list (rod.mu=0,1,10,100), "
                   "linspace(a,b,n) or logspace(a,b,n) (10^a to 10^b); repeat for more "
                   "keys (the grid is their Cartesian product).")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Sweep file to write [default: PRESET_sweep.h5, CONFIG_sweep.h5 or "
                   "sweep.h5].")
@click.option("-j", "--jobs", type=int, help="Worker processes [default: every core].")
@click.option("--scheduler", metavar="local|tcp://HOST:PORT",
              help="Run the points on Dask: 'local' starts a LocalCluster of --jobs workers, "
                   "tcp://HOST:PORT uses an existing cluster [default: a local process pool; "
                   "also 'inline': this process].")
@click.option("--save-runs", type=click.Path(file_okay=False),
              help="Also write one full run file per point into this directory.")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="Override a key of the base configuration (repeatable).")
@click.option("--resume", is_flag=True, help="Run only the points of the sweep file that are "
                                             "missing or failed.")
@click.option("--overwrite", is_flag=True, help="Replace an existing sweep file (and run "
                                                "files in --save-runs).")
@click.option("--force-jobs", is_flag=True, help="Start --jobs workers even if that is more "
                                                 "than the cores.")
@click.option("-q", "--quiet", is_flag=True, help="Print nothing but errors.")
@click.option("--progress/--no-progress", "show_progress", default=None,
              help="Show a progress bar [default: on a terminal].")
@click.option("--max-output", default="10GiB", show_default=True, metavar="SIZE",
              help="Refuse a sweep whose sweep file, or (with --save-runs) any run file, "
                   "would exceed SIZE (e.g. 500M, 50GiB, inf).")
@click.option("--max-steps", type=float, default=1e10, show_default=True, metavar="N",
              help="Refuse a point whose fixed time.dt needs more than N steps.")
@click.option("--max-points", type=float, default=1e6, show_default=True, metavar="N",
              help="Refuse a grid of more than N points (counted before it is made).")
@click.option("--dry-run", is_flag=True,
              help="Check everything (configuration, every point, output paths, limits), "
                   "print the points, the swept keys and the files' estimated sizes, and "
                   "write nothing.")
@click.option("--batch-size", type=int, default=None, metavar="N",
              help="Points per compiled call of the ensemble engine [default: about 0.3 s "
                   "of work, from the measured cost per point].")
def sweep_command(config, grids, output, jobs, scheduler, save_runs, sets, resume, overwrite,
                  force_jobs, quiet, show_progress, max_output, max_steps, max_points,
                  dry_run, batch_size):
    """Run CONFIG.toml, a preset or the built-in default at every point of a grid, on every
    core (or a Dask cluster), into one sweep file with a summary row per point.

    Exit codes: 0 every point completed, 1 some points failed (the file lists them; --resume
    reruns them), 2 usage or configuration error (nothing written), 130/143 interrupted
    (every finished point is kept; --resume continues).
    """
    import signal

    from .driver.files import OutputExists
    from .driver.signals import hold_on_exit, pending_signal
    from .sweeps import SweepFailed, SweepInterrupted, plan_sweep, sweep

    if dry_run and resume:
        raise UsageError("--dry-run checks a new sweep; it cannot be used with --resume")
    command = _command_line(
        "sweep", config, [("--grid", grids), ("--set", sets), ("-o", output), ("--jobs", jobs),
                          ("--scheduler", scheduler), ("--save-runs", save_runs)],
        [("--resume", resume), ("--overwrite", overwrite), ("--quiet", quiet)])
    progress = _progress(show_progress, quiet, _SweepProgress)
    if quiet:
        _quiet_dask()
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
                cfg, _ = _load_config(config)
                cfg = cfg.override(_overrides(sets)) if sets else cfg
            if grids:
                grid = _grid(grids, max_points)
            from .sweeps import load_sweep

            done = load_sweep(output)
            if done.counts["completed"] == len(done.grid):
                raise ValueError(f"{output!r} is already complete ({len(done.grid)} points); "
                                 f"nothing to resume")
        else:
            cfg, default_name = _load_config(config)
            overrides = _overrides(sets)
            if overrides:
                cfg = cfg.override(overrides)
            grid = _grid(grids, max_points)
            if not output:
                output = ("sweep.h5" if default_name == DEFAULT_OUTPUT
                          else default_name[:-3] + "_sweep.h5")
        from .output.estimate import parse_size

        limits = {"max_output": parse_size(max_output), "max_steps": max_steps,
                  "max_points": max_points}
        if dry_run:
            from .sweeps.executors import check_scheduler
            from .sweeps.run_sweep import check_batch_size, check_jobs

            check_jobs(jobs)
            check_batch_size(batch_size)
            check_scheduler(scheduler)
            plan = plan_sweep(cfg, grid, output=output, save_runs=save_runs,
                              overwrite=overwrite, **limits)
            click.echo(plan.report())
            return
        jobs = _cap_jobs(jobs, scheduler, grid, force_jobs, quiet)
        with hold_on_exit():      # from the end of the sweep on, signals wait (see below)
            table = sweep(cfg, grid, output=output, jobs=jobs, scheduler=scheduler,
                          save_runs=save_runs, resume=resume, overwrite=overwrite,
                          progress=progress, command=command, batch_size=batch_size,
                          **limits)
    except OutputExists as exc:
        raise UsageError(str(exc).replace("pass overwrite=True", "use --overwrite (or "
                                          "--resume)")) from None
    except SweepInterrupted as exc:
        _close(progress)
        if not quiet:
            click.echo(exc.table.headline())
            if exc.table.status == "completed":
                click.echo(exc.table.report(max_rows=40))
        click.echo(str(exc), err=True)
        sys.exit(EXIT_SIGNAL + (exc.signum or 2))
    except SweepFailed as exc:
        _close(progress)
        if not quiet:
            click.echo(exc.table.headline())
            click.echo(exc.table.report(max_rows=40))
        click.echo(f"error: {exc}", err=True)
        sys.exit(1)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except OSError as exc:          # the disk refused a write (the sweep file, a run file)
        _close(progress)
        _disk_failed(exc)
    _close(progress)
    if not quiet:
        click.echo(table.headline())
        click.echo(table.report(max_rows=40))
    late = pending_signal()   # came after the file was closed, while the table was printed
    if late is not None:
        click.echo(f"interrupted by {signal.Signals(late).name} after the last point; "
                   f"{output!r} is complete", err=True)
        sys.exit(EXIT_SIGNAL + late)
    if table.counts["failed"]:
        click.echo(f"Error: {_failed_points(table, output)}", err=True)   # even with -q
        sys.exit(1)


def _failed_points(table, output) -> str:
    """One line on the failed points of a sweep: how many, the first one's message."""
    status = table.columns["status"]
    failed = [i for i, s in enumerate(status) if s == "failed"]
    first = str(table.columns.get("message", [""] * len(status))[failed[0]]) if failed else ""
    return one_line(f"{len(failed)} of {len(status)} points failed (point {failed[0]}: "
                    f"{first or 'no message'}); 'rodjit sweep --resume -o {output}' runs them "
                    f"again")


def _quiet_dask() -> None:
    """--quiet: Dask's and distributed's own log lines stay off stderr (here and in the
    processes they start, which read the environment)."""
    import logging
    import os

    os.environ["DASK_LOGGING__DISTRIBUTED"] = "critical"
    for name in ("distributed", "dask", "tornado", "bokeh"):
        logging.getLogger(name).setLevel(logging.CRITICAL)


def _grid(options, max_points: float):
    """The Grid of the --grid options, sized (--max-points) before it is made."""
    from .sweeps.grid import Grid, parse_grid_option

    return Grid.from_spec(parse_grid_option(options), max_points=max_points)


def _cap_jobs(jobs, scheduler, grid, force: bool, quiet: bool):
    """--jobs for a local pool: at most the cores (unless forced, with a note when cut) and
    never more than the points."""
    if jobs is None or isinstance(jobs, bool) or jobs < 1 or scheduler not in (None,
                                                                               "processes"):
        return jobs
    from .sweeps.executors import default_jobs

    cores = default_jobs()
    if jobs > cores and not force:
        if not quiet:
            click.echo(f"note: --jobs {jobs} is more than the {cores} cores; using {cores} "
                       f"(--force-jobs to insist)", err=True)
        jobs = cores
    if grid is not None:
        jobs = max(1, min(jobs, len(grid)))
    return jobs


# ---- rodjit presets -----------------------------------------------------------------------
@main.command("presets")
def presets_command():
    """List the named configurations shipped with rodjit."""
    from . import presets

    for name in presets.preset_names():
        first = presets.preset_path(name).read_text().splitlines()[0]
        about = first.lstrip("# ").strip() if first.startswith("#") else ""
        click.echo(f"{name:<14}{about}")


@main.command("config")
@click.argument("config", required=False, metavar="[CONFIG.toml | PRESET]")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="Override a configuration key, e.g. --set rod.mu=100 (repeatable).")
@click.option("--keys", is_flag=True, help="List every key with its meaning and unit.")
def config_command(config, sets, keys):
    """Print the resolved configuration of CONFIG.toml, a preset or the built-in default
    (with --set overrides) as TOML, each key commented with its meaning, unit, default and
    allowed values; the output is itself a valid configuration file."""
    from .config import key_lines

    if keys:
        if config is not None or sets:
            raise UsageError("--keys lists the keys of every configuration; it takes no "
                             "CONFIG or --set")
        click.echo("\n".join(key_lines()))
        return
    try:
        cfg, _ = _load_config(config)
        cfg = cfg.override(_overrides(sets))
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(cfg.commented_toml(), nl=False)


# ---- rodjit info / plot: dispatch on the file's kind --------------------------------------
def _kind(path: str) -> str:
    """The file's kind ("run", "sweep"), or a UsageError naming what is wrong with it."""
    from .reports import readable_kind

    try:
        return readable_kind(path)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def _draw(plot, path: str, output: str | None, kind: str, **options) -> None:
    """``plot(path, image, kind, **options)`` into ``output`` (default FILE_KIND.png)."""
    from .plotting import MissingMatplotlib, NothingToDraw

    out = output or str(Path(path).with_suffix("")) + f"_{kind}.png"
    from .output.h5files import check_output

    try:
        check_output(out, overwrite=True)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    from .output.h5files import WriteFailed

    try:
        written = plot(path, out, kind, **options)
    except MissingMatplotlib as exc:    # the plot extra: a usage error (install it), exit 2
        raise UsageError(str(exc)) from None
    except WriteFailed as exc:
        raise RunFailed(str(exc)) from None
    except NothingToDraw as exc:
        raise RunFailed(str(exc)) from None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(f"wrote {written}")


def _is_convergence(path: str) -> bool:
    """Whether ``path`` is a convergence file (``rodjit converge -o``)."""
    from .output.h5files import file_kind

    try:
        return file_kind(path) == "convergence"
    except (ValueError, OSError):
        return False


def plot_run(path: str, output: str | None, kind: str, options: dict) -> None:
    from .plotting import plot_file

    _draw(plot_file, path, output, kind, **options)


def plot_sweep(path: str, output: str | None, kind: str, options: dict) -> None:
    from .plotting.sweep import plot_sweep_file

    _draw(plot_sweep_file, path, output, kind, **options)


# copies of plotting.KINDS and plotting.sweep.KINDS (tests/test_cli.py checks they agree):
# importing those modules would load numpy, h5py and Numba before every command
RUN_KINDS = ("heights", "energy", "bounces", "spacetime", "contact")
SWEEP_KINDS = ("restitution", "heatmap")
CONVERGENCE_KINDS = ("convergence",)
PLOT_KINDS = RUN_KINDS + SWEEP_KINDS + CONVERGENCE_KINDS


def _figsize(text: str | None):
    """``--figsize W,H`` (inches) as a tuple, or None."""
    if text is None:
        return None
    try:
        w, h = (float(p) for p in text.split(","))
    except ValueError:
        raise UsageError(f"--figsize {text!r}: give WIDTH,HEIGHT in inches, e.g. 8,5") from None
    if not (0 < w <= 100 and 0 < h <= 100):
        raise UsageError(f"--figsize {text!r} is out of range (inches > 0 and <= 100)")
    return (w, h)


@main.command("info")
@click.argument("file", type=click.Path(dir_okay=True))
def info_command(file):
    """Configuration, status, counts and the bounce table of a rodjit file."""
    from .reports import info

    try:
        text = info(file)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(text)


@main.command("plot")
@click.argument("file", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Image to write [default: FILE_KIND.png next to FILE].")
@click.option("--kind", type=click.Choice(PLOT_KINDS),
              help="Run files: heights (all nodes against time, the paper's figures; the "
                   "default), energy (components, and the drift or balance error), bounces "
                   "(restitution per bounce), spacetime (strain over time and x, contact "
                   "marked), contact (u_0 with -beta, and the floor force).  Sweep files: restitution "
                   "(against --x, one line per value of the other keys; the default), heatmap "
                   "(over two keys at --at values).  Convergence files: convergence (error "
                   "against the level, log-log).")
@click.option("--quantity", metavar="COLUMN",
              help="Run files: what spacetime colours (strain, u, v) [default: strain].  "
                   "Sweep files: the summary column drawn [default: restitution_first, the "
                   "first bounce's restitution, 0 without lift-off].")
@click.option("--x", "x_key", metavar="KEY", help="Sweep files: the key along the x axis, as "
              "the key (rod.mu) or its to_xarray dimension name (mu) [restitution: rod.mu "
              "if swept; heatmap: floor.kappa_b, then floor.beta].")
@click.option("--y", "y_key", metavar="KEY", help="Sweep heatmaps: the key along the y axis.")
@click.option("--at", "at", multiple=True, metavar="KEY=VALUE",
              help="Sweep files: fix another swept key (repeatable) [default for a heatmap: "
                   "the first value of each other key].")
@click.option("--panels", "panels", metavar="KEY", help="Sweep files (restitution): one "
              "panel per value of this swept key.")
@click.option("--dpi", type=click.IntRange(10, 2400), default=150, show_default=True,
              help="Resolution of PNG images.")
@click.option("--figsize", metavar="W,H", help="Figure size in inches, e.g. 8,5.")
def plot_command(file, output, kind, quantity, x_key, y_key, at, panels, dpi, figsize):
    """Draw a figure of a rodjit file (a run or a sweep) as PNG, PDF or SVG (by the suffix
    of -o)."""
    if _is_convergence(file):
        if kind not in (None, *CONVERGENCE_KINDS) or quantity or x_key or y_key or at:
            raise UsageError("a convergence file takes no --kind but 'convergence' and no "
                             "--quantity, --x, --y or --at")
        from .plotting.convergence import plot_convergence_file

        _draw(plot_convergence_file, file, output, "convergence")
        return
    kind_of_file = _kind(file)
    style = {"dpi": dpi, "figsize": _figsize(figsize)}
    if kind_of_file == "run":
        if kind is not None and kind not in RUN_KINDS:
            raise UsageError(f"--kind {kind} is for sweep files; a run file takes one of "
                             f"{', '.join(RUN_KINDS)}")
        if x_key or y_key or at or panels:
            raise UsageError("--x, --y, --at and --panels are for sweep files")
        if quantity and kind != "spacetime":
            raise UsageError("--quantity is for --kind spacetime on a run file")
        plot_run(file, output, kind or "heights",
                 dict(style, **({"quantity": quantity} if quantity else {})))
        return
    if kind is not None and kind not in SWEEP_KINDS:
        raise UsageError(f"--kind {kind} is for run files; a sweep file takes one of "
                         f"{', '.join(SWEEP_KINDS)}")
    try:
        fixed = _overrides(at)
    except ValueError as exc:
        raise UsageError(str(exc).replace("--set", "--at")) from None
    plot_sweep(file, output, kind or "restitution",
               {"quantity": quantity, "x": x_key, "y": y_key, "at": fixed, "panels": panels,
                **style})


@main.command("animate")
@click.argument("file", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Movie to write, .gif or .mp4 (needs ffmpeg) [default: FILE.gif].")
@click.option("--fps", type=click.IntRange(1, 120), default=20, show_default=True,
              help="Frames per second.")
@click.option("--duration", type=click.FloatRange(0, None, min_open=True), default=5.0,
              show_default=True, help="Length of the movie in seconds (frames: fps x "
              "duration, sampled evenly from the snapshots).")
@click.option("--quantity", type=click.Choice(("strain", "v")), default="strain",
              show_default=True, help="What colours the rod.")
@click.option("--dpi", type=click.IntRange(10, 600), default=100, show_default=True)
def animate_command(file, output, fps, duration, quantity, dpi):
    """A movie of a run file: the rod over the floor, coloured by strain."""
    if _kind(file) != "run":
        raise UsageError(f"{file!r} is a sweep file; animate draws run files")
    from .plotting import MissingMatplotlib, NothingToDraw
    from .plotting.animation import MissingWriter, animate

    from .output.h5files import WriteFailed

    out = output or str(Path(file).with_suffix(".gif"))
    try:
        written = animate(file, out, fps=fps, duration=duration, quantity=quantity, dpi=dpi)
    except MissingMatplotlib as exc:    # the plot extra: a usage error (install it), exit 2
        raise UsageError(str(exc)) from None
    except (MissingWriter, NothingToDraw, WriteFailed) as exc:
        raise RunFailed(str(exc)) from None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(f"wrote {written}")


if __name__ == "__main__":  # pragma: no cover
    main()


# ---- rodjit converge / rodjit fit -----------------------------------------------------------
def _key_values(option: str, text: str, allow_many: bool = False) -> dict[str, str]:
    """``KEY=V1,V2,...`` of --ladder / --also / --target as {key: text}."""
    key, sep, values = text.partition("=")
    if not sep or not key.strip() or not values.strip():
        raise ValueError(f"{option} expects KEY=VALUES (e.g. {option} rod.N=25,50,100), "
                         f"got {text!r}")
    return {key.strip(): values.strip()}


def _base_config(config, sets):
    cfg, _ = _load_config(config)
    overrides = _overrides(sets)
    return cfg.override(overrides) if overrides else cfg


@main.command("converge")
@click.argument("config", required=False, metavar="[CONFIG.toml | PRESET]")
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
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Write the study to this HDF5 file (rodjit_kind = convergence).")
@click.option("--overwrite", is_flag=True, help="Replace an existing output file.")
@click.option("-j", "--jobs", type=int, help="Worker processes [default: every core].")
@click.option("--scheduler", metavar="local|tcp://HOST:PORT",
              help="As for rodjit sweep: Dask 'local', tcp://HOST:PORT, or 'inline'.")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="Override a key of the configuration (repeatable).")
def converge_command(config, ladder, also, observables, output, overwrite, jobs, scheduler,
                     sets):
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
    import os

    from .analysis.converge import converge

    try:
        cfg = _base_config(config, sets)
        if output and os.path.exists(output) and not overwrite:
            raise ValueError(f"{output!r} exists; use --overwrite to replace it")
        names = [o.strip() for o in observables.split(",") if o.strip()]
        result = converge(cfg, _key_values("--ladder", ladder),
                          also=(False if also is not None and also.strip() == "none"
                                else _key_values("--also", also) if also else None),
                          observables=names, jobs=jobs, scheduler=scheduler)
        if output:
            result.save(output, overwrite=True)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(repr(result))
    if output:
        click.echo(f"wrote {output}")


@main.command("fit")
@click.argument("key", metavar="KEY[,KEY...]")
@click.argument("config", required=False, metavar="[CONFIG.toml | PRESET]")
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
@click.option("-j", "--jobs", type=int, help="Worker processes [default: every core].")
@click.option("--scheduler", metavar="local|tcp://HOST:PORT",
              help="As for rodjit sweep: Dask 'local', tcp://HOST:PORT, or 'inline'.")
@click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
              help="Override a key of the configuration (repeatable).")
def fit_command(key, config, target, bracket, points, ftol, converged, ladder, table, jobs,
                scheduler, sets):
    """Find the value of KEY for which an observable takes a target (--target), or fit
    several KEYs to a table of measurements (--table).

    Exit codes: 0 done, 1 the target cannot be fitted (unreachable, or crossed more than
    once in the bracket: the message says where), 2 usage or configuration error.
    """
    from .analysis.fit import FitError, fit
    from .analysis.fit_table import fit_table

    try:
        cfg = _base_config(config, sets)
        keys = [k.strip() for k in key.split(",") if k.strip()]
        if table:
            if target:
                raise ValueError("--target and --table exclude each other")
            result = fit_table(keys, table, cfg, jobs=jobs, scheduler=scheduler)
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
                         ladder=_key_values("--ladder", ladder) if ladder else None,
                         jobs=jobs, scheduler=scheduler)
    except FitError as exc:
        raise RunFailed(str(exc)) from None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(repr(result))
    for note in getattr(result, "notes", []):
        click.echo(f"note: {note}")
    for row in getattr(result, "residuals", []):
        click.echo(f"  row {row['row']} {row['observable']}: measured {row['measured']:.6g}, "
                   f"model {row['model']:.6g}, residual {row['residual']:+.3g}")
