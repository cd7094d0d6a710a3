"""The model of MODEL.md as data and plain NumPy: stress laws, the semi-discrete system, a reference."""

from .. import _lazy

# ``rodjit.model.NAME`` imports that submodule on first use (``rodjit._lazy``)
__getattr__ = _lazy.submodules(__name__)
