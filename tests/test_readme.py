"""The README works as printed: its commands, run in order in one directory, and its Python
block, saved as a script and piped to ``python3 -``, do what the README says; nothing it
writes lands on a file of the repository (the examples: tests/test_examples.py)."""
from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"^```{lang}\n(.*?)^```$", README, re.M | re.S)


def _commands() -> list[str]:
    """The README's shell commands in order, each a line (continuations joined); the
    installs (``pip install``, which would change this environment) and the test suite
    itself (run by .ci/run, ``test_packaging``) left out of the part after their ``&&``."""
    out = []
    for block in _blocks("sh"):
        for line in block.replace("\\\n", " ").splitlines():
            parts = [p.strip() for p in line.split("&&")]
            parts = [p for p in parts if p and "pip install" not in p
                     and not p.startswith("python3 -m pytest")]
            if parts:
                out.append(" && ".join(parts))
    return out


@pytest.fixture
def shell(tmp_path):
    """Run a README line with bash in ``tmp_path``, ``rodjit`` being this interpreter's."""
    bindir = tmp_path / "bin"
    bindir.mkdir()
    shim = bindir / "rodjit"
    shim.write_text(f"#!/bin/sh\nexec {shlex.quote(sys.executable)} -m rodjit \"$@\"\n")
    shim.chmod(0o755)
    work = tmp_path / "work"
    work.mkdir()
    env = {**os.environ, "PATH": f"{bindir}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": os.pathsep.join([str(ROOT)] + [p for p in os.environ.get(
               "PYTHONPATH", "").split(os.pathsep) if p])}

    def run(line: str, stdin: str | None = None, args=None):
        return subprocess.run(args or ["bash", "-c", line], input=stdin, capture_output=True,
                              text=True, timeout=600, cwd=work, env=env)

    run.cwd = work
    return run


def _output_paths(line: str) -> list[str]:
    """The files a command line writes: ``-o PATH``, ``--output PATH``, ``> PATH``."""
    words = shlex.split(line, comments=True)
    out = [words[i + 1] for i, w in enumerate(words[:-1]) if w in ("-o", "--output", ">")]
    return out


def test_the_readme_has_the_commands_this_test_runs():
    commands = _commands()
    assert commands[0] == "rodjit run -o default.h5 --overwrite"
    assert any(c.startswith("rodjit run --resume n50.h5") for c in commands)
    assert any("rodjit plot paper-mu0.h5" in c for c in commands)
    assert len(_blocks("python")) == 1


def test_no_readme_command_writes_into_the_repository():
    """Run from the repository's root, no command would replace a file of the repository
    (the paper's figures are drawn into the current directory, not onto docs/).  What the
    README's own first command leaves there (``default.h5``, untracked) does not count: a
    newcomer runs the two top commands one after the other in the same clone."""
    import subprocess

    tracked = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True)
    files = (set(tracked.stdout.split()) if tracked.returncode == 0 else
             {str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file()})
    for line in _commands():
        for path in _output_paths(line):
            assert path not in files and not path.startswith("docs/"), line


# RMS difference of the README's pictures and a new drawing, in grey levels (0-255): a
# line moved by a pixel or a font's hinting stays under it, a curve that differs does not
PNG_TOL = 3.0


@pytest.mark.slow
def test_the_python_block_runs_as_a_script_then_every_command_in_order(shell):
    """One directory, the README's order: the first command, the Python block saved as
    ``script.py``, then every command of *Command line* and *The paper's figures*."""
    commands = _commands()
    first = shell(commands[0])
    assert first.returncode == 0, first.stderr
    assert (shell.cwd / "default.h5").is_file()
    (shell.cwd / "script.py").write_text(_blocks("python")[0])
    script = shell("", args=[sys.executable, "script.py"])
    assert script.returncode == 0, script.stderr[-3000:]
    assert "n50.h5: completed at t = 2 of 2" in script.stdout
    assert "MissingMainGuard" not in script.stderr and "Traceback" not in script.stderr
    import rodjit

    table = rodjit.load_sweep(shell.cwd / "mu.h5")
    assert table.status == "completed" and table.counts["completed"] == 4
    for line in commands[1:]:
        r = shell(line)
        assert r.returncode == 0, f"{line}\n{r.stderr[-2000:]}"
        for path in _output_paths(line):
            assert (shell.cwd / path).stat().st_size > 0, line
        if line.startswith("rodjit run --resume n50.h5"):     # extended past its end
            assert re.search(r"n50\.h5: completed at t = (\S+) of \1", r.stdout), r.stdout
    for png in ("n50.png", "paper_mu0.png", "paper_mu100.png"):
        assert (shell.cwd / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", png
    # the README's pictures are what its commands draw (regenerate them with those commands)
    from matplotlib.testing.compare import compare_images

    for png in ("paper_mu0.png", "paper_mu100.png"):
        diff = compare_images(str(ROOT / "docs" / png), str(shell.cwd / png), tol=PNG_TOL)
        assert diff is None, f"docs/{png} is not what the README's commands draw: {diff}"


def test_the_python_block_piped_to_python_says_why_the_workers_cannot_run(shell):
    """``python3 - < script.py``: the README says the sweep raises MissingMainGuard (the
    workers cannot read standard input again); before, every worker died of
    FileNotFoundError and the sweep file said completed."""
    r = shell("", stdin=_blocks("python")[0], args=[sys.executable, "-"])
    assert r.returncode == 1
    last = r.stderr.strip().splitlines()[-1]
    assert last.startswith("rodjit.sweeps.main_guard.MissingMainGuard: ") and \
        "standard input" in last, r.stderr[-2000:]
    assert "MissingMainGuard" in README and "python3 - < script.py" in README
    assert "FileNotFoundError" not in r.stderr
    assert not (shell.cwd / "mu.h5").exists()       # refused before the sweep file
