"""A campaign's maneuvers made ready for any fit: sliced, the gyro attitude propagated from the
reference, the error angles of eq. 4, and the inertial holds around each rotation."""

__all__ = ["holds", "preprocess"]
