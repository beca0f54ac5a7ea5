"""Are the maneuvers independent at the star tracker's fitted correlation time?

The model takes each maneuver's noise as independent of the others' (each has its own
nuisance and its own Gauss-Markov start, `gyrocal.inference.markov`). A real star tracker's
slow error runs on through the gaps between maneuvers: where a gap is short against the
fitted correlation time, the error at the end of one maneuver carries into the next, the
parameters both inform have errors correlated in a way the model does not know, and their
intervals come out too narrow (docs/validation.md, "Gauss-Markov star-tracker noise").
"""

import itertools

import numpy as np

from gyrocal.checks.finding import Finding, Status

__all__ = ["CHECK", "CORRELATION_MAX", "gap_check", "gaps"]

CHECK = "maneuvers independent"

CORRELATION_MAX = 0.05
"""The Gauss-Markov error's correlation across a gap, ``exp(-gap / tau)``, above which the gap
is short (gaps under 3 tau)."""


def gaps(maneuvers) -> list:
    """``(earlier id, later id, gap in s)`` of consecutive maneuvers in time, from the last reference
    sample of one to the first of the next, within each noise group: maneuvers of different groups are
    separate recordings or trials (`gyrocal import` makes a group per file and puts the files one
    sample apart), whose errors are independent however close their times."""
    ordered = sorted(maneuvers, key=lambda d: d.st_time[0])
    return [(a.id, b.id, float(b.st_time[0] - a.st_time[-1])) for a, b in itertools.pairwise(ordered)
            if a.noise_group == b.noise_group]


def gap_check(maneuvers, tau_s: float | None) -> Finding | None:
    """A warning where consecutive maneuvers are closer than the star tracker's Gauss-Markov error
    remembers (correlation ``exp(-gap / tau_s)`` above `CORRELATION_MAX`); None for white noise
    (``tau_s`` None)."""
    if tau_s is None:
        return None
    pairs = gaps(maneuvers)
    if not pairs:
        return Finding(CHECK, Status.PASS, "no two consecutive maneuvers in one noise group: nothing to correlate")
    rho = np.exp(-np.array([g for *_, g in pairs]) / tau_s)
    close = [(a, b, g, r) for (a, b, g), r in zip(pairs, rho) if r > CORRELATION_MAX]
    if not close:
        return Finding(CHECK, Status.PASS, f"every gap between maneuvers is over {-np.log(CORRELATION_MAX):.0f} times the "
                       f"star tracker's fitted correlation time ({tau_s:.3g} s)", figure=float(rho.max()),
                       threshold=CORRELATION_MAX)
    a, b, g, r = max(close, key=lambda c: c[3])
    why = (f"{len(close)} of {len(pairs)} gaps between maneuvers are short against the star tracker's fitted "
           f"correlation time ({tau_s:.3g} s); the shortest, {a} to {b}, is {g:.3g} s: the tracker's slow error "
           f"carries across it (correlation {r:.2f}), where the model takes the maneuvers as independent. "
           f"Intervals of the parameters both inform may be too narrow (docs/validation.md)")
    return Finding(CHECK, Status.WARN, why, figure=float(r), threshold=CORRELATION_MAX, where=f"{a}, {b}",
                   action=f"fly maneuvers at least {-np.log(CORRELATION_MAX) * tau_s:.0f} s apart (3 correlation times)")
