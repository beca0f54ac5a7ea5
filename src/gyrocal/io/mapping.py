"""An importer mapping (YAML): where each quantity sits in a user's files and in which units.

A mapping says which kind of file it reads (``format``: CSV, MATLAB ``.mat`` or HDF5), where the
time is (a column, a variable, or the rows counted at a sampling rate), the attitude reference's
quaternion columns and their order, the gyro columns and whether they hold rates or increments,
any extra columns to keep as candidate regressors, how the files become maneuvers, and what
``campaign.yaml`` should know (sensor class, noise, rate, range, mounting). In a MAT or HDF5
file a section names its ``variable`` and its columns are that variable's. A new format needs a
mapping, not code: gyrocal ships some in ``gyrocal/io/mappings/`` (``repoimu``: the RepoIMU
T-stick recordings, CSV; ``broad``: the BROAD trials, MATLAB). The mapping is checked against
``gyrocal/io/schemas/mapping.schema.json``, then here for what the schema does not say.
"""

from importlib import resources
from pathlib import Path

import numpy as np

from gyrocal.errors import excerpt
from gyrocal.io.telemetry import TelemetryError
from gyrocal.io.yamlfile import check_schema, read_yaml

__all__ = ["ANGLE_UNITS", "ORDERS", "RATE_UNITS", "check_interval", "declared_range_rad_s", "extra", "mapping_path",
           "read_mapping", "variable", "variables"]

ORDERS = {"xyzw": [0, 1, 2, 3], "wxyz": [1, 2, 3, 0]}
"""Where scalar-last ``q1..q4`` come from in each quaternion order a mapping may declare."""

RATE_UNITS = {"rad/s": 1.0, "deg/s": np.pi / 180.0}
ANGLE_UNITS = {"rad": 1.0, "deg": np.pi / 180.0}


def mapping_path(name_or_path) -> Path:
    """A shipped mapping by name (``repoimu``) or a user's mapping file."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        return path
    shipped = resources.files("gyrocal.io") / "mappings" / f"{name_or_path}.yaml"
    if not shipped.is_file():
        names = sorted(p.name.removesuffix(".yaml") for p in (resources.files("gyrocal.io") / "mappings").iterdir()
                       if p.name.endswith(".yaml"))
        raise TelemetryError(f"no mapping {name_or_path!r}: gyrocal ships {names}; or give a mapping file (.yaml)")
    return Path(str(shipped))


def read_mapping(name_or_path) -> dict:
    """A mapping, read by `gyrocal.io.yamlfile` and checked against its schema
    (``gyrocal/io/schemas/mapping.schema.json``: the sections, the orders, quantities, units and
    axes), then for what the schema does not say."""
    path = mapping_path(name_or_path)
    document = read_yaml(path)
    check_schema(document, "mapping")
    mapping = document.data
    gyro = mapping["gyro"]
    units = RATE_UNITS if gyro["quantity"] == "rate" else ANGLE_UNITS
    if gyro["unit"] not in units:
        raise TelemetryError(f"{path}: gyro.unit of a {gyro['quantity']} must be one of {sorted(units)}")
    check_interval(mapping["reference"].get("sample_interval_s"), f"{path}: reference.sample_interval_s")
    time = mapping["time"]
    ways = [k for k in ("column", "rate_hz", "rate_variable") if k in time] or (["variable"] if "variable" in time else [])
    if len(ways) != 1 or ("variable" in time and "rate" in ways[0]):
        raise TelemetryError.at(path, f"the time is given {len(ways) or 'no'} ways ({', '.join(sorted(time))})",
                                f"time (line {document.line(['time'])})",
                                "give one: column: N (a CSV), variable: name (with column: N for a matrix), "
                                "rate_hz: Hz, or rate_variable: name (a variable holding the rate)")
    options = mapping.get("maneuver") or {}
    if options.get("free") and "direction" in options:
        raise TelemetryError.at(path, "a free maneuver has no direction", f"maneuver (line {document.line(['maneuver'])})",
                                "drop maneuver.direction, or maneuver.free")
    unpaired = sorted(set(gyro["columns"]) ^ set(gyro["axes"]))
    if unpaired:
        raise TelemetryError.at(path, f"gyro.columns and gyro.axes must name the same channels; {unpaired} is in "
                                      "only one", f"gyro (line {document.line(['gyro'])})")
    return mapping


def variable(section: dict):
    """The variable a section's columns are in (a MAT or HDF5 file), or None (a CSV's one table)."""
    return (section or {}).get("variable")


def variables(mapping) -> list:
    """Every variable a mapping reads from a MAT or HDF5 file."""
    time = mapping["time"]
    names = [variable(time), time.get("rate_variable"), variable(mapping["reference"]), variable(mapping["gyro"])]
    names += [e.get("variable") for e in (mapping.get("extras") or {}).values() if isinstance(e, dict)]
    return names


def extra(spec) -> tuple:
    """An extra's variable and column: ``N`` (a CSV column) or ``{variable, column}``."""
    return (spec.get("variable"), int(spec.get("column", 1))) if isinstance(spec, dict) else (None, int(spec))


def declared_range_rad_s(mapping) -> float | None:
    """The gyro's range a mapping declares (``gyro.range``, in its gyro unit: a rate unit, or an
    angle unit per second for increments), in rad/s; None if it declares none."""
    gyro = mapping["gyro"]
    value = gyro.get("range")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise TelemetryError(f"the mapping's gyro.range must be a positive number (in {gyro['unit']}"
                             f"{'' if gyro['quantity'] == 'rate' else ' per second'}), got {excerpt(value)}")
    units = RATE_UNITS if gyro["quantity"] == "rate" else ANGLE_UNITS
    return float(value) * units[gyro["unit"]]


def check_interval(interval_s, where: str):
    """A reference sample interval is ``None`` or a number of seconds >= 0 (0: every row)."""
    if interval_s is not None and not (isinstance(interval_s, (int, float)) and interval_s >= 0):
        raise TelemetryError(f"{where} must be a number of seconds >= 0 (0: every row), got {excerpt(interval_s)}")
