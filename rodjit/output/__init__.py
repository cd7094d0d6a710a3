"""Writing runs to files: the streaming HDF5 layout, its reader and checkpoints."""
