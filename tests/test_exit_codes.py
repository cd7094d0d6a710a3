"""The exit codes: one table in ``rodjit --help`` and in docs/reference/cli.md, both equal
to ``rodjit.cli.EXIT_CODES``, and the codes the commands exit with are the table's."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from rodjit import cli

DOC = Path(__file__).resolve().parents[1] / "docs" / "reference" / "cli.md"


def _norm(text: str) -> str:
    return " ".join(text.replace("`", "").split())


def _help_table() -> dict[int, str]:
    out = CliRunner().invoke(cli.main, ["--help"]).output
    block = out.split("Exit codes (every verb):", 1)[1].split("Options:", 1)[0]
    table: dict[int, str] = {}
    code = None
    for line in block.splitlines():
        m = re.match(r"\s+(\d+)\s+(.*)", line)
        if m:
            code = int(m.group(1))
            table[code] = m.group(2)
        elif line.strip() and code is not None:
            table[code] += " " + line.strip()
    return {c: _norm(t) for c, t in table.items()}


def _doc_table() -> dict[int, str]:
    rows = re.findall(r"^\| (\d+) \| (.*) \|$", DOC.read_text(), re.M)
    return {int(c): _norm(t) for c, t in rows}


def test_help_table_is_the_codes_table():
    assert _help_table() == {c: _norm(t) for c, t in cli.EXIT_CODES.items()}


def test_docs_table_is_the_codes_table():
    assert _doc_table() == {c: _norm(t) for c, t in cli.EXIT_CODES.items()}


def test_the_commands_exit_with_the_table_codes():
    assert cli.UsageError("x").exit_code == cli.EXIT_USAGE == 2
    assert cli.RunFailed("x").exit_code == cli.EXIT_FAILED == 1
    assert {cli.EXIT_SIGNAL + 2, cli.EXIT_SIGNAL + 15} <= set(cli.EXIT_CODES)
    r = CliRunner().invoke(cli.main, ["run", "--set", "rod.N=0", "-o", "x.h5"])
    assert r.exit_code == cli.EXIT_USAGE and "rod.N" in r.output
    r = CliRunner().invoke(cli.main, ["config", "--set", "rod.N=5"])
    assert r.exit_code == cli.EXIT_OK
    # every code a command exits with is in the table
    source = Path(cli.__file__).read_text()
    for code in re.findall(r"sys\.exit\((\d+)\)", source):
        assert int(code) in cli.EXIT_CODES, code


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("args", [["config", "paper-mu100"], ["presets"], ["--help"]],
                         ids=["config", "presets", "help"])
def test_standard_output_on_a_full_disk_is_one_line_and_exit_1(tmp_path, args):
    """stdout refusing a write (``> /dev/full``) ended in a Traceback from the write:
    it is the one line of a refused write, exit 1, and nothing is left behind."""
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "rodjit", *args], stdout=full,
                           stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == cli.EXIT_FAILED, r.stderr
    assert lines == ["Error: could not write to standard output: No space left on device"]
    assert list(tmp_path.iterdir()) == []
