"""The run file's public API in one import: ``from rodjit.output import hdf5``.

The work is split by job: ``h5files`` (opening, kind checks, writer liveness),
``run_layout`` (the layout and its builder), ``run_reader`` (reading a file back,
``load_file``) and ``run_writer`` (``RunWriter``, its checkpoint commit, creating,
reopening and recovering files).  This module gathers their public names, the ones the
README and user scripts name as ``rodjit.output.hdf5.<name>``.
"""
from __future__ import annotations

from .h5files import FileBusy, NotARunFile, check_kind, open_file, writer_alive
from .run_layout import (CLOCK_NAMES, COUNT_NAMES, EV_NAMES, FORMAT_VERSION, KIND, STATUSES,
                         TABLES)
from .run_reader import (check_run_file, load_file, read_checkpoint, read_config, read_table,
                         read_x)
from .run_writer import RunWriter, create_run_file, recover, reopen_run_file

__all__ = ["KIND", "FORMAT_VERSION", "STATUSES", "TABLES", "RunWriter", "NotARunFile",
           "FileBusy", "open_file", "check_kind", "check_run_file", "read_config",
           "read_checkpoint", "read_table", "read_x", "load_file", "create_run_file", "reopen_run_file",
           "recover", "writer_alive", "CLOCK_NAMES", "COUNT_NAMES", "EV_NAMES"]
