"""``rodjit info``: configuration, status, counts and bounces of a run, sweep or
convergence file."""
from __future__ import annotations

import click

from .exits import UsageError

__all__ = ["info_command"]


@click.command("info")
@click.argument("file", type=click.Path(dir_okay=True))
def info_command(file: str) -> None:
    """Configuration, status, counts and the bounce table of a rodjit file (a run, a sweep
    or a convergence study)."""
    from ..reports import info

    try:
        text = info(file)
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(text)
