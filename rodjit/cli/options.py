"""The options several verbs share, each defined once (a verb passes only the words of its
help that differ), and the ways they are read: ``--set`` and ``--at`` pairs, the
configuration argument, ``KEY=VALUES`` ladders, the recorded command line, the bar.
"""
from __future__ import annotations

import shlex
import sys
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence, TypeVar

import click

__all__ = ["DEFAULT_OUTPUT", "CONFIG_METAVAR", "config_argument", "set_option",
           "output_option", "overwrite_option", "quiet_option", "progress_option",
           "max_output_option", "max_steps_option", "max_points_option", "jobs_option",
           "scheduler_option", "count_limit", "verb_saying_where",
           "load_config", "base_config", "overrides", "key_values", "command_line",
           "progress", "run_bar", "sweep_bar", "close"]

F = TypeVar("F", bound=Callable[..., Any])
DEFAULT_OUTPUT = "default.h5"
CONFIG_METAVAR = "[CONFIG.toml | PRESET]"
SCHEDULER_METAVAR = "local|tcp://HOST:PORT"
SCHEDULER_AS_SWEEP = "As for rodjit sweep: Dask 'local', tcp://HOST:PORT, or 'inline'."


def config_argument() -> Callable[[F], F]:
    """``[CONFIG.toml | PRESET]``: a configuration file, a preset or the default."""
    return click.argument("config", required=False, metavar=CONFIG_METAVAR)


def set_option() -> Callable[[F], F]:
    """``--set KEY=VALUE``, repeatable: a configuration key overridden (``overrides``)."""
    return click.option("--set", "sets", multiple=True, metavar="KEY=VALUE",
                        help="Override a configuration key, e.g. --set rod.mu=100 "
                             "(repeatable).")


def output_option(help: str) -> Callable[[F], F]:
    """``-o/--output FILE``."""
    return click.option("-o", "--output", type=click.Path(dir_okay=False), help=help)


def overwrite_option(help: str = "Replace an existing output file.") -> Callable[[F], F]:
    """``--overwrite``."""
    return click.option("--overwrite", is_flag=True, help=help)


def quiet_option() -> Callable[[F], F]:
    """``-q/--quiet``: nothing but errors, no warning either (``say.keep_quiet``)."""
    def quiet(ctx: click.Context, param: click.Parameter, value: bool) -> bool:
        from .say import keep_quiet

        keep_quiet(value)
        return value

    return click.option("-q", "--quiet", is_flag=True, callback=quiet,
                        help="Print nothing but errors (no warnings either).")


def progress_option() -> Callable[[F], F]:
    """``--progress/--no-progress`` (None: on a terminal)."""
    return click.option("--progress/--no-progress", "show_progress", default=None,
                        help="Show a progress bar [default: on a terminal].")


def max_output_option(what: str) -> Callable[[F], F]:
    """``--max-output SIZE``; ``what``: the file(s) the limit is about."""
    return click.option("--max-output", default="10GiB", show_default=True, metavar="SIZE",
                        help=f"Refuse {what} would exceed SIZE (e.g. 500M, 50GiB, inf).")


def count_limit(ctx: click.Context, param: click.Parameter, value: Any) -> float:
    """The callback of a limit on a count (``--max-steps``, ``--max-points``): a whole
    number >= 1, never NaN or infinity, which would turn the limit off
    (``output.estimate.check_count_limit``, the API's check: one line naming the option,
    exit code 2)."""
    from ..output.estimate import check_count_limit
    from .exits import UsageError

    option = param.opts[0] if param.opts else str(param.name)
    try:
        return check_count_limit(option, value, unlimited=False)
    except ValueError as exc:
        raise UsageError(exc) from None


def max_steps_option(what: str) -> Callable[[F], F]:
    """``--max-steps N``; ``what``: what is refused."""
    return click.option("--max-steps", default="1e10", callback=count_limit,
                        show_default=True, metavar="N",
                        help=f"Refuse {what} needs more than N steps.")


def max_points_option() -> Callable[[F], F]:
    """``--max-points N``."""
    return click.option("--max-points", default="1e6", callback=count_limit,
                        show_default=True, metavar="N",
                        help="Refuse a grid of more than N points (counted before it is "
                             "made).")


def jobs_option() -> Callable[[F], F]:
    """``-j/--jobs N``."""
    return click.option("-j", "--jobs", type=int,
                        help="Worker processes [default: every core].")


def force_jobs_option() -> Callable[[F], F]:
    """``--force-jobs``: start --jobs workers beyond the cores (``cap_jobs``)."""
    return click.option("--force-jobs", is_flag=True, help="Start --jobs workers even if "
                                                           "that is more than the cores.")


def cap_jobs(jobs: int | None, scheduler: str | None, grid: Any = None, force: bool = False,
             quiet: bool = False) -> int | None:
    """--jobs for workers on this machine (the local pool, or Dask's ``local`` cluster, which
    starts --jobs worker processes here too): at most the cores (unless forced, with a note
    when cut) and never more than the points.  A remote cluster's workers are its own."""
    from ..sweeps.start_method import POOL_SCHEDULERS

    if (jobs is None or isinstance(jobs, bool) or jobs < 1
            or scheduler not in (*POOL_SCHEDULERS, "local")):
        return jobs
    from ..sweeps.executors import default_jobs

    cores = default_jobs()
    if jobs > cores and not force:
        if not quiet:
            click.echo(f"note: --jobs {jobs} is more than the {cores} cores; using {cores} "
                       f"(--force-jobs to insist)", err=True)
        jobs = cores
    if grid is not None:
        jobs = max(1, min(jobs, len(grid)))
    return jobs


def scheduler_option(help: str = SCHEDULER_AS_SWEEP) -> Callable[[F], F]:
    """``--scheduler local|tcp://HOST:PORT``."""
    return click.option("--scheduler", metavar=SCHEDULER_METAVAR, help=help)


def verb_saying_where(elsewhere: dict[str, str]) -> type[click.Command]:
    """A verb's command class that answers an option it lacks but another verb has with
    where that option belongs, instead of click's bare "No such option".

    Parameters
    ----------
    elsewhere : dict of str to str
        Option (``"--device"``) -> what to say about it.
    """

    class Verb(click.Command):
        def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
            try:
                return super().parse_args(ctx, args)
            except click.NoSuchOption as exc:
                where = elsewhere.get(exc.option_name)
                if where is None:
                    raise
                raise click.UsageError(f"{exc.option_name} is not an option of rodjit "
                                       f"{self.name}: {where}", ctx) from None

    return Verb


# ---- reading them ---------------------------------------------------------------------
def load_config(source: str | None) -> tuple[Any, str]:
    """(Config, default output name) from a TOML path, a preset name, or the default.

    Raises
    ------
    ValueError
        A run file given as configuration, or a name that is neither file nor preset.
    """
    from .. import presets
    from ..config import Config

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


def overrides(items: Iterable[str], option: str = "--set",
              example: str = "rod.mu=100") -> dict[str, str]:
    """``KEY=VALUE`` pairs of a repeatable option as {key: value text}.

    Raises
    ------
    ValueError
        An item without ``=`` or without a key, naming ``option``.
    """
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"{option} expects KEY=VALUE (e.g. {option} {example}), "
                             f"got {item!r}")
        out[key.strip()] = value
    return out


def base_config(config: str | None, sets: Sequence[str]) -> Any:
    """The configuration of the ``CONFIG`` argument with the ``--set`` overrides."""
    cfg, _ = load_config(config)
    changes = overrides(sets)
    return cfg.override(changes) if changes else cfg


def key_values(option: str, text: str) -> dict[str, str]:
    """``KEY=V1,V2,...`` of --ladder / --also / --target as {key: text}.

    Raises
    ------
    ValueError
        No ``=``, no key or no values, naming ``option``.
    """
    key, sep, values = text.partition("=")
    if not sep or not key.strip() or not values.strip():
        raise ValueError(f"{option} expects KEY=VALUES (e.g. {option} rod.N=25,50,100), "
                         f"got {text!r}")
    return {key.strip(): values.strip()}


def command_line(verb: str, config: str | None, options: Sequence[tuple[str, Any]],
                 flags: Sequence[tuple[str, bool]]) -> str:
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


def run_bar(cold: Any = None) -> Any:
    """The run bar on stderr (``driver.progress.RunBar``)."""
    from ..driver.progress import RunBar

    return RunBar(file=sys.stderr, cold=cold)


def sweep_bar(cold: Any = None) -> Any:
    """The sweep bar on stderr (``driver.progress.SweepBar``)."""
    from ..driver.progress import SweepBar

    return SweepBar(file=sys.stderr, cold=cold)


def progress(flag: bool | None, quiet: bool, bar: Callable[[Any], Any],
             config: Any = None) -> Any:
    """The CLI's bar (``driver.progress``): on a terminal unless --no-progress or --quiet;
    says once when the kernels are being compiled (for ``config``'s run, if given)."""
    show = (sys.stderr.isatty() if flag is None else flag) and not quiet
    if not show:
        return None
    from ..driver.progress import COMPILING, kernels_cold

    cold = kernels_cold(config)
    if cold:
        click.echo(COMPILING, err=True)
    return bar(cold)


def close(bar: Any) -> None:
    """Close the bar, if there is one."""
    if bar is not None:
        bar.close()
