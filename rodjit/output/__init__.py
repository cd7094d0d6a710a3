"""Writing runs to files: the HDF5 run file (``hdf5`` gathers its public API), split by job
into ``h5files``, ``run_layout``, ``run_reader``, ``run_writer`` and ``growing_table``; and
``summary``, what a run file says about its run."""
