"""Hostile catalogue, numbers: huge integers, subnormals, NaN and infinity wherever the
command line reads a number (--set, a TOML file, --grid, the options).  Each is refused in
one line naming the field, exit code 2, nothing written; or (a subnormal in range) runs.
The commands run in this process (click's runner: the same parsing and errors)."""
from __future__ import annotations

import pytest
from click.testing import CliRunner

from rodjit import cli

BIG = "9" * 400
TINY = ["--set", "time.t_end=0.02", "--set", "rod.N=3", "-q"]


def invoke(*args, cwd=None):
    return CliRunner().invoke(cli.main, [str(a) for a in args])


CASES = [
    # (name, arguments, text in the line)
    ("400-digit float key by --set", ["run", "--set", f"rod.mu={BIG}"], "rod.mu"),
    ("400-digit negative float key", ["run", "--set", f"rod.kappa=-{BIG}"], "rod.kappa"),
    ("400-digit int key by --set", ["run", "--set", f"rod.N={BIG}"], "rod.N"),
    ("400-digit t_end", ["run", "--set", f"time.t_end={BIG}"], "time.t_end"),
    ("400-digit dt", ["run", "--set", f"time.dt={BIG}"], "time.dt"),
    ("400-digit gravity", ["run", "--set", f"gravity.g={BIG}"], "gravity.g"),
    ("400-digit grid value", ["sweep", "--grid", f"rod.mu=1,{BIG}"], "rod.mu"),
    ("400-digit grid int", ["sweep", "--grid", f"rod.N=3,{BIG}"], "rod.N"),
    ("400-digit linspace count", ["sweep", "--grid", f"rod.mu=linspace(0,1,{BIG})"],
     "rod.mu"),
    ("400-digit linspace end", ["sweep", "--grid", f"rod.mu=linspace(0,{BIG},3)"],
     "rod.mu"),
    ("400-digit --t-end", ["run", *TINY, "--t-end", BIG], "time.t_end"),
    ("400-digit fit points", ["fit", "rod.mu", "--target", "restitution_first=0.5",
                              "--points", BIG], "points"),
    ("400-digit fit target", ["fit", "rod.mu", "--target", f"restitution_first={BIG}"],
     "restitution_first"),
    ("400-digit converge ladder", ["converge", "--ladder", f"rod.N=5,{BIG}"], "rod.N"),
    ("nan by --set", ["run", "--set", "rod.mu=nan"], "rod.mu"),
    ("inf by --set", ["run", "--set", "rod.mu=inf"], "rod.mu"),
    ("-inf by --set", ["run", "--set", "floor.beta=-inf"], "floor.beta"),
    ("nan height", ["run", "--set", "initial.height=nan"], "initial.height"),
    ("nan grid value", ["sweep", "--grid", "rod.mu=1,nan"], "rod.mu"),
    ("inf grid value", ["sweep", "--grid", "rod.kappa=inf,1"], "rod.kappa"),
    ("nan --t-end", ["run", *TINY, "--t-end", "nan"], "time.t_end"),
    ("inf --t-end", ["run", *TINY, "--t-end", "inf"], "time.t_end"),
    ("nan --flush-interval", ["run", *TINY, "--flush-interval", "nan"], "flush_interval"),
    ("400-digit --flush-interval", ["run", *TINY, "--flush-interval", BIG],
     "flush_interval"),
    ("nan --max-output", ["run", *TINY, "--max-output", "nan"], "size"),
    ("negative --max-output", ["run", *TINY, "--max-output", "-1G"], "size"),
    ("nan fit bracket", ["fit", "rod.mu", "--target", "restitution_first=0.5",
                         "--bracket", "nan,1"], "bracket"),
    ("inf fit bracket", ["fit", "rod.mu", "--target", "restitution_first=0.5",
                         "--bracket", f"0,{BIG}"], "bracket"),
    ("empty grid item", ["sweep", "--grid", "rod.mu=1,,2"], "empty"),
    ("empty first grid item", ["sweep", "--grid", "rod.mu=,1"], "empty"),
    ("subnormal below the resolution", ["run", "--set", "time.dt=5e-324"], "time.dt"),
    # a limit is raised, never turned off (NaN compares false) nor rounded in its message
    ("nan --max-points", ["sweep", "--grid", "rod.mu=0,1", "--max-points", "nan"],
     "--max-points nan"),
    ("inf --max-points", ["sweep", "--grid", "rod.mu=0,1", "--max-points", "inf"],
     "--max-points inf"),
    ("fractional --max-points", ["sweep", "--grid", "rod.mu=0,1", "--max-points", "1.5"],
     "--max-points 1.5"),
    ("zero --max-points", ["sweep", "--grid", "rod.mu=0,1", "--max-points", "0"],
     "--max-points 0"),
    ("nan --max-steps", ["run", *TINY, "--set", "time.dt=1e-3", "--max-steps", "nan"],
     "--max-steps nan"),
    ("inf --max-steps", ["run", *TINY, "--max-steps", "inf"], "--max-steps inf"),
    ("fractional --max-steps", ["run", *TINY, "--max-steps", "2.5"], "--max-steps 2.5"),
    ("400-digit --max-steps", ["run", *TINY, "--max-steps", BIG], "--max-steps 9"),
    ("nan --max-steps of a dry run", ["run", "--dry-run", *TINY, "--max-steps", "nan"],
     "--max-steps nan"),
    ("nan --max-points of a dry run", ["sweep", "--dry-run", "--grid", "rod.mu=0,1",
                                       "--max-points", "nan"], "--max-points nan"),
    ("nan --max-steps of converge", ["converge", "--ladder", "rod.N=3,5", "--max-steps",
                                     "nan"], "--max-steps nan"),
    ("inf --max-steps of fit", ["fit", "rod.mu", "--target", "restitution_first=0.5",
                                "--max-steps", "inf"], "--max-steps inf"),
    # fit's tolerance: a search that never stops (0, -1, nan) or stops at once (inf)
    *[(f"{v} --ftol", ["fit", "rod.mu", "--target", "restitution_first=0.5", "--ftol", v],
       f"ftol = {v} is out of range") for v in ("nan", "-1.0", "0.0", "inf")],
]


@pytest.mark.parametrize("name,args,text", CASES, ids=[c[0] for c in CASES])
def test_hostile_number(tmp_path, monkeypatch, name, args, text):
    monkeypatch.chdir(tmp_path)
    if args[0] in ("run", "sweep") and "-o" not in args:
        args = [*args, "-o", "n.h5"]
    r = invoke(*args)
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2, r.output
    assert len(lines) == 1 and lines[0].startswith("Error: "), r.stderr
    assert text in lines[0], lines[0]
    assert len(lines[0]) < 600            # a 400-digit number is not echoed whole
    assert list(tmp_path.iterdir()) == []


TOML = [
    ("400-digit float in TOML", f"[rod]\nmu = {BIG}\n", "rod.mu"),
    ("400-digit int in TOML", f"[rod]\nN = {BIG}\n", "rod.N"),
    ("nan in TOML", "[rod]\nkappa = nan\n", "rod.kappa"),
    ("inf in TOML", "[time]\nt_end = inf\n", "time.t_end"),
    ("inline table for a value", "[rod]\nmu = {a = 1}\n", "not a table"),
    ("array for a value", "[rod]\nmu = [1, 2]\n", "rod.mu"),
]


@pytest.mark.parametrize("name,text,want", TOML, ids=[c[0] for c in TOML])
def test_hostile_toml_number(tmp_path, monkeypatch, name, text, want):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "c.toml").write_text(text)
    r = invoke("run", "c.toml", "-o", "n.h5")
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert want in lines[0] and "did you mean" not in lines[0], lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.toml"]


def test_a_subnormal_in_range_runs(tmp_path, monkeypatch):
    """A subnormal where any value >= 0 is allowed is a number like any other."""
    monkeypatch.chdir(tmp_path)
    r = invoke("run", *TINY, "--set", "rod.mu=1e-320", "-o", "n.h5")
    assert r.exit_code == 0, r.output
    assert invoke("info", "n.h5").exit_code == 0
