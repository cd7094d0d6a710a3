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


@click.group(cls=Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rodjit", prog_name="rodjit")
@click.pass_context
def main(ctx: click.Context) -> None:
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
