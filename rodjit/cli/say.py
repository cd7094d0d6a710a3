"""What a verb says besides its result: warnings as one ``warning:`` line each, once."""
from __future__ import annotations

import contextlib
import warnings
from typing import Any, Iterator

import click

from .exits import one_line

__all__ = ["say_warning", "warnings_as_lines"]

_said: set[str] | None = None     # the warnings said by the running command


def say_warning(text: str) -> None:
    """One line ``warning: TEXT`` on stderr, once per text while a command runs.

    Parameters
    ----------
    text : str
        The warning (put on one line).
    """
    text = one_line(text)
    if _said is not None:
        if text in _said:
            return
        _said.add(text)
    click.echo(f"warning: {text}", err=True)


@contextlib.contextmanager
def warnings_as_lines() -> Iterator[None]:
    """While a command runs, every warning it issues (its own, a library's, a worker's
    passed on by a sweep) is said by ``say_warning``: one line, once, with neither the file
    and line that issued it nor its source line."""
    global _said
    previous = _said
    _said = set()

    def show(message: Any, *_args: Any, **_kw: Any) -> None:
        say_warning(str(message))

    with warnings.catch_warnings():
        warnings.showwarning = show
        try:
            yield
        finally:
            _said = previous
