"""Importing numba-cuda, the optional dependency of the GPU engine (``rodjit[cuda]``)."""
from __future__ import annotations

import numpy as np

__all__ = ["import_cuda", "CudaUnavailable"]

EXTRA = "pip install 'rodjit[cuda]'"


class CudaUnavailable(ValueError):
    """The GPU engine cannot run here (numba-cuda missing, no GPU): one line saying why."""


def import_cuda():
    """``numba.cuda``, or CudaUnavailable naming the extra that brings it.

    numba-cuda 0.30 still calls ``np.row_stack``, which NumPy 2.5 removed: the alias
    (``np.vstack``, which it always was) is restored before the import where missing."""
    if not hasattr(np, "row_stack"):
        np.row_stack = np.vstack
    try:
        # the NVIDIA target (numba-cuda), not Numba's deprecated built-in ``numba.cuda``,
        # which imports without it but lacks what the engine uses
        import numba_cuda  # noqa: F401
        from numba import cuda
    except ImportError as exc:
        raise CudaUnavailable(f"device = 'cuda' needs numba-cuda, which is not installed "
                              f"({exc}): {EXTRA}") from None
    if getattr(cuda, "implementation", "") != "NVIDIA":
        raise CudaUnavailable(f"device = 'cuda' needs numba-cuda, but numba.cuda is Numba's "
                              f"built-in CUDA target: {EXTRA}")
    return cuda
