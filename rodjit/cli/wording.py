"""How the command line words the API's typed errors: the API raises errors carrying the
fields a message needs (a path, a key), and its own messages speak Python (``pass
overwrite=True``); the command line speaks in its options."""
from __future__ import annotations

from typing import Any

__all__ = ["output_exists"]


def output_exists(exc: Any, alternative: str = "") -> str:
    """The line for an ``OutputExists``: the file, and the option that replaces it.

    Parameters
    ----------
    exc : OutputExists
        The error (its ``path``).
    alternative : str, optional
        Another option that would do, e.g. ``"--resume"``.

    Returns
    -------
    str
        ``output file 'x.h5' already exists; use --overwrite to replace it``.
    """
    also = f" (or {alternative})" if alternative else ""
    return f"output file {exc.path!r} already exists; use --overwrite{also} to replace it"
