"""The model of MODEL.md as data and plain NumPy: stress laws, the semi-discrete system, a reference."""
