"""The command line's structure: one module per verb, the shared options defined once, the
API's errors worded from their fields (never by rewriting their text), every exit code in
the table."""
from __future__ import annotations

import re
from pathlib import Path

import pytest
from click.testing import CliRunner

import rodjit.cli as cli
from rodjit.output.h5files import OutputExists

CLI = Path(cli.__file__).resolve().parent
SOURCES = {path.stem: path.read_text() for path in sorted(CLI.glob("*.py"))}


def test_each_verb_lives_in_its_own_module():
    modules = {name: command.callback.__module__ for name, command in cli.main.commands.items()}
    assert set(modules) == {"run", "sweep", "presets", "config", "info", "plot", "animate",
                            "converge", "fit", "restitution"}
    for name, module in modules.items():
        assert module == f"rodjit.cli.{name}", (name, module)


@pytest.mark.parametrize("flag", ["--set", "--quiet", "--jobs", "--scheduler", "--max-output",
                                  "--max-steps", "--progress/--no-progress"])
def test_a_shared_option_is_declared_once(flag):
    declared = [name for name, text in SOURCES.items()
                if re.search(rf"click\.option\([^)]*[\"']{re.escape(flag)}[\"']", text)]
    assert declared == ["options"], declared


def test_the_command_line_never_rewrites_an_error_text():
    for name, text in SOURCES.items():
        assert not re.search(r"str\(exc\)\.replace\(", text), name


def test_every_exit_code_of_every_verb_is_in_the_table():
    for name, text in SOURCES.items():
        for code in re.findall(r"sys\.exit\((\d+)\)", text):
            assert int(code) in cli.EXIT_CODES, (name, code)
        for code in re.findall(r"os\._exit\((\d+)\)", text):
            assert int(code) in cli.EXIT_CODES, (name, code)


def test_an_existing_output_is_a_typed_error_the_command_line_words(tmp_path, monkeypatch):
    exc = OutputExists(tmp_path / "x.h5")
    assert exc.path == str(tmp_path / "x.h5") and "overwrite=True" in str(exc)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "x.h5").write_bytes(b"")
    r = CliRunner().invoke(cli.main, ["run", "--dry-run", "-o", "x.h5"])
    assert r.exit_code == cli.EXIT_USAGE
    assert "output file 'x.h5' already exists; use --overwrite to replace it" in r.output
    assert "overwrite=True" not in r.output


def test_a_bad_at_pair_names_at():
    r = CliRunner().invoke(cli.main, ["plot", "nowhere.h5", "--at", "rod.mu"])
    assert r.exit_code == cli.EXIT_USAGE
