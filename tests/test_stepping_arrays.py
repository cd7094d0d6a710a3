"""The compiled loop's arrays as one named structure (``stepping.arrays.RunArrays``): one
field list, from which a run's arrays, a batch's scratch, the ahead-of-time extension's
arguments and the GPU kernel's arrays are all made."""
import numba

import rodjit
from rodjit.driver.run import Run
from rodjit.gpu.kernel import _source, family_of
from rodjit.stepping import aot
from rodjit.stepping import arrays as A
from rodjit.stepping.arrays import BUFFERS, SPEC, RunArrays, allocate
from rodjit.sweeps.ensemble import _scratch


def test_allocate_makes_every_field_zeroed_with_its_dtype_and_shape():
    run = Run(rodjit.Config())
    a = allocate(7, run.scheme, 5, 6, 9)
    assert isinstance(a, RunArrays) and a._fields == tuple(SPEC)
    size = A.sizes(7, run.scheme, 5, 6, 9)
    for name, x in zip(a._fields, a):
        assert x.dtype == SPEC[name][0] and x.shape == A.shape(name, size), name
        assert x.flags.c_contiguous and not x.any()
    assert a.snap_u.shape == (5, 7) and a.diag.shape[0] == 6 and a.bounces.shape[0] == 9
    assert set(BUFFERS) == {"snap_t", "snap_step", "snap_u", "snap_v", "diag", "episodes",
                            "bounces"}


def test_a_run_and_a_batch_hold_the_same_structure():
    cfg = rodjit.Config()
    run = Run(cfg)
    scratch, imp = _scratch(cfg.rod.N + 1, run.scheme, run.arrays.snap_t.size,
                            run.arrays.diag.shape[0], run.arrays.bounces.shape[0])
    assert type(run.arrays) is type(scratch) is RunArrays
    for mine, theirs in zip(run.arrays, scratch):
        assert (mine.dtype, mine.shape) == (theirs.dtype, theirs.shape)
    assert imp.ndim == 1


def test_numba_types_it_as_a_tuple_of_the_arrays_themselves():
    """The loop's kernels take it as one argument: Numba types it as a named tuple of the
    arrays' own types (C-contiguous, no reflected or copied container), and a field read
    in compiled code is the caller's array, not a copy."""
    a = Run(rodjit.Config()).arrays
    t = numba.typeof(a)
    assert isinstance(t, numba.types.BaseNamedTuple) and t.instance_class is RunArrays
    assert all(isinstance(x, numba.types.Array) and x.layout == "C" for x in t.types)

    @numba.njit
    def poke(arrays):
        arrays.clock[0] = 42.0
        arrays.snap_u[1, 2] = -1.0

    poke(a)
    assert a.clock[0] == 42.0 and a.snap_u[1, 2] == -1.0


def test_the_extension_takes_the_fields_as_separate_arrays_of_their_types():
    for name, (_, extra) in aot.ENTRIES.items():
        exported = dict(aot._expand(extra))
        for field in RunArrays._fields:
            assert exported[field] == A.aot_type(field), (name, field)
    assert A.aot_type("state") == "f8[:,::1]" and A.aot_type("snap_step") == "i8[::1]"


def test_the_gpu_kernel_builds_it_from_local_arrays_and_its_rows_of_the_buffers():
    """The buffers are the point's rows of the kernel's arguments, the inputs (the listed
    output times) those arguments whole, shared by the threads, the other fields local
    arrays."""
    fam = family_of(Run(rodjit.Config().override({"rod.N": 9}))._args())
    src = _source(fam)
    size = {"n1": fam.n1, "work": fam.work_rows, "observed": max(1, fam.observed)}
    assert A.INPUTS == ("times",)
    for name in RunArrays._fields:
        if name in BUFFERS:
            assert f"{name}[i]" in src and f"{name} = cuda.local" not in src
        elif name in A.INPUTS:
            assert f"{name}[i]" not in src and f"{name} = cuda.local" not in src
        else:
            dims = A.shape(name, size)
            assert f"{name} = cuda.local.array({dims}, {SPEC[name][0].name})" in src
    fields = ", ".join(f"{n}[i]" if n in BUFFERS else n for n in RunArrays._fields)
    assert f"arrays = RunArrays({fields})" in src


def test_no_field_list_is_written_outside_stepping_arrays():
    """The field list is written once: a module that passed the loop's arrays one by one
    (a signature, a call, a tuple of them) would name them in a row; none does."""
    from pathlib import Path

    root = Path(rodjit.__file__).parent
    rows = ("trial, work, interp", "state, work, clock, count, ev",
            "count, ev, snap_t", "bounces, fail, imp")
    found = [(p.relative_to(root).as_posix(), row) for p in root.rglob("*.py")
             for row in rows if row in p.read_text(encoding="utf-8").replace("self.", "")]
    assert found == [], found
