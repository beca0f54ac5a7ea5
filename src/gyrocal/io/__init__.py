"""The edges: campaign directories and their CSV and YAML files, the importer (mappings, readers,
recordings, maneuvers split at the rests), scenario files, the calibration table, and results written
whole or not at all. Its entry points, below, are imported when first asked for (`gyrocal.exports`)."""

from gyrocal.exports import lazy

_ENTRY_POINTS = {"read_campaign": "telemetry", "write_campaign": "telemetry", "TelemetryError": "yamlfile",
                 "import_files": "importer", "load_scenario": "scenario", "calibration_table": "calibration",
                 "write_csv": "outputs", "write_json": "outputs"}
"""Each entry point and the module it comes from."""

__all__ = sorted(_ENTRY_POINTS)
__getattr__, __dir__ = lazy(__name__, _ENTRY_POINTS)
