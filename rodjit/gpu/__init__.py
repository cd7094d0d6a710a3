"""The GPU engine of sweeps: a batch of points, one CUDA thread per trajectory, running the
CPU's own compiled loop retargeted to the GPU (``retarget``; docs/gpu.md)."""
