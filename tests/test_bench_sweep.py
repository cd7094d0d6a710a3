"""benchmarks/bench_sweep.py's baseline: a checkout compared against runs with its
ahead-of-time extension, as its install would have it (on the JIT every one of its
workers would pay Numba's start-up, which its users do not)."""
from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_sweep  # noqa: E402

# a checkout's modules as far as the build reaches them: aot builds a marker file
_STUB = {
    "rodjit/__init__.py": "",
    "rodjit/config.py": "class Config:\n    pass\n",
    "rodjit/driver/__init__.py": "",
    "rodjit/driver/run.py": ("class Run:\n    def __init__(self, config):\n        pass\n"
                             "    def _args(self):\n        return ('the default run',)\n"),
    "rodjit/stepping/__init__.py": "",
    "rodjit/stepping/aot.py": (
        "from pathlib import Path\n"
        "MARK = Path(__file__).parent / 'built'\n"
        "def _extension():\n"
        "    return (MARK.read_text() if MARK.exists() else None, None)\n"
        "def build(directory, args):\n"
        "    if 'FAIL' in Path(directory).parts[-3]:\n"
        "        raise RuntimeError('no C compiler')\n"
        "    (Path(directory) / 'built').write_text(repr(args))\n"),
}


def _checkout(root: Path) -> Path:
    for name, text in _STUB.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def test_a_baseline_without_its_extension_gets_it_compiled_once(tmp_path, capsys):
    tree = _checkout(tmp_path / "base")
    bench_sweep.ahead_of_time(str(tree))
    assert (tree / "rodjit/stepping/built").read_text() == "('the default run',)"
    assert "its ahead-of-time extension compiled" in capsys.readouterr().out
    bench_sweep.ahead_of_time(str(tree))             # usable now: nothing to do
    assert capsys.readouterr().out == ""


def test_a_baseline_that_cannot_compile_it_says_it_runs_on_the_jit(tmp_path, capsys):
    tree = _checkout(tmp_path / "FAIL")
    bench_sweep.ahead_of_time(str(tree))
    out = capsys.readouterr().out
    assert "no ahead-of-time extension (RuntimeError: no C compiler); it runs on the JIT" in out
    assert not (tree / "rodjit/stepping/built").exists()
