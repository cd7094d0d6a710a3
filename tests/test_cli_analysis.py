"""rodjit converge and rodjit fit on the command line."""
from __future__ import annotations

import h5py
from click.testing import CliRunner

from rodjit.cli import main


def _run(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_converge_writes_its_file_and_reports(tmp_path):
    out = tmp_path / "conv.h5"
    r = _run("converge", "paper-mu100", "--ladder", "rod.N=5,10,20", "--set", "rod.mu=1",
             "--set", "time.t_end=0.8", "--set", "output.snapshot_interval=0",
             "--observable", "restitution_first,contact_time_first", "-o", str(out), "-j", "1")
    assert r.exit_code == 0, r.output
    assert "restitution_first:" in r.output and "±" in r.output
    with h5py.File(out) as f:
        assert f.attrs["rodjit_kind"] == "convergence"
        assert list(f["observables/restitution_first/values"].shape) == [3]
    again = _run("converge", "paper-mu100", "--ladder", "rod.N=5,10,20", "-o", str(out))
    assert again.exit_code == 2 and "exists" in again.output


def test_converge_bad_input_exits_2_with_one_line():
    for args, text in ((["--ladder", "rod.N=20,10,5"], "refine"),
                       (["--ladder", "rod.N"], "KEY=VALUES"),
                       (["--observable", "nope"], "unknown observable"),
                       (["--also", "time.cfl=0.05,0.01"], "time.rtol")):
        r = _run("converge", *args)
        assert r.exit_code == 2, (args, r.output)
        assert text in r.output and r.output.count("\n") == 1


def test_fit_finds_mu_and_reports_unreachable_targets():
    common = ["--set", "time.t_end=1.5", "--set", "output.snapshot_interval=0", "-j", "1"]
    r = _run("fit", "rod.mu", "paper-mu100", "--target", "restitution_first=0.8",
             "--bracket", "0,3", *common)
    assert r.exit_code == 0, r.output
    assert "rod.mu = 0.18" in r.output
    r = _run("fit", "rod.mu", "paper-mu100", "--target", "restitution_first=0.99",
             "--bracket", "0,3", "--points", "3", *common)
    assert r.exit_code == 1 and "outside the range" in r.output


def test_fit_bad_input_exits_2():
    for args, text in ((["rod.mu"], "--target"),
                       (["rod.mu", "--target", "restitution_first=x"], "OBSERVABLE=NUMBER"),
                       (["rod.mu", "--target", "restitution_first=0.8", "--bracket", "1"],
                        "LO,HI"),
                       (["rod.mu,rod.kappa", "--target", "restitution_first=0.8"], "--table")):
        r = _run("fit", *args)
        assert r.exit_code == 2, (args, r.output)
        assert text in r.output


def test_fit_table_on_the_command_line(tmp_path):
    from rodjit.analysis.evaluate import evaluate
    import rodjit

    # N = 20: at N = 5 the chattering bottom node makes the restitution jump with μ
    base = rodjit.load_preset("paper-mu100").override({"time.t_end": 1.2, "rod.mu": 0.7,
                                                       "rod.N": 20,
                                                       "output.snapshot_interval": 0.0})
    res = evaluate([base.override({"initial.height": h}) for h in (0.5, 1.0)], jobs=1)
    p = tmp_path / "drops.csv"
    p.write_text("initial.height,restitution_first\n"
                 + "".join(f"{h},{x['restitution_first']!r}\n" for h, x in zip((0.5, 1.0), res)))
    r = _run("fit", "rod.mu", "paper-mu100", "--table", str(p), "--set", "time.t_end=1.2",
             "--set", "rod.mu=1.0", "--set", "rod.N=20", "--set", "output.snapshot_interval=0",
             "-j", "1")
    assert r.exit_code == 0, r.output
    assert "rod.mu = 0.7" in r.output and "row 2 restitution_first" in r.output


def test_converge_refuses_a_time_ladder_that_sets_no_steps_and_prints_predictability():
    common = ["paper-mu100", "--ladder", "rod.N=5,10", "--set", "time.t_end=0.6",
              "--set", "output.snapshot_interval=0.01", "--observable", "restitution_first",
              "-j", "1"]
    for integrator in ("dp54", "radau5"):
        r = _run("converge", *common, "--set", f"time.integrator={integrator}",
                 "--set", "time.control=cfl", "--also", "time.cfl=0.05,0.0125,0.003125")
        assert r.exit_code == 2 and r.output.count("\n") == 1, r.output
        assert "ladder time.rtol instead" in r.output
    r = _run("converge", *common, "--set", "time.integrator=verlet")
    assert r.exit_code == 2 and r.output.count("\n") == 1
    assert "time.control = 'cfl' and refine time.cfl" in r.output
    r = _run("converge", *common)
    assert r.exit_code == 0, r.output
    assert "time.rtol = 1e-06, 2.5e-07, 6.25e-08" in r.output
    assert "predictability_time: none before t_end = 0.6 s" in r.output
    r = _run("converge", *common, "--also", "none")
    assert r.exit_code == 0 and "predictability_time" not in r.output


def test_fit_table_with_a_ragged_row_is_one_line(tmp_path):
    """A row with more cells than the header raised an AttributeError (csv's key None)."""
    p = tmp_path / "drops.csv"
    p.write_text("initial.height,restitution_first\n0.5,0.8\n1.0,0.7,0.3\n")
    r = CliRunner().invoke(main, ["fit", "rod.mu", "--table", str(p)])
    lines = r.stderr.strip().splitlines()
    assert r.exit_code == 2 and len(lines) == 1, r.output
    assert "line 3: 3 cells, more than the 2 columns of the header" in lines[0]
    assert [q.name for q in tmp_path.iterdir()] == ["drops.csv"]


def test_converge_replaces_only_a_convergence_file_and_info_reads_it(tmp_path, monkeypatch):
    """``converge -o X --overwrite`` turned any file into HDF5 (a text file, a FIFO, a run
    file, its own configuration) and ``rodjit info`` could not read what it wrote: it
    refuses, before the study runs, what ``run -o`` refuses (one line, exit 2, the file as
    it was), and ``info`` reads a convergence file."""
    import hashlib
    import os

    import rodjit

    monkeypatch.chdir(tmp_path)
    study = ["converge", "cfg.toml", "--ladder", "rod.N=3,5", "--also", "none",
             "--observable", "min_u0", "-j", "1"]
    (tmp_path / "cfg.toml").write_text("[rod]\nmu = 1.0\n[time]\nt_end = 0.05\n")
    (tmp_path / "notes.txt").write_text("my notes\n")
    os.mkfifo(tmp_path / "pipe.h5")
    rodjit.run_to_file(rodjit.Config().override({"time.t_end": 0.02, "rod.N": 3}),
                       tmp_path / "run.h5")

    def digest():
        return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
                for p in tmp_path.iterdir() if p.is_file() and not p.name.endswith(".lock")}

    before = digest()
    for target, said in (("notes.txt", "'notes.txt' is not a rodjit file; --overwrite "
                                       "replaces only rodjit convergence files"),
                         ("cfg.toml", "'cfg.toml' is not a rodjit file"),
                         ("run.h5", "'run.h5' is a rodjit run file"),
                         ("pipe.h5", "'pipe.h5' is a named pipe (FIFO), not a regular file")):
        r = CliRunner().invoke(main, [*study, "-o", target, "--overwrite"])
        lines = r.stderr.strip().splitlines()
        assert r.exit_code == 2 and len(lines) == 1, r.output
        assert said in lines[0], lines[0]
    assert digest() == before
    r = CliRunner().invoke(main, [*study, "-o", "conv.h5"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["info", "conv.h5"])
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    assert lines[0].startswith("rodjit convergence file conv.h5 (format 2")
    assert "ladder    rod.N = 3, 5" in lines and "  mu = 1.0" in lines
    assert lines[2].startswith("command   rodjit converge cfg.toml --ladder rod.N=3,5")
    assert any(line.startswith("  min_u0: ") for line in lines), r.stdout
    r = CliRunner().invoke(main, [*study, "-o", "conv.h5", "--overwrite"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["animate", "conv.h5"])
    assert r.exit_code == 2 and "is a convergence file; animate draws run files" in r.stderr
