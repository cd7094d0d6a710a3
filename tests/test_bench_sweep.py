"""benchmarks/bench_sweep.py's baseline: a checkout compared against runs with its
ahead-of-time extension, as its install would have it (on the JIT every one of its
workers would pay Numba's start-up, which its users do not); and the CPU time of a
command's whole process tree, the processes it leaves behind included."""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_a_checkout_that_names_its_schemes_gets_one_entry_set_per_scheme(tmp_path, capsys):
    """A checkout whose ``aot`` names the schemes it compiles (``aot.schemes``) gets the
    default run's parameters with each, as its setup.py builds them."""
    tree = _checkout(tmp_path / "base")
    (tree / "rodjit/stepping/aot.py").write_text(
        _STUB["rodjit/stepping/aot.py"] + "def schemes():\n    return ('a', 'b')\n")
    (tree / "rodjit/config.py").write_text(
        "class Config:\n    def override(self, over):\n        return over\n")
    (tree / "rodjit/driver/setup.py").write_text("def parameters(config):\n    return config\n")
    bench_sweep.ahead_of_time(str(tree))
    assert (tree / "rodjit/stepping/built").read_text() == repr(
        [{"time.integrator": "a"}, {"time.integrator": "b"}])


def test_a_baseline_that_cannot_compile_it_says_it_runs_on_the_jit(tmp_path, capsys):
    tree = _checkout(tmp_path / "FAIL")
    bench_sweep.ahead_of_time(str(tree))
    out = capsys.readouterr().out
    assert "no ahead-of-time extension (RuntimeError: no C compiler); it runs on the JIT" in out
    assert not (tree / "rodjit/stepping/built").exists()


@pytest.mark.slow
def test_loop_pairs_times_both_trees_on_the_same_points(capsys):
    """The loop's cost per step in two trees at once (here: this tree against itself, so
    both take the same steps); a child that fails stops the benchmark."""
    here = str(Path(__file__).resolve().parents[1])
    r = bench_sweep.loop_pairs(here, here, rounds=2, points=((40.0, 1000.0, 0.05),
                                                              (70.0, 3000.0, 0.1)),
                               reps=1, t_end=0.05)
    assert r["steps_here"] == r["steps_baseline"] > 0
    assert len(r["here_ns"]) == len(r["baseline_ns"]) == 2
    # times only positive and finite: on a loaded machine one short run may be preempted
    assert all(0.0 < x < math.inf for x in r["here_ns"] + r["baseline_ns"])
    assert 0.0 < r["ratio"] < math.inf
    assert "the compiled loop per step on 2 grid points" in capsys.readouterr().out


def test_loop_pairs_stops_on_a_failing_child(tmp_path):
    here = str(Path(__file__).resolve().parents[1])
    broken = tmp_path / "broken"
    (broken / "rodjit").mkdir(parents=True)
    (broken / "rodjit" / "__init__.py").write_text("raise ImportError('not a rodjit')\n")
    with pytest.raises(SystemExit, match="a loop timing child exited 1"):
        bench_sweep.loop_pairs(here, str(broken), rounds=1, points=((40.0, 1000.0, 0.05),),
                               reps=1, t_end=0.05)


def test_descendants_walks_the_whole_tree_and_nothing_else():
    table = {1: (0, 0.0, 0), 2: (1, 0.0, 0), 3: (2, 0.0, 0), 4: (1, 0.0, 0),
             5: (9, 0.0, 0), 6: (5, 0.0, 0)}
    assert bench_sweep.descendants(1, table) == {1, 2, 3, 4}
    assert bench_sweep.descendants(5, table) == {5, 6}
    assert bench_sweep.descendants(7, table) == {7}


# in a child, so that this test process does not stay the reaper of later tests' orphans:
# a command that starts a process, which outlives it, burns 0.4 s of CPU and exits
_ORPHAN = """
import json, sys
sys.path.insert(0, sys.argv[1])
import bench_sweep
burn = "import time\\nt = time.process_time()\\nwhile time.process_time() - t < 0.4: pass"
command = [sys.executable, "-c",
           f"import subprocess, sys; subprocess.Popen([sys.executable, '-c', {burn!r}])"]
adopted = bench_sweep.adopt_orphans()
print(json.dumps({"adopted": adopted, **bench_sweep.cpu_run(command)}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux /proc and prctl")
def test_cpu_run_counts_the_processes_a_command_leaves_behind():
    """``rodjit sweep``'s fork server and workers outlive the command: their CPU time
    counts only once this process has adopted and reaped them."""
    bench = str(Path(__file__).resolve().parents[1] / "benchmarks")
    done = subprocess.run([sys.executable, "-c", _ORPHAN, bench], capture_output=True,
                          text=True, timeout=120, check=True)
    r = json.loads(done.stdout.strip().splitlines()[-1])
    assert r["adopted"]
    assert r["cpu"] >= 0.4
    assert r["wall"] < r["cpu"]          # the command itself returned before the burn ended
