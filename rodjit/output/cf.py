"""netCDF-4 / CF conventions for rodjit's HDF5 files (format 2): the library-version bound
every file is written with, the root attributes CF names, a column's ``long_name`` and
``units`` (from ``records.metadata``), booleans as flagged ``int8``, and dimensions.

netCDF-C and xarray (h5netcdf) see an HDF5 file as netCDF-4 when every dimensioned dataset
has a dimension scale attached to each axis, visible from its own group or a parent group.
A dimension that has no values of its own (the checkpoint's rows) is a dimension scale
whose ``NAME`` starts with the phrase netCDF-C gives such dimensions.
"""
from __future__ import annotations

import h5py
import numpy as np

from ..records.metadata import UNIT_SYSTEM, meaning
from ..version import __version__

__all__ = ["LIBVER", "CONVENTIONS", "BOOL_DTYPE", "FLAG_MEANINGS", "root_attrs",
           "column_attrs", "pure_dimension", "as_bool"]

# HDF5 1.10 objects: the oldest file format that keeps SWMR writing (1.8 has no SWMR), so
# the HDF5 1.10 tools and netCDF-C of current distributions read every file
LIBVER = ("v110", "v110")
CONVENTIONS = "CF-1.10"
BOOL_DTYPE = np.int8                # booleans: 0 / 1 with flag_values, flag_meanings
FLAG_MEANINGS = {"open": "ended still_in_contact"}
REFERENCES = ("Aiki, M. and Kosugi, T., New approach for elastic collisions with singular "
              "stress functions (the model of docs/MODEL.md)")
_NO_VARIABLE = "This is a netCDF dimension but not a netCDF variable."


def root_attrs(title: str) -> dict:
    """The CF root attributes of a new file (``history`` is rodjit's own, kept apart)."""
    return {"Conventions": CONVENTIONS, "title": title,
            "source": f"rodjit {__version__} (https://pypi.org/project/rodjit/)",
            "references": REFERENCES, "units_system": UNIT_SYSTEM}


def column_attrs(table: str, column: str, dtype=None) -> dict:
    """``long_name``, ``units`` (and for a boolean column its flags) of one table column."""
    m = meaning(table, column)
    out: dict[str, object] = {"long_name": m.long_name, "units": m.units}
    if column in FLAG_MEANINGS or not m.units:
        out.pop("units")                # CF: flags and text have no units
    if column in FLAG_MEANINGS:
        out["flag_values"] = np.array([0, 1], BOOL_DTYPE)
        out["flag_meanings"] = FLAG_MEANINGS[column]
    return out


def pure_dimension(group: h5py.Group, name: str, size: int) -> h5py.Dataset:
    """A netCDF dimension ``name`` of ``size`` without a coordinate variable."""
    ds = group.create_dataset(name, shape=(size,), dtype=np.float32)
    ds.make_scale(f"{_NO_VARIABLE}{size:10d}")
    return ds


def as_bool(values) -> np.ndarray:
    """A boolean column as rodjit hands it out, from either format (bool or 0/1)."""
    return np.asarray(values).astype(bool)
