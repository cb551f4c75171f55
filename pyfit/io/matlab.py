"""The numeric variables of a MATLAB .mat file, in every format MATLAB saves: v4, v6 and v7 (MATLAB's default)
through scipy.io.loadmat, and v7.3 (`save(..., '-v7.3')`, the format MATLAB needs for variables over 2 GB)
through h5py, since a v7.3 file is an HDF5 file behind a 512-byte MATLAB header.

Both give the same thing: {name: array} of the real numeric variables with MATLAB's own dimensions (singleton
dimensions dropped, as loadmat's squeeze_me does), a 1x1 struct's fields named 'struct.field'. Text, cells,
logicals, complex values, empty arrays, struct arrays and objects (a table, a timetable) are left out: a
measurement's channels are real numbers.
"""
from __future__ import annotations

import pathlib

import numpy as np

# MATLAB_class of a v7.3 dataset holding real numbers (MATLAB's 'logical' and 'char' are stored as integers)
_NUMERIC_CLASSES = {b"double", b"single", b"int8", b"uint8", b"int16", b"uint16", b"int32", b"uint32", b"int64",
                    b"uint64"}


class MatlabFileError(ValueError):
    """The file is not a MATLAB file either reader can open."""


def _numeric(a) -> np.ndarray | None:
    """A real numeric array of one or two dimensions, squeezed; None for anything else."""
    a = np.asarray(a)
    if a.dtype.kind in "biuf":
        a = a.squeeze()
        return a if a.ndim in (1, 2) else None
    return None


def _v7_variables(path: pathlib.Path) -> dict[str, np.ndarray]:
    """v4 to v7: scipy.io.loadmat."""
    import scipy.io

    try:
        raw = scipy.io.loadmat(path, squeeze_me=True, struct_as_record=False)
    except (NotImplementedError, ValueError, TypeError, OSError, scipy.io.matlab.MatReadError) as exc:
        raise MatlabFileError(str(exc)) from exc
    found = {}
    for name, v in raw.items():
        if name.startswith("__"):
            continue
        fields = getattr(v, "_fieldnames", None)
        found.update({f"{name}.{f}": getattr(v, f) for f in fields} if fields else {name: v})
    return {n: a for n, a in ((n, _numeric(v)) for n, v in found.items()) if a is not None}


def _h5_numeric(item) -> np.ndarray | None:
    """A v7.3 dataset's real numbers in MATLAB's dimensions (HDF5 holds MATLAB's column-major array with its
    dimensions reversed), or None."""
    import h5py

    if not isinstance(item, h5py.Dataset) or item.attrs.get("MATLAB_empty", 0):
        return None
    if item.attrs.get("MATLAB_class", b"") not in _NUMERIC_CLASSES or item.attrs.get("MATLAB_int_decode", 0):
        return None
    return _numeric(item[()].T)


def _v73_variables(path: pathlib.Path) -> dict[str, np.ndarray]:
    """v7.3: an HDF5 file; a variable is a dataset, a 1x1 struct a group of datasets (struct arrays hold
    references, and MATLAB's '#refs#' and '#subsystem#' groups hold what cells and objects point to)."""
    import h5py

    found = {}
    try:
        with h5py.File(path, "r") as f:
            for name, item in f.items():
                if name.startswith("#"):
                    continue
                if isinstance(item, h5py.Group):
                    if item.attrs.get("MATLAB_class", b"") == b"struct":
                        found.update({f"{name}.{field}": _h5_numeric(v) for field, v in item.items()})
                else:
                    found[name] = _h5_numeric(item)
    except OSError as exc:
        raise MatlabFileError(str(exc)) from exc
    return {n: a for n, a in found.items() if a is not None}


def mat_variables(path: str | pathlib.Path) -> dict[str, np.ndarray]:
    """The real numeric variables of a MATLAB file of any format (v4 to v7.3), by name ('s.x' for a struct's
    field), each of one or two dimensions; raises MatlabFileError for a file that is not one."""
    import h5py

    path = pathlib.Path(path)
    return _v73_variables(path) if h5py.is_hdf5(path) else _v7_variables(path)
