"""``rodjit presets``: the named configurations shipped with rodjit."""
from __future__ import annotations

import click

__all__ = ["presets_command"]


@click.command("presets")
def presets_command() -> None:
    """List the named configurations shipped with rodjit."""
    from .. import presets

    for name in presets.preset_names():
        first = presets.preset_path(name).read_text().splitlines()[0]
        about = first.lstrip("# ").strip() if first.startswith("#") else ""
        click.echo(f"{name:<14}{about}")
