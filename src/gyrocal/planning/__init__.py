"""Before flying: what a planned campaign will tell (Cramér-Rao bounds, detection) and a gyro's
noise from a static recording (Allan deviation)."""

__all__ = ["allan", "plan"]
