"""The sampler's budget: when to stop a posterior that will not converge, rather than run on.

The chains must be `min_tau_multiple` autocorrelation times long. Where the autocorrelation time
already measured (an underestimate on a short chain) asks for more steps than ``max_steps``
allows, or the sampling has taken ``max_seconds`` of wall-clock time, running on cannot converge:
sampling stops at once with the reason, and the caller says which parameters are slow and why.
"""

import logging
import time

import numpy as np

__all__ = ["SamplingBudget", "SamplingStopped"]

log = logging.getLogger("gyrocal")


class SamplingStopped(RuntimeError):
    """Sampling stopped before convergence: ``reason`` in words, ``tau`` the autocorrelation times (steps,
    ensembles by parameters) it stopped at."""

    def __init__(self, reason: str, tau: np.ndarray):
        super().__init__(reason)
        self.reason, self.tau = reason, np.asarray(tau)


class SamplingBudget:
    """A sampler's step and time budget, started when it is made (`stop` says when it is spent)."""

    def __init__(self, cfg: dict):
        self.max_steps = int(cfg["max_steps"])
        self.multiple = float(cfg["min_tau_multiple"])
        self.max_seconds = cfg.get("max_seconds")
        self.started = time.monotonic()

    def check(self, steps: int, tau: np.ndarray, spent: int = 0):
        """Raise `SamplingStopped` when the budget is spent (`stop`)."""
        if reason := self.stop(steps, tau, spent):
            raise SamplingStopped(reason, tau)

    def stop(self, steps: int, tau: np.ndarray, spent: int = 0) -> str:
        """Why sampling must stop after ``steps`` steps with autocorrelation times ``tau`` (steps, one
        per ensemble and parameter), or "" to go on. ``spent``: production steps discarded before these
        (`ensemble.REFIT_TAU_STEPS`), which count against ``max_steps`` too."""
        if not np.any(np.isfinite(tau)):
            return ""
        worst = float(np.nanmax(tau))
        needed = self.multiple * worst
        elapsed = time.monotonic() - self.started
        log.info("posterior: %d steps in %.0f s, autocorrelation time %.1f steps (%.0f steps needed)",
                 steps, elapsed, worst, needed)
        if spent + needed > self.max_steps:
            before = f" (and {spent} before the noise proposal was refitted)" if spent else ""
            return (f"after {steps} steps{before} the chains' autocorrelation time is already {worst:.0f} steps: "
                    f"converging needs {self.multiple:g} times that, {needed:.0f} steps, beyond sampler.max_steps = "
                    f"{self.max_steps}")
        if self.max_seconds and elapsed > self.max_seconds and steps < needed:
            return (f"after {elapsed:.0f} s (sampler.max_seconds = {self.max_seconds:g}) and {steps} steps the chains "
                    f"are {steps / worst:.0f} autocorrelation times ({worst:.0f} steps) long, of the "
                    f"{self.multiple:g} needed")
        return ""
