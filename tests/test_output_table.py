"""Tables of the run file: rows grow in chunk-sized blocks, whole chunks go to the file
directly (uncompressed) or through HDF5's filters, and a table reopens mid-chunk."""
import h5py
import numpy as np
import pytest

from rodjit.output.growing_table import Table


def test_table_writes_in_chunk_blocks_and_reopens(tmp_path):
    with h5py.File(tmp_path / "t.h5", "w", libver="latest") as f:
        g = f.create_group("g")
        for name in ("a", "b"):
            g.create_dataset(name, shape=(0, 2), maxshape=(None, 2), chunks=(4, 2), dtype="f8")
        table = Table.of([g["a"], g["b"]])
        rows = np.arange(22, dtype=float).reshape(11, 2)
        table.append((rows[:3], -rows[:3]))
        assert g["a"].shape[0] == 0 and table.length == 3     # waiting for a full chunk
        table.append((rows[3:10], -rows[3:10]))
        assert g["a"].shape[0] == 8                            # two full chunks written
        table.flush()
        assert g["a"].shape[0] == 10                           # partial chunk written, kept
        reopened = Table.of([g["a"], g["b"]])
        assert reopened.start == 8 and reopened.fill == 2
        reopened.append((rows[10:], -rows[10:]))
        reopened.flush()
        assert np.array_equal(g["a"][()], rows) and np.array_equal(g["b"][()], -rows)
        more = np.arange(100, 118, dtype=float).reshape(9, 2)
        reopened.append((more[:1], -more[:1]))       # completes the chunk at rows 8..11
        assert g["a"].shape[0] == 12 and reopened.fill == 0
        reopened.append((more[1:], -more[1:]))       # two whole chunks go straight through
        assert g["a"].shape[0] == 20 and reopened.fill == 0
        assert np.array_equal(g["a"][()], np.vstack([rows, more]))
        assert np.array_equal(g["b"][()], -np.vstack([rows, more]))


@pytest.mark.parametrize("compression", [None, "gzip", "lzf"])
def test_every_dtype_and_strided_columns_survive_direct_and_filtered_writes(tmp_path, rng,
                                                                           compression):
    """float rows, int and bool columns, and columns that are strided views (as drained
    diagnostics are), over many chunks in blocks of random sizes, with flushes between:
    the file holds exactly what was appended."""
    n = 3000
    u = rng.normal(size=(n, 7))
    table_rows = rng.normal(size=(n, 3))               # columns are strided views of this
    k = rng.integers(-10**12, 10**12, n)
    flag = rng.random(n) < 0.3
    with h5py.File(tmp_path / "t.h5", "w", libver="latest") as f:
        g = f.create_group("g")
        spec = {"u": ((7,), "f8"), "a": ((), "f8"), "b": ((), "f8"), "k": ((), "i8"),
                "flag": ((), bool)}
        for name, (row, dtype) in spec.items():
            g.create_dataset(name, shape=(0,) + row, maxshape=(None,) + row, chunks=(64,) + row,
                             dtype=dtype, compression=compression)
        f.swmr_mode = True
        table = Table.of(g[name] for name in spec)
        assert table.direct == (compression is None)
        i = 0
        while i < n:
            j = min(n, i + int(rng.integers(1, 300)))
            table.append((u[i:j], table_rows[i:j, 0], table_rows[i:j, 2], k[i:j], flag[i:j]))
            if rng.random() < 0.3:
                table.flush()
                assert g["u"].shape[0] == table.written == j
            i = j
        table.flush()
    with h5py.File(tmp_path / "t.h5", "r") as f:
        g = f["g"]
        assert np.array_equal(g["u"][()], u)
        assert np.array_equal(g["a"][()], table_rows[:, 0])
        assert np.array_equal(g["b"][()], table_rows[:, 2])
        assert np.array_equal(g["k"][()], k) and g["k"].dtype == np.int64
        assert np.array_equal(g["flag"][()], flag) and g["flag"].dtype == bool
