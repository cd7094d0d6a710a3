"""The ``rodjit`` group: its help (with the exit-code table), the warnings of every verb
as lines, and a missing optional dependency as a usage error."""
from __future__ import annotations

from typing import Any

import click

from .exits import UsageError
from .say import warnings_as_lines

__all__ = ["main"]


class Commands(click.Group):
    """The verbs; an optional dependency a verb needs and does not find (``MissingExtra``:
    the message names the extra to install) is a usage error, exit code 2, like a bad
    option: nothing ran."""

    def invoke(self, ctx: click.Context) -> Any:
        from .._extras import MissingExtra

        try:
            return super().invoke(ctx)
        except MissingExtra as exc:
            raise UsageError(exc) from None


def import_modules(names: tuple[str, ...]) -> None:
    """Import the modules ``--import`` names, the working directory first on the path (as
    ``python -m`` has it): what they register (a stress law, an integrator, an observer)
    is then selectable by name, here and in a sweep's worker processes, which import the
    modules that define a point's laws, integrator and observer
    (``sweeps.point.user_modules``).  A module
    that cannot be imported is a usage error, one line naming it."""
    import importlib
    import os
    import sys

    if names and os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    for name in names:
        try:
            importlib.import_module(name)
        except Exception as exc:          # any failure of the user's module: say it, exit 2
            raise UsageError(f"--import {name}: {type(exc).__name__}: {exc}") from None


@click.group(cls=Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rodjit", prog_name="rodjit")
@click.option("--import", "imports", multiple=True, metavar="MODULE",
              help="Import MODULE first (from the working directory or the Python path): "
                   "a module of one's own that registers a stress law, an integrator or an "
                   "observer, "
                   "e.g. rodjit --import myfloor run --set floor.law=my-floor. Repeatable.")
@click.pass_context
def main(ctx: click.Context, imports: tuple[str, ...]) -> None:
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
    ctx.with_resource(warnings_as_lines())
    import_modules(imports)
