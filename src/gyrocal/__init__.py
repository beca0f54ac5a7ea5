"""gyrocal: in-flight gyro calibration from single-axis maneuvers and star-tracker data.

After Manjusha et al., "Gyro misalignment and scale factor error determination in
Mars Orbiter Mission". The packages, from the bottom layer up (docs/architecture.md):
`model` (the physics, pure functions on arrays), `io` (files), `inference` and `simulation`,
`checks`, `criticism`, `report` and `planning`, the `pipeline` and the validation `study`.
"""

__version__ = "0.1.0"

__all__ = ["__version__"]
