"""Time stepping: integrator steps, step-size control, event tracking, the compiled loop."""

from .. import _lazy

# ``rodjit.stepping.NAME`` imports that submodule on first use (``rodjit._lazy``)
__getattr__ = _lazy.submodules(__name__)
