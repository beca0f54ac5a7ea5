"""gyrocal: in-flight gyro calibration from single-axis maneuvers and star-tracker data.

After Manjusha et al., "Gyro misalignment and scale factor error determination in
Mars Orbiter Mission". Physics is in pure array functions (`kinematics`, `channels`),
inference in `estimate` and `posterior`, I/O at the edges (`telemetry`, `report`).
"""

__version__ = "0.1.0"
