"""``rodjit info``: one path lays out every kind of file (header, details, configuration,
report); the command prints exactly what ``reports.info`` returns."""
import h5py
import pytest
from click.testing import CliRunner

import rodjit
from rodjit import reports
from rodjit.cli import main


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("info")
    cfg = rodjit.Config().override({"time.t_end": 0.3, "rod.N": 6})
    rodjit.run_to_file(cfg, d / "run.h5", command="rodjit run test")
    rodjit.sweep(cfg, {"rod.mu": [0, 1]}, output=d / "sweep.h5", jobs=1, scheduler="inline",
                 command="rodjit sweep test")
    return d


@pytest.mark.parametrize("kind, title", [("run", "configuration:"),
                                         ("sweep", "base configuration:")])
def test_both_kinds_share_the_layout(files, kind, title):
    path = str(files / f"{kind}.h5")
    text = reports.info(path)
    lines = text.splitlines()
    version = 3   # run and sweep files: format 3
    assert lines[0].startswith(f"rodjit {kind} file {path} (format {version}, written by rodjit ")
    assert lines[1].startswith("created   ") and lines[2] == f"command   rodjit {kind} test"
    assert lines[3] == "status    completed"
    _, about = reports.about(path)
    assert lines[4:4 + len(about.details)] == about.details
    assert lines[4 + len(about.details)] == title
    assert "  [rod]" in lines and text.endswith(about.report)


@pytest.mark.parametrize("kind", ["run", "sweep"])
def test_the_command_prints_what_info_returns(files, kind):
    path = str(files / f"{kind}.h5")
    r = CliRunner().invoke(main, ["info", path])
    assert r.exit_code == 0, r.output
    assert r.output == reports.info(path) + "\n"


def test_a_new_kind_is_one_reader(files, monkeypatch, tmp_path):
    """A reader registered for a kind goes through the same layout as runs and sweeps."""
    path = tmp_path / "other.h5"
    with h5py.File(path, "w") as f:
        f.attrs["rodjit_kind"] = "other"
        f.attrs["created"] = "today"
    with pytest.raises(ValueError, match="rodjit 'other' file, which this version"):
        reports.info(path)

    def other(p):
        return reports.About(7, {"created": "today"}, "fine", ["details"],
                             "settings:", rodjit.Config(), "the report")
    monkeypatch.setitem(reports.READERS, "other", other)
    lines = reports.info(path).splitlines()
    assert lines[0] == f"rodjit other file {path} (format 7, written by rodjit ?)"
    assert lines[1:6] == ["created   today", "command   ?", "status    fine", "details",
                          "settings:"]
    assert lines[-1] == "the report"


def test_not_a_rodjit_file_is_a_one_line_error(tmp_path):
    path = tmp_path / "plain.h5"
    with h5py.File(path, "w"):
        pass
    with pytest.raises(ValueError, match="no 'rodjit_kind' attribute"):
        reports.info(path)
    r = CliRunner().invoke(main, ["info", str(path)])
    assert r.exit_code == 2 and "no 'rodjit_kind' attribute" in r.output
    assert len(r.output.strip().splitlines()) == 1
