"""The pipeline: one function per step, the paths of a run, the fleet and the ``gyrocal`` command.
Only this package (and the study above it) reads and writes files by step; the library below never imports it."""

__all__ = ["cli", "paths", "readback", "run", "settings", "steps"]
