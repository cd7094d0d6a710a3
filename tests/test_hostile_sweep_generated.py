"""Hostile catalogue, generated: corrupted sweep files nobody wrote by hand.

Each case is drawn by a seeded random generator (``RODJIT_HOSTILE_SEED`` picks another
draw; the default is fixed so a failure reproduces) from a sweep file interrupted after 2
of its 4 points: a byte flipped with a random mask in the stored data of any dataset
(summary and key columns, the bounce table); one element changed to another value of its
dtype, in range or not; a dataset deleted, retyped or resized; a root attribute (or the
bounce table's ``rows``) deleted or given a random value; the file cut at a random length.
Every variant is shown (``info``) and continued (``sweep --resume``): refused in one line
with exit code 2 and the file untouched, or shown as it was written and continued to the
table of an uninterrupted sweep; never exit 0 with another table, never a Traceback.

CI runs ``CASES`` draws; ``-m slow`` runs ``SLOW_CASES`` more.
"""
from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest

import rodjit
from conftest import same_table
from test_hostile_files import _flip, invoke, partial_sweep, refusal, sha  # noqa: F401

SEED = int(os.environ.get("RODJIT_HOSTILE_SEED", "20261207"))
CASES = 30
SLOW_CASES = 240
KINDS = ("flip", "element", "delete", "retype", "resize", "attribute", "truncate")


def _datasets(path) -> list[str]:
    names: list[str] = []
    with h5py.File(path, "r") as f:
        f.visititems(lambda n, o: names.append(n) if isinstance(o, h5py.Dataset) else None)
    return sorted(names)


def _extents(path, name: str) -> list[tuple[int, int]]:
    """Where a dataset's data lie in the file: (offset, bytes) of each chunk, or of the
    one contiguous block."""
    with h5py.File(path, "r") as f:
        ds = f[name]
        if ds.chunks is None:
            offset = ds.id.get_offset()
            return [(offset, ds.id.get_storage_size())] if offset is not None else []
        out = []
        for k in range(ds.id.get_num_chunks()):
            info = ds.id.get_chunk_info(k)
            out.append((info.byte_offset, info.size))
        return out


def _value(rng, dtype, n: int):
    """Another value of ``dtype``: in range (a row number, a small or usual value, a
    status) or not (huge, negative, NaN, inf, text of any kind)."""
    if h5py.check_string_dtype(dtype) is not None:
        if dtype.kind == "S":
            return "".join(chr(c) for c in rng.integers(48, 103, 32)).encode()
        choices = ["pending", "completed", "failed", "", "lift-off", "no impact",
                   "".join(chr(c) for c in rng.integers(32, 127, 10))]
        return choices[rng.integers(len(choices))]
    if dtype.kind in "iu":
        choices = [int(rng.integers(-2, n + 3)), -1, 0, 1, int(rng.integers(-2**62, 2**62))]
        return np.array(choices[rng.integers(len(choices))]).astype(dtype)
    choices = [float(rng.normal()), 0.0, np.nan, np.inf, -np.inf,
               float(rng.normal() * 10.0 ** rng.integers(-300, 300))]
    return choices[rng.integers(len(choices))]


def _rewrite(f, name: str, data) -> None:
    del f[name]
    f.create_dataset(name, data=data)


def mutate(path, rng) -> str:
    """Corrupt ``path`` in one random way; what was done."""
    kind = KINDS[rng.integers(len(KINDS))]
    names = _datasets(path)
    name = names[rng.integers(len(names))]
    if kind == "flip":
        blocks = _extents(path, name)
        if not blocks or sum(b[1] for b in blocks) == 0:
            return f"{kind} {name}: no data stored"
        offset, size = blocks[rng.integers(len(blocks))]
        at, mask = int(rng.integers(size)), int(rng.integers(1, 256))
        _flip(path, offset + at, mask)
        return f"{kind} {name} byte {at} ^ {mask:#x}"
    if kind == "truncate":
        size = os.path.getsize(path)
        n = int(rng.integers(size))
        with open(path, "r+b") as fh:
            fh.truncate(n)
        return f"{kind} at {n} of {size}"
    with h5py.File(path, "r+") as f:
        if kind == "attribute":
            where = f["bounces"] if rng.integers(8) == 0 else f
            attr = sorted(where.attrs)[rng.integers(len(where.attrs))]
            how = ("delete", "text", "int", "float")[rng.integers(4)]
            if how == "delete":
                del where.attrs[attr]
            elif how == "text":
                where.attrs[attr] = "".join(chr(c) for c in rng.integers(32, 127, 12))
            elif how == "int":
                where.attrs[attr] = int(rng.integers(-2**62, 2**62))
            else:
                where.attrs[attr] = float(rng.normal() * 10.0 ** rng.integers(-300, 300))
            return f"{kind} {where.name}:{attr} {how}"
        ds = f[name]
        if kind == "delete":
            del f[name]
            return f"{kind} {name}"
        data = ds[()]
        if kind == "element":
            if data.size == 0:
                return f"{kind} {name}: empty"
            i = int(rng.integers(data.size))
            ds[i] = _value(rng, ds.dtype, int(f.attrs["n_points"]))
            return f"{kind} {name}[{i}] = {ds[i]!r}"
        if kind == "retype":
            if h5py.check_string_dtype(ds.dtype) is not None:
                new = [np.dtype("S40"), h5py.string_dtype("ascii")][rng.integers(2)]
                _rewrite(f, name, np.array([v if isinstance(v, bytes) else str(v).encode()
                                            for v in data], dtype=object).astype(new)
                         if new.kind == "S" else np.asarray(data, dtype=new))
            else:
                new = [np.int32, np.float32, np.float64, np.int64, np.uint8][rng.integers(5)]
                with np.errstate(invalid="ignore", over="ignore"):
                    _rewrite(f, name, np.asarray(data).astype(new))
            return f"{kind} {name} as {f[name].dtype}"
        # resize: a row more or less
        if rng.integers(2) and data.size:
            _rewrite(f, name, data[:-1])
        else:
            _rewrite(f, name, np.concatenate([data, data[-1:] if data.size else data]))
        return f"{kind} {name} to {f[name].shape}"


def check_sweep_contract(path, full, cut) -> str | None:
    """``info`` then ``sweep --resume`` of ``path``: each refused in one line (exit 2, the
    file untouched), or ``info`` shows the table as written (``cut``) and the resume ends
    in the uninterrupted sweep's table (``full``); the refusal line, if any."""
    before = sha(path)
    i = invoke("info", path)
    if refusal(i, path, before, "info") is None:
        assert i.exit_code == 0, i.output
        same_table(rodjit.load_sweep(path), cut)
    r = invoke("sweep", "--resume", "-o", path, "--scheduler", "inline", "-q")
    line = refusal(r, path, before, "resume")
    if line is not None:
        return line
    assert r.exit_code == 0, r.output
    table = rodjit.load_sweep(path)
    assert table.status == "completed"
    same_table(table, full)
    return None


def _case(partial_sweep, tmp_path, i: int) -> None:
    d, full = partial_sweep
    p = tmp_path / "s.h5"
    shutil.copy(d / "cut.h5", p)
    rng = np.random.default_rng([SEED, i])
    what = mutate(p, rng)
    try:
        check_sweep_contract(p, full, rodjit.load_sweep(d / "cut.h5"))
    except AssertionError as exc:
        raise AssertionError(f"case {i} (seed {SEED}): {what}: {exc}") from None


@pytest.mark.parametrize("i", range(CASES))
def test_generated_sweep_corruption(partial_sweep, tmp_path, i):
    _case(partial_sweep, tmp_path, i)


@pytest.mark.slow
@pytest.mark.parametrize("i", range(CASES, CASES + SLOW_CASES))
def test_generated_sweep_corruption_more(partial_sweep, tmp_path, i):
    _case(partial_sweep, tmp_path, i)


def test_the_draws_reach_every_kind():
    """The CI draws cover every kind of corruption (the generator is not stuck)."""
    seen = {KINDS[np.random.default_rng([SEED, i]).integers(len(KINDS))]
            for i in range(CASES)}
    assert seen == set(KINDS)
