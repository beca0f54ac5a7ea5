"""The Monte Carlo validation study: simulated campaigns through the pipeline, and the tables and
figures of coverage, efficiency against the Cramér-Rao bound and SBC."""

__all__ = ["baseline", "campaign", "figures", "hidden", "looexact", "steps", "tables"]
