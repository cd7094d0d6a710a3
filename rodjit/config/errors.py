"""The errors and the warning class of the configuration: typed, carrying the fields a
message needs (the key, the file), so that callers word them without parsing text."""
from __future__ import annotations

import errno
from pathlib import Path
from typing import Any

__all__ = ["ConfigError", "MissingFile", "ModelWarning"]


class ConfigError(ValueError):
    """A configuration key or value rodjit refuses: one line naming the key and the range.

    A ``ValueError`` (exit code 2 on the command line).  ``key`` is the dotted key the
    error is about (``"rod.mu"``; ``"flor."`` for an unknown section; None when no single
    key is to blame), so that a TOML reader can point at the line that set it.

    Parameters
    ----------
    message : str
        The one-line message.
    key : str or None, optional
        The dotted key.
    """

    def __init__(self, message: str, key: str | None = None) -> None:
        super().__init__(message)
        self.key = key

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.args[0], self.key)


class MissingFile(ValueError, FileNotFoundError):
    """A file rodjit was asked to read does not exist: a ``FileNotFoundError`` (what
    ``open`` raises) that is also a ValueError (a bad argument: one line, exit code 2).

    Parameters
    ----------
    path : str or Path
        The missing file.
    what : str, optional
        What the file is, for the message (``"configuration file "``).
    """

    def __init__(self, path: str | Path, what: str = "") -> None:
        message = f"{what}{str(path)!r} does not exist"
        super().__init__(message)
        self.errno, self.strerror, self.filename = errno.ENOENT, message, str(path)
        self.what = what

    def __str__(self) -> str:
        return str(self.args[0])

    def __reduce__(self) -> tuple[Any, ...]:
        return type(self), (self.filename, self.what)


class ModelWarning(UserWarning):
    """A configuration that runs, but whose results mean less than a user would expect."""
