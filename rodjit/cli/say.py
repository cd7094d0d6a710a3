"""What a verb says besides its result: warnings as one ``warning:`` line each, once; none
under ``--quiet`` but a wait the user must end (``said_when_quiet``)."""
from __future__ import annotations

import contextlib
import warnings
from typing import Any, Iterator

import click

from .exits import one_line

__all__ = ["say_warning", "warnings_as_lines", "keep_quiet"]

_said: set[str] | None = None     # the warnings said by the running command
_quiet = False                    # --quiet: the running command says no warning


def say_warning(text: str, *, even_quiet: bool = False) -> None:
    """One line ``warning: TEXT`` on stderr, once per text while a command runs.

    Parameters
    ----------
    text : str
        The warning (put on one line).
    even_quiet : bool, optional
        Said under ``--quiet`` too: a wait the user must act on (another process holding
        the output open), which a quiet command would otherwise spend without a word.
    """
    if _quiet and not even_quiet:
        return
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
    global _said, _quiet
    previous, previous_quiet = _said, _quiet
    _said, _quiet = set(), False

    def show(message: Any, *_args: Any, **_kw: Any) -> None:
        say_warning(str(message), even_quiet=getattr(message, "said_when_quiet", False))

    with warnings.catch_warnings():
        warnings.showwarning = show
        try:
            yield
        finally:
            _said, _quiet = previous, previous_quiet


def keep_quiet(quiet: bool) -> None:
    """``--quiet``: the running command says no warning (``say_warning``) until it ends
    (``warnings_as_lines`` restores what was before)."""
    global _quiet
    _quiet = bool(quiet)
