"""The command line's wording lives in ``rodjit/cli/``: the API's errors speak Python
(``overwrite=True``, ``max_points=``), and ``cli/wording.py`` words each typed error in the
command line's options (``--overwrite``, ``--max-points``)."""
from __future__ import annotations

import ast
import importlib
import re
from pathlib import Path

import pytest

from rodjit.cli.exits import RunFailed, UsageError
from rodjit.cli.wording import WORDINGS, word

PACKAGE = Path(__file__).resolve().parent.parent / "rodjit"
OPTION = re.compile(r"(?<![\w-])--[a-z][a-z-]*")
# the callables whose arguments are messages: warnings, and errors built anywhere (raised
# at once, returned to be raised, or a class's own message through super().__init__)
MESSAGE_CALL = re.compile(r"^(warn|[A-Z]\w*(Error|Exception|Warning|Failed|Interrupted|"
                          r"Missing|Exists|Busy|Unsupported|Unavailable))$")


def _callee(call: ast.Call) -> str:
    f = call.func
    if isinstance(f, ast.Attribute):
        if (f.attr == "__init__" and isinstance(f.value, ast.Call)
                and isinstance(f.value.func, ast.Name) and f.value.func.id == "super"):
            return "super().__init__"
        return f.attr
    return f.id if isinstance(f, ast.Name) else ""


def _strings(node: ast.AST):
    """The string constants inside ``node`` (an f-string's literal parts included)."""
    for n in ast.walk(node):
        if isinstance(n, ast.Constant) and isinstance(n.value, str):
            yield n


def _trees(root: Path) -> dict[Path, ast.Module]:
    return {path: ast.parse(path.read_text(), filename=str(path))
            for path in sorted(root.rglob("*.py"))
            if "cli" not in path.relative_to(root).parts}


def _error_classes(trees) -> set[str]:
    """The package's own exception classes by name (``NotARunFile``): those whose bases are
    errors by their names or, through each other, by theirs."""
    bases = {n.name: [b.id if isinstance(b, ast.Name) else getattr(b, "attr", "")
                      for b in n.bases]
             for tree in trees.values() for n in ast.walk(tree) if isinstance(n, ast.ClassDef)}
    errors: set[str] = set()
    while True:
        more = {name for name, of in bases.items() if name not in errors
                and any(MESSAGE_CALL.match(b) or b in errors for b in of)}
        if not more:
            return errors
        errors |= more


def option_messages(root: Path = PACKAGE) -> list[str]:
    """Every message string outside ``cli/`` that names a command-line option: in a
    ``raise``, a warning, or an error's construction (docstrings and comments do not
    count: they may say what the command line does)."""
    found = []
    trees = _trees(root)
    errors = _error_classes(trees)
    for path, tree in trees.items():
        messages = [n for n in ast.walk(tree) if isinstance(n, ast.Raise)
                    or (isinstance(n, ast.Call) and (MESSAGE_CALL.match(_callee(n))
                                                     or _callee(n) in errors
                                                     or _callee(n) == "super().__init__"))]
        for node in messages:
            for s in _strings(node):
                if OPTION.search(s.value):
                    found.append(f"{path.relative_to(root.parent)}:{s.lineno}: {s.value!r}")
    return sorted(set(found))


def test_no_message_below_the_command_line_names_an_option():
    assert option_messages() == []


# texts outside cli/ that name a command on purpose, by file and function: the status a
# stopped file keeps (file contents are a contract), and the report ``rodjit info`` prints
COMMAND_TEXTS = {
    ("rodjit/driver/errors.py", "resume_command"): "a run file's status message",
    ("rodjit/sweeps/errors.py", "resume_note"): "a sweep file's status message",
    ("rodjit/reports.py", "_about_run"): "what rodjit info says of a run file",
    ("rodjit/reports.py", "_about_sweep"): "what rodjit info says of a sweep file",
}


def test_no_other_text_below_the_command_line_names_an_option():
    """Beyond messages: no string outside ``cli/`` (docstrings aside) names an option, but
    for the few texts that name a command on purpose (``COMMAND_TEXTS``)."""
    found = set()
    for path, tree in _trees(PACKAGE).items():
        docs = {id(n.body[0].value) for n in ast.walk(tree)
                if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                  ast.AsyncFunctionDef))
                and n.body and isinstance(n.body[0], ast.Expr)}
        owner = {id(s): (f.name if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef))
                         else "<module>")
                 for f in [tree, *ast.walk(tree)]
                 if isinstance(f, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef))
                 for s in _strings(f)}      # the innermost function wins: walked last
        for s in _strings(tree):
            if id(s) not in docs and OPTION.search(s.value):
                found.add((str(path.relative_to(PACKAGE.parent)), owner[id(s)]))
    assert found == set(COMMAND_TEXTS)


def test_the_scan_finds_an_option_in_a_message(tmp_path):
    """The scan itself: a raise, a warning, an error built for later and an error's own
    message are found; a docstring, a comment and a plain text are not."""
    pkg = tmp_path / "rodjit"
    (pkg / "cli").mkdir(parents=True)
    (pkg / "cli" / "x.py").write_text('raise ValueError("use --overwrite")\n')
    (pkg / "m.py").write_text(
        '"""``--overwrite`` replaces a file."""\n'
        'import warnings\n'
        'HELP = "see --help"\n'
        'def f(p):\n'
        '    """rodjit run --resume"""\n'
        '    # --resume continues\n'
        '    if p:\n'
        '        raise ValueError(f"{p!r} exists; use --overwrite to replace it")\n'
        '    warnings.warn("raise it with --max-steps")\n'
        '    return WriteFailed(f"continue with: rodjit run --resume {p}")\n'
        'class E(ValueError):\n'
        '    def __init__(self, k):\n'
        '        super().__init__(f"--grid {k} is given twice")\n')
    found = option_messages(pkg)
    assert [line.split(":")[1] for line in found] == ["10", "13", "8", "9"], found


class _Table:
    status = "interrupted"


# one instance of every worded error, with what each wording must and must not say:
# (error, the command line's words, Python's words)
def _cases():
    from rodjit.driver.errors import RunWriteFailed
    from rodjit.driver.files import RunInterrupted
    from rodjit.gpu.executor import NotOnDevice
    from rodjit.output.errors import (FileTooLarge, OutputNotRegular, OutputOtherKind,
                                      TooManySteps)
    from rodjit.output.h5files import FileCutShort, OutputExists
    from rodjit.plotting.sweep_options import BadPlotOption
    from rodjit.sweeps.errors import (BadGridItem, DaskMissing, FormatNotContinued,
                                      ResumeMismatch, RunsDirUnusable, SweepFileTooLarge,
                                      SweepWriteFailed, TooManyPoints)
    from rodjit.sweeps.outcome import SweepInterrupted

    return [
        (OutputExists("x.h5"), "use --overwrite to replace it", "pass overwrite=True"),
        (TooManyPoints({"rod.mu": 2000, "floor.beta": 1000}, 1e6),
         "raise it with --max-points / max_points=", "raise it with max_points="),
        (BadGridItem("form", item="rod.mu"), "--grid expects KEY=VALUES (e.g. --grid rod.mu",
         "a grid item is KEY=VALUES"),
        (BadGridItem("twice", key="rod.mu"), "--grid rod.mu is given twice",
         "grid key rod.mu is given twice"),
        (BadGridItem("none"), "a sweep needs at least one --grid KEY=VALUES",
         "a sweep needs at least one KEY=VALUES grid item"),
        (SweepFileTooLarge(10**9, 2.0**40, 2.0**30), "raise it with --max-output / max_output=",
         "raise it with max_output="),
        (RunsDirUnusable("runs", "not_a_directory"), "--save-runs 'runs' is not a directory",
         "save_runs 'runs' is not a directory"),
        (RunsDirUnusable("runs", "not_creatable"), "--save-runs directory 'runs' cannot",
         "save_runs directory 'runs' cannot"),
        (RunsDirUnusable("runs", "holds", "0_rod.mu=0.h5"),
         "use --overwrite to replace its run files, or --resume",
         "pass overwrite=True to replace its run files, or resume=True"),
        (ResumeMismatch("s.h5", "configuration", "rod.N"),
         "--resume continues the file's sweep: drop the changes",
         "resume=True continues the file's sweep: drop the changes"),
        (ResumeMismatch("s.h5", "grid", "{}"), "--resume continues the file's sweep: drop --grid",
         "resume=True continues the file's sweep: drop grid="),
        (SweepWriteFailed("writing 's.h5' failed: disk full", "disk full", "s.h5", 3, 8),
         "continue with: rodjit sweep --resume -o s.h5", "continue with resume=True"),
        (SweepInterrupted("interrupted by SIGINT after 2 of 4 points", 2, _Table(), "s.h5"),
         "; continue with: rodjit sweep --resume -o s.h5", "continue with resume=True"),
        (DaskMissing("local"), "--scheduler local needs Dask distributed",
         "scheduler = 'local' needs Dask distributed"),
        (FormatNotContinued("s.h5", 1, 3), "; --resume continues format 3 only",
         "; resume=True continues format 3 only"),
        (TooManySteps(1e-12, 1.0, 1e12, 1e10), "raise it with --max-steps / max_steps=",
         "raise it with max_steps="),
        (FileTooLarge("the run", "many rows", 2.0**30, "1 GiB"),
         "raise it with --max-output / max_output=", "raise it with max_output="),
        (OutputNotRegular("fifo", "named pipe (FIFO)"), "(with or without --overwrite)",
         "(with or without overwrite=True)"),
        (OutputOtherKind("x.h5", "run", "sweep"), "--overwrite replaces only rodjit sweep",
         "overwrite=True replaces only rodjit sweep"),
        (FileCutShort("r.h5", 10, 20), "continue it with 'rodjit run --resume r.h5' (or "
         "'rodjit sweep --resume -o r.h5')", "continue it with resume_file('r.h5')"),
        (RunWriteFailed("r.h5", "disk full", 0.5),
         "free space, then continue with: rodjit run --resume r.h5",
         "free space, then continue with resume_file('r.h5')"),
        (RunInterrupted("interrupted by SIGINT at t = 0.5", 2, None, "r.h5"),
         "; continue with: rodjit run --resume r.h5", "; continue with resume_file('r.h5')"),
        (NotOnDevice("scheduler", "local"), "scheduler = 'local' (--scheduler) cannot",
         "scheduler = 'local' cannot"),
        (NotOnDevice("save_runs", "runs"), "save_runs (--save-runs) is not available",
         "save_runs is not available"),
        (BadPlotOption("not_swept", "at", "rod.nope", "rod.mu"),
         "--at 'rod.nope' is not a swept key", "at 'rod.nope' is not a swept key"),
        (BadPlotOption("quantity", "quantity", "nope", "bounces"),
         "--quantity 'nope' is not a numeric", "quantity 'nope' is not a numeric"),
        (BadPlotOption("too_many_lines", "", "40 lines (one per value of rod.N)"),
         "fix some keys with --at KEY=VALUE", "fix some keys with at KEY=VALUE"),
        (BadPlotOption("heatmap_only", "y"), "--y is for heatmaps", "y is for heatmaps"),
    ]


CASES = _cases()


@pytest.mark.parametrize("exc, cli, python", CASES,
                         ids=[f"{type(c[0]).__name__}-{i}" for i, c in enumerate(CASES)])
def test_the_command_line_names_the_option_python_the_keyword(exc, cli, python):
    line, own = word(exc), str(exc)
    assert cli in line and python in own, (line, own)
    assert line != own
    assert OPTION.search(line), line                 # the command line names its option
    assert not OPTION.search(own), own               # Python never does
    assert UsageError(exc).message == line and RunFailed(exc).message == line


def test_every_wording_is_of_a_real_error_and_tested():
    tested = {f"{type(c[0]).__module__}.{type(c[0]).__qualname__}" for c in CASES}
    assert set(WORDINGS) == tested
    for name in WORDINGS:
        module, _, cls = name.rpartition(".")
        assert issubclass(getattr(importlib.import_module(module), cls), Exception), name


def test_an_error_without_a_wording_is_its_own_text():
    assert word(ValueError("rod.N = 1 is out of range")) == "rod.N = 1 is out of range"


def test_worded_errors_keep_their_types_and_pickle():
    """Every typed error is still what callers caught (ValueError, or OSError for a refused
    write), and crosses a process boundary (a sweep's workers) with its fields."""
    import pickle

    for exc, _, _ in CASES:
        assert isinstance(exc, (ValueError, OSError, RuntimeError)), exc
        if type(exc).__name__ in ("SweepInterrupted", "RunInterrupted"):
            continue            # they hold a table, a summary: raised in the calling process
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc) and word(back) == word(exc)
