"""A lab recording as it comes, read into arrays: CSV (a column by its number), MATLAB ``.mat``
(`scipy.io.loadmat`; a v7.3 file is HDF5 and read as one) and HDF5 (`h5py`), a variable by its name
and a column of it by its number (from 1, as a spreadsheet and MATLAB count).

A mapping's ``format: {type: csv | mat | hdf5}`` says which; without ``type`` the file's suffix
does (``.mat``; ``.h5``, ``.hdf5``; anything else is CSV). A variable holds one sample per row:
one stored with its samples along the second axis (``3 x N``, as MATLAB v7.3 and some HDF5
writers store an ``N x 3`` array) is turned, and a vector is one column.

Every value read is a number: a cell that is not one is refused, naming the file, its line (CSV)
or its variable and row (MAT/HDF5), and the column. Only where the caller allows a missing value
(the reference quaternion, where a motion-capture system loses its markers) does an empty cell,
``NaN`` or a NaN in a binary file become NaN instead.
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from gyrocal.errors import excerpt
from gyrocal.io.yamlfile import TelemetryError

__all__ = ["BINARY", "BINARY_WORDS", "FORMATS", "MISSING_TEXT", "Table", "file_type", "printed_quantum", "read_table"]

FORMATS = ("csv", "mat", "hdf5")
BINARY = {".mat": "mat", ".h5": "hdf5", ".hdf5": "hdf5", ".he5": "hdf5"}
"""The file types a suffix names where the mapping gives no ``format.type``."""
BINARY_WORDS = "binary floats"
"""The precision of a binary file's numbers, in words (`printed_quantum`)."""
MISSING_TEXT = {"", "nan", "-nan", "+nan"}
"""What a CSV cell holds where a value is missing (matched lower-case, stripped)."""


def file_type(path, fmt: dict) -> str:
    """``csv``, ``mat`` or ``hdf5``: the mapping's ``format.type``, or the file's suffix."""
    return fmt.get("type") or BINARY.get(Path(path).suffix.lower(), "csv")


@dataclass
class Table:
    """One file's numbers. ``variables`` maps a name (``None`` for a CSV's one table) to an
    ``(N, k)`` float array; ``text`` holds a CSV's cells as printed, for their precision."""

    path: Path
    kind: str
    variables: dict
    text: pd.DataFrame | None = None
    first_line: int = 1
    """The line in a CSV of the first row of numbers (the lines before it are headers)."""
    scalars: dict = field(default_factory=dict)
    samples: tuple | None = None
    """(variable, rows) every column read must have as many rows as (`sampled_as`)."""

    @property
    def rows(self) -> int:
        return self.samples[1] if self.samples else len(next(iter(self.variables.values())))

    def sampled_as(self, variable, what: str):
        """Every column read from now on must have as many rows as ``variable`` (the gyro's): the
        importer reads the gyro and the reference at the same timestamps."""
        self.samples = (variable, len(self.array(variable, what)))

    def where(self, variable, row: int, column: int, what: str) -> str:
        """Where one cell is, in words: ``line 12, column 3 (gyro x)`` or ``variable imu_gyr, row 12,
        column 3 (gyro x)``; rows are counted from 1."""
        if self.kind == "csv":
            return f"line {row + self.first_line}, column {column} ({what})"
        return f"variable {variable}, row {row + 1}, column {column} ({what})"

    def lines(self) -> np.ndarray:
        """(N,) each row's line in a CSV (the first line is 1), or its row (from 1) in a variable."""
        return np.arange(self.rows) + (self.first_line if self.kind == "csv" else 1)

    def array(self, variable, what: str) -> np.ndarray:
        if variable not in self.variables:
            known = sorted(k for k in self.variables if k is not None)
            raise TelemetryError.at(self.path, f"the mapping's {what} is variable {variable!r}, which the file does "
                                               f"not hold", todo=f"the file holds {known}" if known else "")
        return self.variables[variable]

    def column(self, variable, number: int, what: str, missing_ok: bool = False) -> np.ndarray:
        """Column ``number`` (from 1) of ``variable`` (``None``: a CSV's table), as floats; a value
        that is not a finite number is refused, unless ``missing_ok`` and it is missing (NaN)."""
        values = self.array(variable, what)
        if not 1 <= number <= values.shape[1]:
            holds = f"the file has {values.shape[1]} columns" if variable is None else \
                f"variable {variable} has {values.shape[1]} columns ({values.shape[0]} x {values.shape[1]})"
            raise TelemetryError.at(self.path, f"the mapping's {what} is column {number}, but {holds}",
                                    todo="check the mapping's column numbers (counted from 1)")
        if self.samples and len(values) != self.samples[1]:
            raise TelemetryError.at(self.path, f"variable {variable} has {len(values)} rows, variable "
                                               f"{self.samples[0]} {self.samples[1]}: gyrocal reads the gyro and the "
                                               "reference at the same timestamps, one row each",
                                    f"variable {variable} ({what})",
                                    "resample one onto the other's times before importing")
        values = values[:, number - 1]
        bad = ~np.isfinite(values)
        if missing_ok:
            bad &= ~self._missing(variable, number, values)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            shown = excerpt(self.text.iloc[row, number - 1]) if self.text is not None else f"{values[row]}"
            raise TelemetryError.at(self.path, f"not a number: {shown} ({int(bad.sum())} such row{'s' if bad.sum() > 1 else ''})",
                                    self.where(variable, row, number, what),
                                    "fix or drop those rows, or check the mapping's column")
        return values

    def _missing(self, variable, number, values) -> np.ndarray:
        if self.text is None:
            return np.isnan(values)
        return self.text.iloc[:, number - 1].fillna("").str.strip().str.lower().isin(MISSING_TEXT).to_numpy()

    def printed(self, variable, number: int) -> pd.Series | None:
        """A CSV column's cells as printed; None for a binary file (its numbers are not printed)."""
        return None if self.text is None else self.text.iloc[:, number - 1]

    def scalar(self, variable: str, what: str) -> float:
        """One number a binary file holds (``sampling_rate``)."""
        if variable not in self.scalars:
            raise TelemetryError.at(self.path, f"the mapping's {what} is variable {variable!r}, which the file does "
                                               "not hold as one number")
        value = self.scalars[variable]
        if not (np.isfinite(value) and value > 0):
            raise TelemetryError.at(self.path, f"{what} must be a positive number, the file holds {value!r}",
                                    f"variable {variable}")
        return value


def read_table(path, fmt: dict, names) -> Table:
    """The file at ``path`` as a `Table`. ``names`` are the variables a binary file's mapping reads
    (only they are loaded)."""
    path = Path(path)
    kind = file_type(path, fmt)
    if not path.is_file():
        raise TelemetryError.at(path, "file not found")
    if kind == "csv":
        return _read_csv(path, fmt)
    names = sorted({n for n in names if n is not None})
    if kind == "mat":
        return _read_mat(path, names)
    return _read_hdf5(path, names)


def _read_csv(path: Path, fmt: dict) -> Table:
    header_rows = int(fmt.get("header_rows", 1))
    try:
        frame = pd.read_csv(path, sep=fmt.get("delimiter", ","), skiprows=header_rows, header=None, dtype=str,
                            keep_default_na=False)
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise TelemetryError(f"{path}: cannot be read with this mapping: {exc}") from exc
    values = frame.apply(pd.to_numeric, errors="coerce").to_numpy(dtype=float)
    return Table(path, "csv", {None: values}, frame, header_rows + 1)


def _samples_by_row(value) -> np.ndarray:
    """A variable as ``(N, k)`` floats: a vector is one column, a ``k x N`` array with fewer rows
    than columns is turned."""
    array = np.asarray(value, dtype=float)
    if array.ndim == 1:
        array = array[:, None]
    elif array.ndim == 2 and array.shape[0] < array.shape[1]:
        array = array.T
    return np.ascontiguousarray(array)


def _store(path, name, value, variables, scalars):
    array = np.asarray(value)
    if array.dtype.kind not in "biuf":
        return  # text (a trial's description), structures: not numbers, not read
    if array.size == 1:
        scalars[name] = float(array.reshape(-1)[0])
    if array.ndim > 2 and sum(s > 1 for s in array.shape) > 2:
        raise TelemetryError.at(path, f"variable {name} is a {array.ndim}-dimensional array {array.shape}: gyrocal "
                                      "reads vectors and matrices of one sample per row")
    variables[name] = _samples_by_row(array.squeeze() if array.ndim > 2 else array)


def _read_mat(path: Path, names) -> Table:
    import scipy.io

    try:
        raw = scipy.io.loadmat(path, variable_names=names or None)
    except NotImplementedError:  # MATLAB v7.3: an HDF5 file
        return _read_hdf5(path, names, kind="mat")
    except (OSError, ValueError, TypeError) as exc:
        raise TelemetryError.at(path, f"cannot be read as a MATLAB file: {exc}",
                                todo="check the mapping's format.type (csv, mat or hdf5)") from exc
    variables, scalars = {}, {}
    for name, value in raw.items():
        if not name.startswith("__"):
            _store(path, name, value, variables, scalars)
    return Table(path, "mat", variables, scalars=scalars)


def _read_hdf5(path: Path, names, kind: str = "hdf5") -> Table:
    import h5py

    variables, scalars = {}, {}
    try:
        with h5py.File(path, "r") as f:
            for name in names:
                item = f.get(name)
                if isinstance(item, h5py.Dataset):
                    _store(path, name, item[()], variables, scalars)
    except OSError as exc:
        raise TelemetryError.at(path, f"cannot be read as an HDF5 file: {exc}",
                                todo="check the mapping's format.type (csv, mat or hdf5)") from exc
    return Table(path, kind, variables, scalars=scalars)


_NUMBER = r"^\s*[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?\s*$"
"""A number as a file prints it: whole part, decimals, exponent."""


def printed_quantum(text, values) -> tuple:
    """The unit in the last place of each value of one column as the file prints it, and the
    column's precision in words. A column printed to a fixed number of decimals (``%.4f``) has
    one unit, 10^-decimals; one printed to significant digits (``%.5g``: 0.98275, 2.4976e-006)
    has a unit that scales with each value, 10^(exponent - digits + 1). Which one is read off the
    column: the most decimals and the most significant digits any value shows; each value's unit
    is the larger of the two readings, which is the right one in either case (a value printed as
    ``1`` among 5-digit ones stands for 1.0000). In words, a column whose values all show as many
    decimals is printed to decimals, any other to significant digits. ``text`` None: the values
    are binary floats, whose unit is their spacing (`numpy.spacing`)."""
    values = np.asarray(values, dtype=float)
    if text is None:
        return np.spacing(np.abs(values)), BINARY_WORDS
    if len(values) == 0:
        return np.zeros(0), "no values"
    parts = pd.Series(text, dtype=object).astype(str).str.extract(_NUMBER)
    whole, frac = parts[0].fillna(""), parts[1].fillna("")
    exponent = pd.to_numeric(parts[2], errors="coerce").fillna(0).to_numpy(dtype=float)
    shown = frac.str.len().to_numpy(dtype=float) - exponent
    decimals = float(shown.max())
    digits = float(max(1, (whole + frac).str.lstrip("0").str.len().max()))
    with np.errstate(divide="ignore"):
        by_digits = 10.0 ** (np.floor(np.log10(np.abs(values))) - digits + 1)
    if shown.min() < decimals:
        words = f"{digits:.0f} significant digit{'s' if digits != 1 else ''}"
    else:
        words = f"{decimals:.0f} decimal{'s' if decimals != 1 else ''}"
    return np.maximum(by_digits, 10.0 ** -decimals), words
