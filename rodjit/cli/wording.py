"""How the command line words the API's typed errors: the API raises errors carrying the
fields a message needs (a path, a key, a count, a limit), and its own messages speak Python
(``pass overwrite=True``, ``max_points=``, ``resume=True``); the command line speaks in its
options (``--overwrite``, ``--max-points``, ``--resume``).

``word(exc)`` is the line for any error: the wording of its type (or of the nearest base
type that has one, found by name so that no lower layer is imported here), else its own
text.  Each wording reproduces, option for option, what the command line has always said.

Why a layer of its own rather than one message per error: an error's fields are the API's
(``overwrite=True``) and its remedy on the command line is an option (``--overwrite``);
without this layer the command line's one-line errors would name keywords no command takes
(29 of the 34 tests of tests/test_cli_wording.py fail with its table emptied).
"""
from __future__ import annotations

from typing import Any, Callable

__all__ = ["output_exists", "word", "WORDINGS"]


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


def _too_many_points(exc: Any) -> str:
    return f"{exc.stem()} (raise it with --max-points / max_points=, or sweep fewer values)"


def _bad_grid_item(exc: Any) -> str:
    if exc.problem == "form":
        return (f"--grid expects KEY=VALUES (e.g. --grid rod.mu=0,1,10 or "
                f"--grid floor.beta=linspace(0.01,0.05,3)), got {exc.item!r}")
    if exc.problem == "twice":
        return f"--grid {exc.key} is given twice; list all its values in one --grid"
    return "a sweep needs at least one --grid KEY=VALUES"


def _sweep_file_too_large(exc: Any) -> str:
    return f"{exc.stem()} (raise it with --max-output / max_output=, or sweep fewer points)"


def _runs_dir_unusable(exc: Any) -> str:
    if exc.problem == "not_a_directory":
        return f"--save-runs {exc.path!r} is not a directory"
    if exc.problem == "not_creatable":
        return f"--save-runs directory {exc.path!r} cannot be created here"
    if exc.problem == "holds_output":
        return (f"--save-runs {exc.path!r} would hold the sweep file -o {exc.clash!r}; "
                f"write the sweep file outside the run files' directory")
    return (f"--save-runs {exc.path!r} already holds {exc.clash!r}; use --overwrite to "
            f"replace its run files, or --resume")


def _resume_mismatch(exc: Any) -> str:
    drop = "the changes" if exc.what == "configuration" else "--grid"
    return f"{exc.stem()}; --resume continues the file's sweep: drop {drop} or start a new sweep"


def _sweep_write_failed(exc: Any) -> str:
    return (f"{exc.kept_text()}; free space, then continue with: rodjit sweep --resume -o "
            f"{exc.output}")


def _sweep_interrupted(exc: Any) -> str:
    if exc.output is None:
        return str(exc.stem)
    return f"{exc.stem}; continue with: rodjit sweep --resume -o {exc.output}"


def _too_many_steps(exc: Any) -> str:
    return f"{exc.stem()} (raise it with --max-steps / max_steps=)"


def _file_too_large(exc: Any) -> str:
    return str(exc.worded("--max-output / max_output="))


def _output_not_regular(exc: Any) -> str:
    return f"{exc.stem()} (with or without --overwrite)"


def _output_other_kind(exc: Any) -> str:
    return str(exc.worded("--overwrite"))


def _file_cut_short(exc: Any) -> str:
    return (f"{exc.stem()}: continue it with 'rodjit run --resume {exc.path}' (or 'rodjit "
            f"sweep --resume -o {exc.path}') once there is space")


def _run_write_failed(exc: Any) -> str:
    return f"{exc.stem()}; free space, then continue with: rodjit run --resume {exc.path}"


def _run_interrupted(exc: Any) -> str:
    if exc.path is None:
        return str(exc.stem)
    return f"{exc.stem}; continue with: rodjit run --resume {exc.path}"


def _not_on_device(exc: Any) -> str:
    return str(exc.worded(f" (--{exc.option.replace('_', '-')})"))


def _dask_missing(exc: Any) -> str:
    return str(exc.worded(f"--scheduler {exc.scheduler}"))


def _format_not_continued(exc: Any) -> str:
    return str(exc.worded("--resume"))


def _bad_plot_option(exc: Any) -> str:
    return str(exc.worded(lambda keyword: f"--{keyword}"))


# the wording of each typed error, by the module and name of its class
WORDINGS: dict[str, Callable[[Any], str]] = {
    "rodjit.output.h5files.OutputExists": output_exists,
    "rodjit.sweeps.errors.TooManyPoints": _too_many_points,
    "rodjit.sweeps.errors.BadGridItem": _bad_grid_item,
    "rodjit.sweeps.errors.SweepFileTooLarge": _sweep_file_too_large,
    "rodjit.sweeps.errors.RunsDirUnusable": _runs_dir_unusable,
    "rodjit.sweeps.errors.ResumeMismatch": _resume_mismatch,
    "rodjit.sweeps.errors.SweepWriteFailed": _sweep_write_failed,
    "rodjit.sweeps.outcome.SweepInterrupted": _sweep_interrupted,
    "rodjit.sweeps.errors.DaskMissing": _dask_missing,
    "rodjit.sweeps.errors.FormatNotContinued": _format_not_continued,
    "rodjit.output.errors.TooManySteps": _too_many_steps,
    "rodjit.output.errors.FileTooLarge": _file_too_large,
    "rodjit.output.errors.OutputNotRegular": _output_not_regular,
    "rodjit.output.errors.OutputOtherKind": _output_other_kind,
    "rodjit.output.h5files.FileCutShort": _file_cut_short,
    "rodjit.driver.errors.RunWriteFailed": _run_write_failed,
    "rodjit.driver.files.RunInterrupted": _run_interrupted,
    "rodjit.gpu.executor.NotOnDevice": _not_on_device,
    "rodjit.plotting.sweep_options.BadPlotOption": _bad_plot_option,
}


def word(exc: BaseException) -> str:
    """The command line's line for ``exc``.

    Parameters
    ----------
    exc : BaseException
        An error the API raised.

    Returns
    -------
    str
        Its wording in the command line's options if its type (or a base type) has one,
        else its own text.
    """
    for cls in type(exc).__mro__:
        wording = WORDINGS.get(f"{cls.__module__}.{cls.__qualname__}")
        if wording is not None:
            return wording(exc)
    return str(exc)
