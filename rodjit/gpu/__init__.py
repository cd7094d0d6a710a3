"""The GPU engine of sweeps: a batch of points, one CUDA thread per trajectory, running the
CPU's own compiled loop retargeted to the GPU (``retarget``; docs/gpu.md)."""

from .. import _lazy

# ``rodjit.gpu.NAME`` imports that submodule on first use (``rodjit._lazy``)
__getattr__ = _lazy.submodules(__name__)
