"""What ``info``, ``plot`` and ``animate`` share: a file's kind (``rodjit_kind``: run,
sweep, convergence), the figure kinds of each, and drawing a figure into an image with the
command line's errors."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable

import click

from .exits import RunFailed, UsageError

__all__ = ["RUN_KINDS", "SWEEP_KINDS", "CONVERGENCE_KINDS", "PLOT_KINDS", "file_kind", "draw",
           "check_picture", "is_convergence"]

# copies of plotting.KINDS and plotting.sweep.KINDS (tests/test_cli.py checks they agree):
# importing those modules would load numpy, h5py and Numba before every command
RUN_KINDS = ("heights", "energy", "bounces", "spacetime", "contact")
SWEEP_KINDS = ("restitution", "heatmap")
CONVERGENCE_KINDS = ("convergence",)
PLOT_KINDS = RUN_KINDS + SWEEP_KINDS + CONVERGENCE_KINDS


def file_kind(path: str) -> str:
    """The file's kind ("run", "sweep"), or a UsageError naming what is wrong with it."""
    from ..reports import readable_kind

    try:
        return str(readable_kind(path))
    except ValueError as exc:
        raise UsageError(exc) from None


def draw(plot: Callable[..., Any], path: str, output: str | None, kind: str,
         overwrite: bool = False, **plot_options: Any) -> None:
    """``plot(path, image, kind, **plot_options)`` into ``output`` (default FILE_KIND.png);
    an existing image is replaced only with ``overwrite`` (--overwrite), as every writer's
    output."""
    from ..plotting import MissingMatplotlib, NothingToDraw

    out = output or str(Path(path).with_suffix("")) + f"_{kind}.png"
    check_picture(out, overwrite, path)
    from ..output.h5files import WriteFailed

    try:
        written = plot(path, out, kind, **plot_options)
    except MissingMatplotlib as exc:    # the plot extra: a usage error (install it), exit 2
        raise UsageError(exc) from None
    except WriteFailed as exc:
        raise RunFailed(exc) from None
    except NothingToDraw as exc:
        raise RunFailed(exc) from None
    except ValueError as exc:
        raise UsageError(exc) from None
    click.echo(f"wrote {written}")


def check_picture(output: str, overwrite: bool, source: str | None = None,
                  option: str = "-o", what: str = "a picture") -> None:
    """UsageError (one line, naming ``option``) unless the picture (or other plain file,
    ``what``) ``output`` can be written: its directory, a special file, and an existing
    file only with --overwrite (``output.h5files.check_output``); never the file drawn
    (``source``) nor any HDF5 file, whatever its name: a picture replaces only a
    picture."""
    from ..output.h5files import check_output, looks_hdf5

    if source is not None and _same_file(output, source):
        raise UsageError(f"{option} {output!r} is the file being drawn; choose another name")
    if looks_hdf5(output):
        raise UsageError(f"{option} {output!r} is an HDF5 file, not {what}; rodjit does not "
                         f"replace it with one (choose another name)")
    try:
        check_output(output, overwrite=overwrite)
    except ValueError as exc:
        raise UsageError(exc) from None


def _same_file(a: str, b: str) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.abspath(a) == os.path.abspath(b)


def is_convergence(path: str) -> bool:
    """Whether ``path`` is a convergence file (``rodjit converge -o``)."""
    from ..output.h5files import file_kind as kind_of

    try:
        return bool(kind_of(path) == "convergence")
    except (ValueError, OSError):
        return False
