"""The installed rodjit version, recorded in every file rodjit writes (``rodjit_version``).

A module of its own at the bottom of the package, so the file writers can name the version
without importing the package's top level (which imports them)."""
from importlib.metadata import PackageNotFoundError, version as _version

__all__ = ["__version__"]

try:
    __version__ = _version("rodjit")
except PackageNotFoundError:  # running from a source tree without installation
    __version__ = "0.0.0+unknown"
