"""The script-without-guard check: worker processes are started by *spawn*, which imports
the user's main script again in every worker.  A script that calls ``rodjit.sweep`` at its
top level, outside ``if __name__ == "__main__":``, would start a sweep inside every worker
(multiprocessing forbids it and the worker dies), so every point failed.  ``check_main``
finds that before any worker starts and says what to add; so too a main script the workers
cannot read again (read from standard input or a pipe): spawn would fail to import it in
every worker.  With no main script (a notebook, the interactive interpreter, ``python -c``)
spawn imports nothing and no guard is needed."""
from __future__ import annotations

import ast
import multiprocessing
import os
import sys
from types import FrameType, ModuleType

__all__ = ["MissingMainGuard", "check_main"]

ADVICE = ('put the code that calls rodjit.sweep under  if __name__ == "__main__":  in {where} '
          '(worker processes import the main script again), or use jobs=1, scheduler="inline"')


class MissingMainGuard(RuntimeError):
    """``rodjit.sweep`` with worker processes was called from a script's top level outside
    ``if __name__ == "__main__":``, or from a main script the workers cannot import again
    (one read from standard input)."""


def _is_main_test(node: ast.expr) -> bool:
    """``__name__ == "__main__"`` (either order)."""
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1
            and isinstance(node.ops[0], ast.Eq)):
        return False
    sides = [node.left, node.comparators[0]]
    names = [s for s in sides if isinstance(s, ast.Name) and s.id == "__name__"]
    consts = [s for s in sides if isinstance(s, ast.Constant) and s.value == "__main__"]
    return bool(names and consts)


def _guarded(source: str, line: int) -> bool:
    """Whether line ``line`` of the module ``source`` lies inside a top-level
    ``if __name__ == "__main__":`` block (True also when the source cannot be parsed: the
    check then stays out of the way)."""
    try:
        tree = ast.parse(source)
    except SyntaxError:
        return True
    for stmt in tree.body:
        if stmt.lineno <= line <= (stmt.end_lineno or stmt.lineno):
            return isinstance(stmt, ast.If) and _is_main_test(stmt.test) and \
                any(s.lineno <= line <= (s.end_lineno or s.lineno) for s in stmt.body)
    return True


def _readable_again(path: str) -> bool:
    """Whether a spawned worker can read the main script ``path`` again: a regular file
    (relative paths from the directory the interpreter started in, as spawn reads them);
    not ``<stdin>``, a pipe such as ``/dev/fd/63`` or a file deleted since."""
    # ORIGINAL_DIR: where spawn's children start; set by multiprocessing.process at import
    # but absent from its type stubs.
    original_dir: str | None = getattr(multiprocessing.process, "ORIGINAL_DIR", None)
    if not os.path.isabs(path) and original_dir is not None:
        path = os.path.join(original_dir, path)
    return os.path.isfile(path)


def check_main() -> None:
    """Raise MissingMainGuard when this call comes (through any functions) from the top
    level of the main script outside its ``__main__`` guard, or from a worker's re-import
    of that script."""
    if multiprocessing.parent_process() is not None and "__mp_main__" in sys.modules:
        mp_main = sys.modules["__mp_main__"]
        raise MissingMainGuard("rodjit.sweep was started again inside a worker process: "
                               + ADVICE.format(where=getattr(mp_main, "__file__", "the script")))
    main: ModuleType | None = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if main is None or path is None:           # interactive, notebook, python -c: spawn
        return                                 # has no script to import again
    spec = getattr(main, "__spec__", None)
    if spec is not None and spec.name.endswith(".__main__"):   # python -m package: spawn
        return                                                 # does not import it again
    if spec is None and not _readable_again(path):
        where = ("standard input (python3 -)" if path == "<stdin>"
                 else f"{path!r}, which is not a file")
        raise MissingMainGuard(f"rodjit.sweep with worker processes was called from a main "
                               f"script read from {where}: worker processes import the main "
                               f"script again and cannot read it; save the script to a file "
                               f"and run python3 FILE, or use jobs=1, scheduler=\"inline\"")
    frame: FrameType | None = sys._getframe(1)
    while frame is not None:
        if frame.f_globals is main.__dict__ and frame.f_code.co_name == "<module>":
            try:
                with open(path, encoding="utf-8") as fh:
                    source = fh.read()
            except OSError:
                return
            if not _guarded(source, frame.f_lineno):
                raise MissingMainGuard(f"rodjit.sweep with worker processes was called at the "
                                       f"top level of {path} (line {frame.f_lineno}): "
                                       + ADVICE.format(where="the script"))
            return
        frame = frame.f_back
