"""``rodjit config``: a configuration resolved, each key commented; or every key."""
from __future__ import annotations

import click

from . import options
from .exits import UsageError
from .options import overrides

__all__ = ["config_command"]


@click.command("config")
@options.config_argument()
@options.set_option()
@click.option("--keys", is_flag=True, help="List every key with its meaning and unit.")
def config_command(config: str | None, sets: tuple[str, ...], keys: bool) -> None:
    """Print the resolved configuration of CONFIG.toml, a preset or the built-in default
    (with --set overrides) as TOML, each key commented with its meaning, unit, default and
    allowed values; the output is itself a valid configuration file."""
    from ..config import key_lines

    if keys:
        if config is not None or sets:
            raise UsageError("--keys lists the keys of every configuration; it takes no "
                             "CONFIG or --set")
        click.echo("\n".join(key_lines()))
        return
    try:
        cfg, _ = options.load_config(config)
        cfg = cfg.override(overrides(sets))
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(cfg.commented_toml(), nl=False)
