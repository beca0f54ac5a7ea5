"""Maneuvers whose star-tracker Gauss-Markov error runs on between them, as one likelihood.

A star tracker's slow error does not stop between maneuvers: where one follows another within a
few correlation times their errors are correlated, and a likelihood that takes them as independent
makes the intervals of the parameters both inform too narrow (docs/validation.md: 92.3 % at
tau 30 s with 20 s gaps). Consecutive maneuvers of one noise group (`chains`) are therefore one
series here, the Gauss-Markov filter (`markov`) running on across each gap with the gap's ``phi``
(on a clock of the angle turned too, `errormodel.gm_clock_steps`, the gap counts its time alone: the turn
between two maneuvers is not recorded).

The gyros' walk restarts at each maneuver (the propagation starts afresh from the star tracker).
In the chained series it is taken as running on, and each channel set's difference (its walk at
the end of the earlier maneuvers, a constant over the later one) is taken up by a free offset per
set, which for every later maneuver stands where the initial attitude error, one for all sets,
stood: the same span and more. The likelihood is then exact for a model that forgets only that the
sets restart together (with one set, it forgets nothing), and stays banded two samples deep.
The reference's timing jitter (`st_jitter`), white, is one more component at each sample, from each
maneuver's body rate there: the chain's is theirs end to end.
"""

import itertools

import numpy as np

from gyrocal.inference.noise import covariance

__all__ = ["MAX_CHAIN", "Chains", "build", "chains", "gaps_s"]


MAX_CHAIN = 6
"""At most this many maneuvers make one series. A chain's nuisance columns (each maneuver's own) all
enter its whitened right-hand sides, so a chain of m maneuvers costs m times a maneuver's columns over
all its rows: unbounded, the cost would grow with the square of the campaign. A longer run of
maneuvers is cut at its longest gaps, where the error has forgotten most, and the cut maneuvers are
taken as independent, as all were before."""


def _split(run: list, gaps: np.ndarray, max_members: int) -> list:
    """``run`` (time-ordered) cut at its longest gaps into pieces of at most ``max_members``."""
    if len(run) <= max_members:
        return [run]
    cut = int(np.argmax(gaps)) + 1
    return _split(run[:cut], gaps[:cut - 1], max_members) + _split(run[cut:], gaps[cut:], max_members)


def chains(maneuvers, max_members: int = MAX_CHAIN) -> list:
    """The maneuvers (indices into ``maneuvers``) that make one series each: consecutive in time
    within one noise group, in time order, at most ``max_members`` (`MAX_CHAIN`) to a series. Groups are
    separate recordings or trials (`gyrocal import` makes a group per file), whose errors are independent
    however close their times."""
    order = sorted(range(len(maneuvers)), key=lambda m: maneuvers[m].st_time[0])
    by_group = {}
    for m in order:
        by_group.setdefault(maneuvers[m].noise_group, []).append(m)
    pieces = [p for run in by_group.values() for p in _split(run, gaps_s(maneuvers, run), max_members)]
    return sorted(pieces, key=lambda c: c[0])


def gaps_s(maneuvers, chain) -> np.ndarray:
    """(len(chain) - 1,) the time from the last star-tracker sample of each maneuver to the first of the next
    (s); a maneuver that does not start after the one before it is refused (they would share samples)."""
    gaps = np.array([maneuvers[b].st_time[0] - maneuvers[a].st_time[-1] for a, b in itertools.pairwise(chain)],
                    dtype=float)
    if np.any(gaps <= 0):
        k = int(np.argmin(gaps))
        raise ValueError(f"maneuvers {maneuvers[chain[k]].id} and {maneuvers[chain[k + 1]].id} of noise group "
                         f"{maneuvers[chain[k]].noise_group!r} overlap in time ({gaps[k]:g} s apart): their "
                         "star-tracker errors cannot be chained")
    return gaps


def _set_offsets(m_samples: int, n_sets: int) -> np.ndarray:
    """(M, S, 3, 3 S): a constant error per channel set."""
    out = np.zeros((m_samples, n_sets, 3, 3 * n_sets))
    for s in range(n_sets):
        out[:, s, :, 3 * s:3 * s + 3] = np.eye(3)
    return out


def build(lins, gaps, boresight_body, correlation_time_s: float, jitter: bool = False) -> covariance.ManeuverNoise:
    """One `covariance.ManeuverNoise` for maneuvers flown one after another (``lins`` in time order,
    ``gaps`` between them, s) with Gauss-Markov star-tracker noise of ``correlation_time_s``: the
    filter runs on across the gaps; the nuisance is each maneuver's own (its biases; the first its
    initial attitude error, the later ones an offset per set). ``jitter``: the reference's timing
    jitter too, white at each sample of each maneuver (`covariance.jitter_shapes`)."""
    if len(lins) == 1:
        return covariance.build(lins[0], boresight_body, correlation_time_s, jitter)
    n_sets = lins[0].z.shape[1]
    parts = [covariance.nuisance_design(lin) for lin in lins]
    parts[1:] = [np.concatenate([_set_offsets(len(lin.z), n_sets), nuis[..., 3:]], axis=3)
                 for lin, nuis in zip(lins[1:], parts[1:])]
    widths = np.cumsum([0] + [p.shape[3] for p in parts])
    rows = np.cumsum([0] + [len(lin.z) for lin in lins])
    nuisance = np.zeros((rows[-1], n_sets, 3, widths[-1]))
    for k, part in enumerate(parts):
        nuisance[rows[k]:rows[k + 1], ..., widths[k]:widths[k + 1]] = part
    clock_s = np.concatenate([lin.gm_steps for lin in lins])  # the part's clock; across a gap, its time alone
    clock_s[rows[1:-1]] = gaps
    lag1 = [lin.walk_lag1_or_none() for lin in lins]
    lag1 = None if all(x is None for x in lag1) else np.concatenate(
        [np.zeros(len(lin.z)) if x is None else x for lin, x in zip(lins, lag1)])
    return covariance.filtered(
        "+".join(lin.maneuver for lin in lins), np.concatenate([lin.z for lin in lins]),
        np.concatenate([lin.design for lin in lins]), nuisance, np.concatenate([lin.st_matrix for lin in lins]),
        np.concatenate([lin.random_walk() for lin in lins]), clock_s, lag1, boresight_body, correlation_time_s,
        np.concatenate([covariance.jitter_shapes(lin) for lin in lins]) if jitter else None)


class Chains:
    """A campaign's chains (`chains`) and their gaps: what the likelihood of correlated star-tracker
    noise needs of the maneuvers beyond their linearisations."""

    def __init__(self, members: list, gaps: list):
        self.members, self.gaps = members, gaps

    @classmethod
    def of(cls, maneuvers) -> "Chains":
        """The chains of ``maneuvers`` (`chains`)."""
        members = chains(maneuvers)
        return cls(members, [gaps_s(maneuvers, c) for c in members])

    @classmethod
    def apart(cls, n_maneuvers: int) -> "Chains":
        """Every maneuver a chain of its own: their errors independent."""
        return cls([[m] for m in range(n_maneuvers)], [np.zeros(0)] * n_maneuvers)

    def groups(self, index):
        """Each chain's noise group from each maneuver's (``index``; None stays None)."""
        return None if index is None else np.asarray(index)[[c[0] for c in self.members]]

    def noises(self, lins, boresight_body, correlation_time_s: float, jitter: bool = False):
        """The chains' `build`, one at a time (a generator: each is summed and dropped by its caller);
        ``jitter``: with the reference's timing jitter."""
        for chain, gap in zip(self.members, self.gaps):
            yield build([lins[m] for m in chain], gap, boresight_body, correlation_time_s, jitter)
