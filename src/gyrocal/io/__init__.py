"""The edges: campaign directories and their CSV and YAML files, importer mappings, scenario
files, and results written whole or not at all."""

__all__ = ["calibration", "campaign_yaml", "importer", "outputs", "scenario", "telemetry", "yamlfile"]
