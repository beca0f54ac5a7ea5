"""A Mars-Orbiter-like spacecraft simulated from a scenario: the truth, telemetry and campaign files."""

__all__ = ["simulate"]
