"""The ``rodjit`` command: a thin layer over ``run_to_file``, ``resume_file``, the summary
and the plots.

``info`` and ``plot`` dispatch on a file's ``rodjit_kind`` root attribute through the
``INFO`` and ``PLOT`` tables, so another kind of file (a sweep) plugs in with one entry.
Exit codes: 0 done, 1 the run failed, 2 usage or configuration error (nothing written),
130/143 interrupted by SIGINT/SIGTERM (checkpoint written).
"""
from __future__ import annotations

import shlex
import sys
import time
from pathlib import Path

import click

EXIT_USAGE = 2
DEFAULT_OUTPUT = "default.h5"


class UsageError(click.ClickException):
    """One line on stderr, exit code 2; raised before anything is written."""

    exit_code = EXIT_USAGE


class RunFailed(click.ClickException):
    exit_code = 1


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rodjit", prog_name="rodjit")
def main():
    """Simulate an elastic rod bouncing on a floor (Aiki & Kosugi) and inspect the runs."""


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


def _command(config, output, sets, t_end, overwrite, resume, quiet) -> str:
    """The command line as recorded in the file (canonical form of the options used)."""
    words = ["rodjit", "run"]
    if resume:
        words.append("--resume")
    if config:
        words.append(config)
    if output:
        words += ["-o", output]
    for item in sets:
        words += ["--set", item]
    if t_end is not None:
        words += ["--t-end", repr(t_end)]
    if overwrite:
        words.append("--overwrite")
    if quiet:
        words.append("--quiet")
    return shlex.join(words)


class _Progress:
    """A one-line progress bar on stderr: simulated time, steps/s, bounces so far."""

    WIDTH = 24

    def __init__(self):
        self.last = 0.0
        self.shown = False

    def __call__(self, run) -> None:
        now = time.monotonic()
        if now - self.last < 0.1:
            return
        self.last = now
        frac = min(1.0, max(0.0, run.t / run.t_end)) if run.t_end > 0 else 1.0
        fill = int(round(frac * self.WIDTH))
        rate = run.steps / run.run_time if run.run_time > 0 else 0.0   # compiled-loop rate
        line = (f"\r  t = {run.t:.4g} / {run.t_end:g} [{'#' * fill}{'.' * (self.WIDTH - fill)}] "
                f"{100 * frac:3.0f}%  {rate:.3g} steps/s  {run.bounces_total} bounces")
        click.echo(line, err=True, nl=False)
        self.shown = True

    def close(self) -> None:
        if self.shown:
            click.echo("\r" + " " * 100 + "\r", err=True, nl=False)


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
def run_command(config, output, sets, t_end, overwrite, resume, quiet, flush_interval):
    """Run CONFIG.toml, a preset (see 'rodjit presets') or the built-in default, streaming
    snapshots, diagnostics, contact episodes and bounces to an HDF5 file.

    Ctrl-C or SIGTERM stops at once with a checkpoint; 'rodjit run --resume FILE.h5'
    continues exactly where the run stopped.
    """
    from .driver.files import OutputExists, RunInterrupted, resume_file, run_to_file
    from .driver.run import SimulationError

    command = _command(config, output, sets, t_end, overwrite, resume, quiet)
    progress = None if quiet or not sys.stderr.isatty() else _Progress()
    try:
        if resume:
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
            summary = resume_file(target, t_end=t_end, command=command, progress=progress,
                                  flush_interval=flush_interval)
        else:
            cfg, default_name = _load_config(config)
            overrides = _overrides(sets)
            if overrides:
                cfg = cfg.override(overrides)
            summary = run_to_file(cfg, output or default_name, overwrite=overwrite,
                                  command=command, progress=progress, t_end=t_end,
                                  flush_interval=flush_interval)
    except OutputExists as exc:
        raise UsageError(str(exc).replace("pass overwrite=True", "use --overwrite")) from None
    except RunInterrupted as exc:
        _close(progress)
        if not quiet:
            click.echo(exc.summary.report())
        click.echo(str(exc), err=True)
        sys.exit(128 + exc.signum)
    except SimulationError as exc:
        _close(progress)
        if not quiet and getattr(exc, "summary", None) is not None:
            click.echo(exc.summary.report())
        raise RunFailed(str(exc)) from None
    except ValueError as exc:       # configuration, path and file errors: nothing written
        raise UsageError(str(exc)) from None
    except OSError as exc:          # the disk failed us during the run (full, removed, ...)
        _close(progress)
        raise RunFailed(f"{exc}; the file keeps its last checkpoint") from None
    _close(progress)
    if not quiet:
        click.echo(summary.report())


def _close(progress) -> None:
    if progress is not None:
        progress.close()


# ---- rodjit presets -----------------------------------------------------------------------
@main.command("presets")
def presets_command():
    """List the named configurations shipped with rodjit."""
    from . import presets

    for name in presets.preset_names():
        first = presets.preset_path(name).read_text().splitlines()[0]
        about = first.lstrip("# ").strip() if first.startswith("#") else ""
        click.echo(f"{name:<14}{about}")


# ---- rodjit info / plot: dispatch on the file's kind --------------------------------------
def _kind(path: str) -> str:
    from .output import hdf5

    try:
        with hdf5.open_file(path) as f:
            kind = f.attrs.get("rodjit_kind")
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if kind is None:
        raise UsageError(f"{path!r} is not a rodjit file (no 'rodjit_kind' attribute)")
    kind = str(kind)
    if kind not in INFO:
        raise UsageError(f"{path!r} is a rodjit {kind!r} file, which this version of rodjit "
                         f"cannot read")
    return kind


def info_run(path: str) -> None:
    from .output import hdf5
    from .output.summary import summarize

    try:
        s = summarize(path)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    a = s.attrs
    status = s.status
    if status == "running":
        if s.writer_alive:
            status += " (the writing process is alive)"
        elif s.writer_alive is False:
            status += (f" (the writing process is gone: it was killed; 'rodjit run --resume "
                       f"{path}' continues from the checkpoint at t = {s.t:.6g})")
    click.echo(f"rodjit run file {path} (format {hdf5.FORMAT_VERSION}, written by rodjit "
               f"{a.get('rodjit_version', '?')})")
    click.echo(f"created   {a.get('created', '?')}")
    click.echo(f"command   {a.get('command', '?')}")
    click.echo(f"status    {status}")
    c = s.counts
    click.echo(f"rows      {c['snapshots']} snapshots, {c['diagnostics']} diagnostics, "
               f"{c['episodes']} episodes, {c['bounces']} bounces")
    click.echo("configuration:")
    for line in s.config.to_toml().strip().splitlines():
        click.echo(f"  {line}")
    click.echo(s.report(max_bounces=None))


def plot_run(path: str, output: str | None, kind: str) -> None:
    from .plotting import MissingMatplotlib, plot_file

    out = output or str(Path(path).with_suffix("")) + f"_{kind}.png"
    try:
        written = plot_file(path, out, kind)
    except MissingMatplotlib as exc:
        raise RunFailed(str(exc)) from None
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    click.echo(f"wrote {written}")


INFO = {"run": info_run}          # rodjit_kind -> info(path)
PLOT = {"run": plot_run}          # rodjit_kind -> plot(path, output, kind)
PLOT_KINDS = ("heights", "energy", "bounces")


@main.command("info")
@click.argument("file", type=click.Path(dir_okay=True))
def info_command(file):
    """Configuration, status, counts and the bounce table of a rodjit file."""
    INFO[_kind(file)](file)


@main.command("plot")
@click.argument("file", type=click.Path(dir_okay=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Image to write [default: FILE_KIND.png next to FILE].")
@click.option("--kind", type=click.Choice(PLOT_KINDS), default="heights", show_default=True,
              help="heights: all nodes against time (the paper's figures); energy: energy "
                   "components and dissipation; bounces: restitution per bounce.")
def plot_command(file, output, kind):
    """Draw a figure of a rodjit file."""
    kind_of_file = _kind(file)
    if kind_of_file not in PLOT:
        raise UsageError(f"rodjit plot does not draw {kind_of_file!r} files")
    PLOT[kind_of_file](file, output, kind)


if __name__ == "__main__":  # pragma: no cover
    main()
