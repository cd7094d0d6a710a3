"""Hostile catalogue, corrupted files: a run file or a sweep file altered on disk (bytes
flipped at many offsets of each checkpoint dataset and of the stored configuration, the
file truncated at many lengths, attributes and objects deleted or edited, the checkpoint
slots swapped).  Every variant is continued (``run --resume``) and shown (``info``); the
contract: either one line on stderr with exit code 2 and the file left byte for byte as it
was, or exit 0 with a result identical to an uninterrupted run.  Never a Traceback, never
exit 0 with different data.

The command line runs in this process (click's runner: the same commands, parsing and
one-line errors as ``python -m rodjit``, without an interpreter start per case); a few
cases also go through a real subprocess (``test_real_command_line``)."""
from __future__ import annotations

import hashlib
import shutil

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from conftest import datasets, rodjit_cli
import rodjit
from rodjit import cli
from rodjit.output.run_layout import CK_DATASETS

RUN = ["--set", "time.t_end=0.3", "--set", "rod.N=3", "--set", "rod.mu=1", "-q",
       "--flush-interval", "0.0001"]
T_NEXT = "0.6"


def invoke(*args):
    return CliRunner().invoke(cli.main, [str(a) for a in args])


def sha(path) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    """A completed run file (both slots written), and the datasets of its uninterrupted
    continuations to t = T_NEXT: resumed from its checkpoint, and run in one go."""
    d = tmp_path_factory.mktemp("hostile_files")
    r = invoke("run", *RUN, "-o", d / "base.h5")
    assert r.exit_code == 0, r.output
    with h5py.File(d / "base.h5", "r") as f:
        assert not np.array_equal(f["checkpoint/slot0/clock"][()],
                                  f["checkpoint/slot1/clock"][()])   # both slots used
    shutil.copy(d / "base.h5", d / "ref.h5")
    assert invoke("run", "--resume", d / "ref.h5", "--t-end", T_NEXT, "-q").exit_code == 0
    r = invoke("run", *RUN, "--set", f"time.t_end={T_NEXT}", "-o", d / "straight.h5")
    assert r.exit_code == 0
    refs = [datasets(d / "ref.h5"), datasets(d / "straight.h5")]
    return d, refs


def _same(got, ref) -> bool:
    return got.keys() == ref.keys() and all(
        np.array_equal(got[k], ref[k], equal_nan=True) for k in ref)


def refusal(r, path, before, what: str = "") -> str | None:
    """A command on a hostile file: never a Traceback; exit 2 is one ``Error:`` line with
    the file as it was (``before``, its sha), returned; None where it did not refuse."""
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    assert "Traceback" not in r.output
    if r.exit_code != 2:
        return None
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error: "), r.stderr
    assert sha(path) == before, f"a refused {what} changed the file"
    return lines[0]


def check_contract(path, refs, expect_refusal: bool | None = None, info_ok=None):
    """Resume ``path`` to T_NEXT and show it: refused in one line (exit 2, the file
    untouched) or identical to an uninterrupted run.  ``expect_refusal``: True/False
    where the outcome is certain."""
    before = sha(path)
    r = invoke("run", "--resume", path, "--t-end", T_NEXT, "-q")
    line = refusal(r, path, before, "resume")
    if line is not None:
        assert expect_refusal is not False, line
        i = invoke("info", path)
        assert i.exit_code in (0, 2) and (i.exception is None or
                                          isinstance(i.exception, SystemExit))
        if i.exit_code == 2:
            assert len(i.stderr.strip().splitlines()) == 1
        return line
    assert r.exit_code == 0, r.output
    assert expect_refusal is not True, "a corrupted checkpoint was believed"
    got = datasets(path)
    assert any(_same(got, ref) for ref in refs), "exit 0 with different data"
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "completed"
    i = invoke("info", path)
    assert i.exit_code == 0, i.output
    return None


def _flip(path, offset: int, mask: int = 0xFF) -> None:
    with open(path, "r+b") as fh:
        fh.seek(offset)
        b = fh.read(1)
        fh.seek(offset)
        fh.write(bytes([b[0] ^ mask]))


def _extent(path, name: str) -> tuple[int, int]:
    with h5py.File(path, "r") as f:
        ds = f[name]
        return ds.id.get_offset(), ds.id.get_storage_size()


def _current(path) -> int:
    with h5py.File(path, "r") as f:
        return int(f["checkpoint/current"][()])


# ---- bytes flipped in each dataset of the checkpoint ---------------------------------------
FRACTIONS = (0.0, 0.5, 1.0)       # first, middle and last byte of the dataset


@pytest.mark.parametrize("frac", FRACTIONS, ids=["first", "middle", "last"])
@pytest.mark.parametrize("name", CK_DATASETS + ("digest",))
def test_flipped_byte_in_the_current_slot(base, tmp_path, name, frac):
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    offset, size = _extent(p, f"checkpoint/slot{_current(p)}/{name}")
    _flip(p, offset + min(size - 1, int(frac * size)))
    line = check_contract(p, refs, expect_refusal=True)
    assert "integrity check" in line


@pytest.mark.parametrize("name", CK_DATASETS + ("digest",))
def test_flipped_byte_in_the_idle_slot(base, tmp_path, name):
    """The slot not in use is not read: the resume is the uninterrupted run."""
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    offset, size = _extent(p, f"checkpoint/slot{1 - _current(p)}/{name}")
    _flip(p, offset + size // 2)
    check_contract(p, refs, expect_refusal=False)


@pytest.mark.parametrize("byte,mask", [(0, 0x01), (0, 0xFF), (0, 0x80), (3, 0x10), (7, 0x80),
                                       (7, 0x01)])
def test_flipped_byte_in_current(base, tmp_path, byte, mask):
    """/checkpoint/current naming the other slot (an older, valid checkpoint: the resume
    continues from it, the same run) or no slot (refused)."""
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    offset, _ = _extent(p, "checkpoint/current")
    _flip(p, offset + byte, mask)
    check_contract(p, refs, expect_refusal=(byte, mask) != (0, 0x01))


@pytest.mark.parametrize("where", [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_flipped_byte_in_the_stored_configuration(base, tmp_path, where):
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with h5py.File(p, "r") as f:
        text = f.attrs["config_toml"].encode()
    data = p.read_bytes()
    start = data.find(text)
    assert start > 0 and data.find(text, start + 1) < 0
    _flip(p, start + min(len(text) - 1, int(where * len(text))), 0x04)
    check_contract(p, refs, expect_refusal=True)


# ---- truncation ------------------------------------------------------------------------
@pytest.mark.parametrize("frac", [0.0, 0.01, 0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 0.99,
                                  0.999])
def test_truncated(base, tmp_path, frac):
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with open(p, "r+b") as fh:
        fh.truncate(int(frac * p.stat().st_size))
    check_contract(p, refs)


# ---- attributes and objects deleted or edited ----------------------------------------------
def _edit(kind):
    def apply(f):
        g = f[f"checkpoint/slot{int(f['checkpoint/current'][()])}"]
        if kind.startswith("del attr "):
            del f.attrs[kind[9:]]
        elif kind.startswith("del "):
            del f[kind[4:].replace("CUR", g.name)]
        elif kind == "status bogus":
            f.attrs["status"] = "bogus"
        elif kind == "format 99":
            f.attrs["format_version"] = 99
        elif kind == "kind sweep":
            f.attrs["rodjit_kind"] = "sweep"
        elif kind == "gravity edited":
            f.attrs["config_toml"] = f.attrs["config_toml"].replace("-9.81", "-1.0")
        elif kind == "config not TOML":
            f.attrs["config_toml"] = "[rod\nN = = 3"
        elif kind == "config N changed":
            f.attrs["config_toml"] = f.attrs["config_toml"].replace("N = 3", "N = 4")
        elif kind == "lengths + 10^6":
            g["lengths"][...] = g["lengths"][()] + 10**6
        elif kind == "lengths - 1":
            g["lengths"][...] = np.full(g["lengths"].shape, -1)
        elif kind == "clock edited":
            c = g["clock"][()]
            c[0] += 1e-3
            g["clock"][...] = c
        elif kind == "current 5":
            f["checkpoint/current"][...] = 5
        elif kind == "current other":
            f["checkpoint/current"][...] = 1 - int(f["checkpoint/current"][()])
        elif kind == "digest zeroed":
            g["digest"][...] = 0
        elif kind == "digest of the other slot":
            other = f[f"checkpoint/slot{1 - int(f['checkpoint/current'][()])}"]
            g["digest"][...] = other["digest"][()]
        elif kind == "slots swapped":
            f.move("checkpoint/slot0", "checkpoint/tmp")
            f.move("checkpoint/slot1", "checkpoint/slot0")
            f.move("checkpoint/tmp", "checkpoint/slot1")
        elif kind == "slots swapped and current flipped":
            f.move("checkpoint/slot0", "checkpoint/tmp")
            f.move("checkpoint/slot1", "checkpoint/slot0")
            f.move("checkpoint/tmp", "checkpoint/slot1")
            f["checkpoint/current"][...] = 1 - int(f["checkpoint/current"][()])
        elif kind == "both digests deleted":
            for i in (0, 1):
                del f[f"checkpoint/slot{i}/digest"]
        elif kind == "idle digest deleted":
            del f[f"checkpoint/slot{1 - int(f['checkpoint/current'][()])}/digest"]
        elif kind == "history a number":
            f.attrs["history"] = 12345
        elif kind == "history one text":
            f.attrs["history"] = "one line"
        elif kind == "snapshots cut":
            f["snapshots/u"].resize(1, axis=0)
        else:
            raise AssertionError(kind)
    return apply


# (edit, refused for certain: True, identical run for certain: False, either: None)
EDITS = [
    ("del attr config_toml", True), ("del attr status", True), ("del attr rodjit_kind", True),
    ("del attr format_version", True), ("status bogus", True), ("format 99", True),
    ("kind sweep", True), ("gravity edited", True), ("config not TOML", True),
    ("config N changed", True), ("lengths + 10^6", True), ("lengths - 1", True),
    ("clock edited", True), ("current 5", True), ("current other", False),
    ("digest zeroed", True), ("digest of the other slot", True), ("slots swapped", False),
    ("slots swapped and current flipped", False), ("snapshots cut", True),
    ("del CUR/state", True), ("del CUR/lengths", True), ("del snapshots/u", True),
    ("del checkpoint/current", True), ("del bounces", True),
    # a file of a format that has digests without them: not complete, never unchecked
    # a history that is not a list of lines is kept as one: continued, never half-opened
    ("history a number", False), ("history one text", False),
    ("both digests deleted", True), ("del CUR/digest", True), ("idle digest deleted", True),
]


@pytest.mark.parametrize("kind,refused", EDITS, ids=[e[0] for e in EDITS])
def test_edited(base, tmp_path, kind, refused):
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with h5py.File(p, "r+") as f:
        _edit(kind)(f)
    check_contract(p, refs, expect_refusal=refused)


def test_a_file_without_digests_gets_them_when_continued(base, tmp_path):
    """A file of a format before digests (none in either slot) is still read and
    continued (rebuilt in the current format), and the continued file has them."""
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with h5py.File(p, "r+") as f:
        f.attrs["format_version"] = 2
        for i in (0, 1):
            del f[f"checkpoint/slot{i}/digest"]
    check_contract(p, refs, expect_refusal=False)
    with h5py.File(p, "r") as f:
        assert all("digest" in f[f"checkpoint/slot{i}"] for i in (0, 1))
        g = f[f"checkpoint/slot{int(f['checkpoint/current'][()])}"]
        assert g["digest"][()].any()


@pytest.mark.parametrize("slots", [(0, 1), (0,), (1,)])
def test_a_file_claiming_digests_without_them_is_not_complete(base, tmp_path, slots):
    """Deleting the digests (of one slot or of both) does not make a current-format file
    look like one of a rodjit before digests: it is refused in one line, naming what is
    missing, by ``info`` and by ``--resume``, and left as it was."""
    d, _ = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with h5py.File(p, "r+") as f:
        for i in slots:
            del f[f"checkpoint/slot{i}/digest"]
    before = sha(p)
    for args in (("info", p), ("run", "--resume", p, "--t-end", T_NEXT, "-q")):
        r = invoke(*args)
        assert r.exit_code == 2, r.output
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and "not a complete rodjit file" in lines[0], r.stderr
        assert f"/checkpoint/slot{slots[0]}/digest' is missing" in lines[0]
    assert sha(p) == before


# ---- sweep files -----------------------------------------------------------------------
@pytest.fixture(scope="module")
def sweep_base(tmp_path_factory):
    d = tmp_path_factory.mktemp("hostile_sweeps")
    r = invoke("sweep", "--grid", "rod.mu=1,2", "--set", "time.t_end=0.02", "--set",
               "rod.N=3", "--scheduler", "inline", "-q", "-o", d / "s.h5")
    assert r.exit_code == 0, r.output
    return d


SWEEP_EDITS = ["del base_config_toml", "del grid", "del n_points", "del status",
               "n_points 3", "grid edited", "base edited", "status bogus", "summary cut",
               "digest edited", "del header_digest"]


@pytest.mark.parametrize("kind", SWEEP_EDITS)
def test_edited_sweep(sweep_base, tmp_path, kind):
    p = tmp_path / "s.h5"
    shutil.copy(sweep_base / "s.h5", p)
    with h5py.File(p, "r+") as f:
        if kind.startswith("del "):
            del f.attrs[kind[4:]]
        elif kind == "n_points 3":
            f.attrs["n_points"] = 3
        elif kind == "grid edited":
            f.attrs["grid"] = f.attrs["grid"].replace("2", "3")
        elif kind == "base edited":
            f.attrs["base_config_toml"] = f.attrs["base_config_toml"].replace("-9.81", "-1.0")
        elif kind == "status bogus":
            f.attrs["status"] = "bogus"
        elif kind == "summary cut":
            ds = f["summary/status"]
            data = ds[()]
            del f["summary/status"]
            f["summary"].create_dataset("status", data=data[:1])
        elif kind == "digest edited":
            f.attrs["header_digest"] = "0" * 32
    before = sha(p)
    for args in (("info", p), ("sweep", "--resume", "-o", p, "--scheduler", "inline", "-q")):
        r = invoke(*args)
        assert r.exit_code == 2 and (r.exception is None or
                                     isinstance(r.exception, SystemExit)), r.output
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("Error: "), r.stderr
        assert sha(p) == before


# ---- the real command line -----------------------------------------------------------------
@pytest.mark.parametrize("kind", ["lengths + 10^6", "gravity edited", "del attr config_toml"])
def test_real_command_line(base, tmp_path, kind):
    """The issue's three cases, through ``python -m rodjit``: one line, exit 2."""
    d, _ = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    with h5py.File(p, "r+") as f:
        _edit(kind)(f)
    before = sha(p)
    for args in (("info", p), ("run", "--resume", p, "--t-end", T_NEXT, "-q")):
        r = rodjit_cli(*args, cwd=tmp_path, timeout=120)
        lines = r.stderr.strip().splitlines()
        assert r.returncode == 2 and len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert sha(p) == before


# ---- a sweep file's columns prove themselves -------------------------------------------------
SWEEP_CONFIG = {"rod.N": 3, "time.t_end": 0.1, "initial.height": 0.005}
SWEEP_GRID = {"rod.mu": [1.0, 2.0], "floor.kappa_b": [1000.0, 3000.0]}


@pytest.fixture(scope="module")
def partial_sweep(tmp_path_factory):
    """A sweep file interrupted after 2 of its 4 points (each with bounce rows), and the
    table of the same sweep run in one go."""
    from test_sweep_driver import _interrupt_after

    d = tmp_path_factory.mktemp("hostile_sweep_columns")
    cfg = rodjit.Config().override(SWEEP_CONFIG)
    with pytest.raises(rodjit.SweepInterrupted):
        rodjit.sweep(cfg, SWEEP_GRID, output=d / "cut.h5", scheduler="inline", batch_size=1,
                     progress=_interrupt_after(2))
    cut = rodjit.load_sweep(d / "cut.h5")
    assert list(cut["status"]) == ["completed", "completed", "pending", "pending"]
    full = rodjit.sweep(cfg, SWEEP_GRID, output=d / "full.h5", scheduler="inline",
                        handle_signals=False)
    assert np.all(full["n_bounces"] > 0)
    return d, rodjit.load_sweep(d / "full.h5")


def refused_sweep(path, names: str) -> str:
    """``info`` and ``sweep --resume`` of ``path``: one line naming ``names``, exit 2, the
    file untouched; the line."""
    before = sha(path)
    for args in (("info", path), ("sweep", "--resume", "-o", path, "--scheduler", "inline",
                                  "-q")):
        r = invoke(*args)
        assert r.exit_code == 2 and (r.exception is None or
                                     isinstance(r.exception, SystemExit)), r.output
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("Error: "), r.stderr
        assert names in lines[0] and ("changed after rodjit wrote it" in lines[0]
                                      or "integrity check" in lines[0]), lines[0]
        assert sha(path) == before
    with pytest.raises(ValueError) as exc:
        rodjit.load_sweep(path)
    assert len(str(exc.value).splitlines()) == 1 and names in str(exc.value)
    return lines[0]


def _retype(f, name, dtype) -> None:
    data = f[name][()]
    del f[name]
    f.create_dataset(name, data=data.astype(dtype))


SWEEP_COLUMN_EDITS = {
    "bounce_start far past the table": ("/summary/bounce_start[0]", lambda f: f[
        "summary/bounce_start"].__setitem__(0, 10**9)),
    "pending rows marked completed": ("/summary/", lambda f: f["summary/status"].__setitem__(
        slice(2, 4), np.array(["completed"] * 2, dtype=object))),
    "a column retyped": ("/summary/steps", lambda f: _retype(f, "summary/steps", np.float64)),
    "the bounce table deleted": ("/bounces", lambda f: f.__delitem__("bounces")),
    "a bounce count below 0": ("/summary/bounce_count[1] = -1", lambda f: f[
        "summary/bounce_count"].__setitem__(1, -1)),
    "save_runs redirected": ("header_digest", lambda f: f.attrs.__setitem__(
        "save_runs", "elsewhere")),
}


@pytest.mark.parametrize("kind", SWEEP_COLUMN_EDITS)
def test_edited_sweep_columns(partial_sweep, tmp_path, kind):
    """Each edit is refused by info, --resume and load_sweep in one line naming what
    does not hold, the file untouched and nothing written (no run-file directory)."""
    d, _ = partial_sweep
    p = tmp_path / "s.h5"
    shutil.copy(d / "cut.h5", p)
    names, edit = SWEEP_COLUMN_EDITS[kind]
    with h5py.File(p, "r+") as f:
        edit(f)
    refused_sweep(p, names)
    assert sorted(x.name for x in tmp_path.iterdir()) == ["s.h5"]


def test_a_running_sweeps_table_keeps_its_own_pending_points(partial_sweep, tmp_path):
    """A table read while the sweep runs gives no bounce rows for the points it calls
    pending, though the file has them by the time they are asked for."""
    d, full = partial_sweep
    p = tmp_path / "s.h5"
    shutil.copy(d / "cut.h5", p)
    table = rodjit.load_sweep(p)
    rodjit.sweep(output=p, resume=True, scheduler="inline", handle_signals=False)
    rows = table.bounce_rows()
    assert set(rows["point"]) == {0, 1}
    assert table.bounces(2)["t_impact"].size == 0 < full.bounces(2)["t_impact"].size
    for i in (0, 1):
        assert np.array_equal(table.bounces(i)["t_impact"], full.bounces(i)["t_impact"])
