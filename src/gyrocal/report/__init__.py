"""What a reviewer reads: the pre-uplink HTML report, its figures and the fleet summary. It renders
findings and decides nothing."""

__all__ = ["context", "figures", "fleet", "review"]
