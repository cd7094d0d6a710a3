"""Hostile catalogue, generated: corrupted checkpoints nobody wrote by hand.

Each case is drawn by a seeded random generator (``RODJIT_HOSTILE_SEED`` picks another
draw; the default is fixed so a failure reproduces): a byte flipped with a random mask at a
random offset of any dataset of either checkpoint slot, of ``/checkpoint/current`` or of
the stored configuration; one element of the current slot moved by one ulp; the file cut at
a random length; a root attribute deleted or given a random value; datasets swapped between
the slots, or the slots swapped, with ``current`` kept or flipped.  Every variant is
continued (``run --resume``) and shown (``info``) under the contract of
``test_hostile_files.check_contract``: refused in one line with exit code 2 and the file
untouched, or identical to an uninterrupted run; never exit 0 with different data.  Where
the outcome is certain (a change inside the slot in use: refused; a change to the slot not
in use: the uninterrupted run) the case asserts it.

CI runs ``CASES`` draws; ``-m slow`` runs ``SLOW_CASES`` more.
"""
from __future__ import annotations

import os
import shutil

import h5py
import numpy as np
import pytest

from rodjit.output.run_layout import CK_DATASETS
from test_hostile_files import _current, _extent, _flip, base, check_contract  # noqa: F401

SEED = int(os.environ.get("RODJIT_HOSTILE_SEED", "20261205"))
CASES = 120
SLOW_CASES = 1000
SLOT_DATASETS = CK_DATASETS + ("digest",)
ROOT_ATTRS = ("config_toml", "status", "format_version", "rodjit_kind", "message",
              "history", "command", "created", "rodjit_version")
KINDS = ("flip current slot", "flip idle slot", "flip current", "flip config", "ulp",
         "truncate", "attribute", "swap dataset", "swap slots")


def _swap(f, a: str, b: str) -> None:
    f.move(a, "checkpoint/tmp")
    f.move(b, a)
    f.move("checkpoint/tmp", b)


def mutate(path, rng) -> tuple[str, bool | None]:
    """Corrupt ``path`` in one random way: (what was done, refusal certain: True,
    identical run certain: False, either: None)."""
    kind = KINDS[rng.integers(len(KINDS))]
    cur = _current(path)
    if kind in ("flip current slot", "flip idle slot"):
        slot = cur if kind == "flip current slot" else 1 - cur
        name = SLOT_DATASETS[rng.integers(len(SLOT_DATASETS))]
        offset, size = _extent(path, f"checkpoint/slot{slot}/{name}")
        at, mask = int(rng.integers(size)), int(rng.integers(1, 256))
        _flip(path, offset + at, mask)
        return f"{kind} {name} byte {at} ^ {mask:#x}", slot == cur
    if kind == "flip current":
        offset, size = _extent(path, "checkpoint/current")
        at, mask = int(rng.integers(size)), int(rng.integers(1, 256))
        _flip(path, offset + at, mask)
        # the other slot (0 <-> 1) is an older valid checkpoint of the same run
        return f"{kind} byte {at} ^ {mask:#x}", None if (at, mask) == (0, 1) else True
    if kind == "flip config":
        with h5py.File(path, "r") as f:
            text = f.attrs["config_toml"].encode()
        data = open(path, "rb").read()
        start = data.find(text)
        at, mask = int(rng.integers(len(text))), int(rng.integers(1, 256))
        _flip(path, start + at, mask)
        return f"{kind} byte {at} ^ {mask:#x}", True
    if kind == "truncate":
        size = os.path.getsize(path)
        n = int(rng.integers(size))
        with open(path, "r+b") as fh:
            fh.truncate(n)
        return f"{kind} at {n} of {size}", None
    with h5py.File(path, "r+") as f:
        g = f[f"checkpoint/slot{cur}"]
        if kind == "ulp":
            name = ("state", "clock", "ev", "run_time", "compile_time")[rng.integers(5)]
            a = np.array(g[name][()], dtype=float)
            flat = a.reshape(-1)
            i = int(rng.integers(flat.size))
            flat[i] = np.nextafter(flat[i], np.inf if rng.integers(2) else -np.inf)
            g[name][...] = a
            return f"{kind} {name}[{i}]", True
        if kind == "attribute":
            name = ROOT_ATTRS[rng.integers(len(ROOT_ATTRS))]
            how = ("delete", "text", "int", "float")[rng.integers(4)]
            if how == "delete":
                del f.attrs[name]
            elif how == "text":
                f.attrs[name] = "".join(chr(c) for c in rng.integers(32, 127, 12))
            elif how == "int":
                f.attrs[name] = int(rng.integers(-2**62, 2**62))
            else:
                f.attrs[name] = float(rng.normal() * 10.0 ** rng.integers(-300, 300))
            # the configuration or the kind changed: certainly refused; the rest (status,
            # history, ...) may be believed, but the data must then be the same
            return f"{kind} {name} {how}", True if name in ("config_toml",
                                                            "rodjit_kind") else None
        if kind == "swap dataset":
            name = SLOT_DATASETS[rng.integers(len(SLOT_DATASETS))]
            same = np.array_equal(f[f"checkpoint/slot0/{name}"][()],
                                  f[f"checkpoint/slot1/{name}"][()])
            _swap(f, f"checkpoint/slot0/{name}", f"checkpoint/slot1/{name}")
            # equal in both slots (no event between the two checkpoints): nothing changed
            return f"{kind} {name}", not same
        flipped = bool(rng.integers(2))
        _swap(f, "checkpoint/slot0", "checkpoint/slot1")
        if flipped:
            f["checkpoint/current"][...] = 1 - cur
        # slots swapped with current flipped: the same checkpoint; kept: the older one,
        # whose digest proves it (the resume redoes the rows after it, the same run)
        return f"{kind}{' and current flipped' if flipped else ''}", False


def _case(base, tmp_path, i: int) -> None:
    d, refs = base
    p = tmp_path / "x.h5"
    shutil.copy(d / "base.h5", p)
    rng = np.random.default_rng([SEED, i])
    what, refused = mutate(p, rng)
    try:
        check_contract(p, refs, expect_refusal=refused)
    except AssertionError as exc:
        raise AssertionError(f"case {i} (seed {SEED}): {what}: {exc}") from None


@pytest.mark.parametrize("i", range(CASES))
def test_generated_corruption(base, tmp_path, i):
    _case(base, tmp_path, i)


@pytest.mark.slow
@pytest.mark.parametrize("i", range(CASES, CASES + SLOW_CASES))
def test_generated_corruption_more(base, tmp_path, i):
    _case(base, tmp_path, i)


def test_the_draws_reach_every_kind():
    """The CI draws cover every kind of corruption (the generator is not stuck)."""
    seen = set()
    for i in range(CASES):
        seen.add(KINDS[np.random.default_rng([SEED, i]).integers(len(KINDS))])
    assert seen == set(KINDS)
