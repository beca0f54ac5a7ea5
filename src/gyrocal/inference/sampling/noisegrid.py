"""The likelihood's sufficient statistics tabulated over the noise's shape, and interpolated.

The noise covariance is ``sigma_cross^2`` times a matrix fixed by the log ratios of the other
scales to it (`covariance.ratios_of`): two for white star-tracker noise, with a Gauss-Markov
part (`markov`) its share's logit and ``log tau`` too, with the reference's timing jitter its
ratio. The scale enters in closed form; the statistics at unit scale are tabulated on a grid over
the ratios, spanning many posterior standard deviations, and interpolated (tensor-product cubic
Lagrange), so a posterior draw costs a weighted sum instead of a factorisation.
"""

import logging

import numpy as np

from gyrocal.inference.fit.likelihood import campaign_stats, maneuver_stats, total
from gyrocal.inference.fit.noisefit import finite_profile
from gyrocal.inference.noise import covariance, segments
from gyrocal.inference.sampling.proposal import SamplingError

__all__ = ["MAX_HALF_WIDTH_LOG_RATIO", "NoiseShapes", "RatioGrid", "ratio_curvature"]

MAX_HALF_WIDTH_LOG_RATIO = 8.0
"""The grid spans at most this either way of each ratio's estimate (a factor e^8 = 3 000 in the
noise): where the ratios' profile is flat and the grid falls back on their prior (sd 2.1 with
``noise_log_sd`` 1.5), +-8 sd would reach e^17, where the covariance is numerically singular
(a 30-sample maneuver's banded Cholesky fails from e^10; a RepoIMU trial's posterior crashed)."""


class NoiseShapes:
    """The likelihood's noise structures at a noise shape: each maneuver's, fixed, for white noise;
    for Gauss-Markov noise each chain's (`segments.Chains`: the error runs on between consecutive
    maneuvers of a group), rebuilt at each correlation time (its filter depends on tau; every other
    ratio only weighs the components). ``groups`` (each maneuver's noise group) gives the REML profile
    one level per group; `groups_of_parts` is the structures' own."""

    def __init__(self, noises, lins=None, boresight=None, groups=None, chained=None, jitter=False):
        """``chained``: a `segments.Chains` (None: every maneuver apart); ``jitter``: the Gauss-Markov
        structures hold the reference's timing jitter too (white structures have it as built)."""
        self.noises, self.lins, self.boresight, self.groups = noises, lins, boresight, groups
        self.chained = segments.Chains.apart(len(lins)) if chained is None and lins is not None else chained
        self.jitter = jitter

    @property
    def correlated(self) -> bool:
        return self.lins is not None

    @property
    def groups_of_parts(self):
        """Each structure's noise group (None: one group)."""
        return self.chained.groups(self.groups) if self.correlated else self.groups

    def _built(self, ratios):
        return self.chained.noises(self.lins, self.boresight, covariance.correlation_time_of(ratios), self.jitter)

    def at(self, ratios) -> list:
        """The `covariance.ManeuverNoise` structures for ``ratios`` (only ``log tau`` matters)."""
        return list(self._built(ratios)) if self.correlated else self.noises

    def profile(self, ratios) -> float:
        """The REML profile's negative log-likelihood at ``ratios`` (`noisefit.finite_profile`: inf where the
        covariance is not positive definite in floating point); Gauss-Markov structures are built, summed
        and dropped one at a time."""
        parts = self._built(ratios) if self.correlated else self.noises
        return finite_profile(parts, ratios, self.groups_of_parts)


def _lagrange(f):
    """Cubic Lagrange weights of the four nodes around a point at fraction ``f`` past the second."""
    return np.stack([-f * (f - 1) * (f - 2) / 6, (f + 1) * (f - 1) * (f - 2) / 2,
                     -(f + 1) * f * (f - 2) / 2, (f + 1) * f * (f - 1) / 6], axis=-1)


class RatioGrid:
    """Unit-scale sufficient statistics on a grid over the noise ratios (`covariance.ratios_of`).

    At each node the statistics are computed with ``sigma_cross = 1``. The grid spans
    ``half_width_sd`` sd either way, at most `MAX_HALF_WIDTH_LOG_RATIO`, with ``nodes`` along every
    ratio (the config's ``grid.nodes``), or its own along each. With Gauss-Markov noise the structures
    are built once per node of ``log tau`` (`NoiseShapes.at`), the outer loop. ``noises`` is the
    maneuvers' noise structures, or a `NoiseShapes` where they change with the ratios; ``groups``,
    each maneuver's noise group where ``noises`` is a list (a `NoiseShapes` has its own), tabulates
    each group's statistics apart (they scale apart).

    A node whose covariance is not positive definite in floating point (a Gauss-Markov correlation
    time far beyond the maneuvers while the attitude turns about changing axes: `markov`) has no
    likelihood: it is left out (``valid``), and a point whose interpolation needs it is off the grid,
    where the posterior is zero. The posterior is then bounded where the likelihood can be computed,
    and the log says where; `SamplingError` where no node can be.
    """

    complete = True
    """Whether every node is valid (``valid``), so that no point's weights need checking against it; a grid
    whose nodes were not tabulated here (built bare, as the interpolation's tests build it) has none left out."""

    def __init__(self, noises, center, sd, nodes, half_width_sd: float, groups=None):
        """``nodes``: per ratio, or one count for all."""
        shapes = noises if isinstance(noises, NoiseShapes) else NoiseShapes(noises, groups=groups)
        center = np.asarray(center, dtype=float)
        self.nodes, self.dims = nodes, len(center)
        shape = self.shape
        groups = shapes.groups_of_parts
        self.groups = None if groups is None or np.max(groups) == 0 else np.asarray(groups)
        self.n_groups = 1 if self.groups is None else int(self.groups.max()) + 1
        half_width = np.minimum(half_width_sd * np.asarray(sd, dtype=float), MAX_HALF_WIDTH_LOG_RATIO)
        self.sd = half_width / half_width_sd
        """The ratios' sd that the grid spans ``half_width_sd`` of: ``sd``, or less where the span is capped."""
        self.start = center - half_width
        self.step = 2 * half_width / (np.array(shape) - 1)
        self.values = None
        self.valid = np.ones(self.size, dtype=bool)
        """Per node (flat index): whether its covariance could be factored and its statistics are finite."""
        self._last = None
        """The last `stats` call's ratios, interpolated rows and inside mask (`_interpolated`)."""
        tau = covariance.ratio_position(center, covariance.GM_TAU_SCALE) if shapes.correlated else None
        inner = shape if tau is None else shape[:tau] + shape[tau + 1:]
        for outer in [None] if tau is None else range(shape[tau]):  # Gauss-Markov: tau outermost, each filter built once
            current = shapes.noises if tau is None else shapes.at(self.start + self.step * outer)
            for index in np.ndindex(*inner):
                index = index if tau is None else index[:tau] + (outer,) + index[tau:]
                flat = np.ravel_multi_index(index, shape)
                r = self.start + self.step * np.array(index)
                try:
                    parts = self._group_stats(current, covariance.unit_variances(r))
                except np.linalg.LinAlgError:
                    self.valid[flat] = False
                    continue
                row = np.concatenate([np.concatenate([s.A.ravel(), s.b, [s.c, s.logdet]]) for s in parts])
                if not np.all(np.isfinite(row)):
                    self.valid[flat] = False
                    continue
                if self.values is None:
                    self.values = np.empty((self.size, len(row)))
                self.values[flat] = row
                self.n_params = len(parts[0].b)
                self.n = parts[0].n if self.groups is None else np.array([s.n for s in parts])
        if self.values is None:
            raise SamplingError(f"the noise's covariance is not positive definite at any node of the noise-ratio grid "
                                f"(log ratios {np.round(center, 3).tolist()} +- {np.round(half_width, 3).tolist()}): "
                                "no likelihood can be computed there")
        self.complete = bool(self.valid.all())
        if not self.complete:
            self.values[~self.valid] = 0.0  # never weighted: a point that needs such a node is off the grid
            self._log_left_out()

    @property
    def shape(self) -> tuple:
        """The nodes along each ratio."""
        return tuple(int(n) for n in np.broadcast_to(self.nodes, (self.dims,)))

    @property
    def size(self) -> int:
        """The count of nodes."""
        return int(np.prod(self.shape))

    def _log_left_out(self):
        """Which nodes were left out, in the ratios' ranges they cover."""
        bad = np.array(np.unravel_index(np.flatnonzero(~self.valid), self.shape)).T
        ranges = [f"{lo:.3g} to {hi:.3g}" for lo, hi in zip(self.start + self.step * bad.min(axis=0),
                                                             self.start + self.step * bad.max(axis=0))]
        logging.getLogger("gyrocal").warning(
            "noise-ratio grid: %d of %d nodes left out, their covariance not positive definite in floating point "
            "(log ratios %s; with a Gauss-Markov part, log tau fourth: a correlation time far beyond the "
            "maneuvers while the attitude turns); the posterior is bounded to where the likelihood can be computed",
            (~self.valid).sum(), self.valid.size, ", ".join(ranges))

    def _group_stats(self, noises, var) -> list:
        """The statistics of each noise group (one for the campaign without groups)."""
        if self.groups is None:
            return [campaign_stats(noises, var)]
        each = [maneuver_stats(nz, var) for nz in noises]
        return [total([s for s, g in zip(each, self.groups) if g == k]) for k in range(self.n_groups)]

    def weights(self, ratios: np.ndarray):
        """(W, `size`) cubic Lagrange weights, and a mask of points inside the grid."""
        shape = np.array(self.shape)
        t = (ratios - self.start) / self.step
        inside = np.all((t >= 1) & (t <= shape - 2), axis=1)
        i = np.clip(np.floor(t), 1, shape - 3).astype(int)
        w1 = _lagrange(t - i)
        offsets = np.indices((4,) * self.dims).reshape(self.dims, -1)
        flat = np.zeros((len(ratios), offsets.shape[1]), dtype=int)
        product = w1[:, 0, offsets[0]]
        for d in range(self.dims):
            flat = flat * shape[d] + (i[:, d, None] + offsets[d] - 1)
            if d:
                product = product * w1[:, d, offsets[d]]
        weights = np.zeros((len(ratios), self.size))
        np.put_along_axis(weights, flat, product, axis=1)
        if not self.complete:  # a node left out may only have no weight
            inside &= np.all(self.valid[flat] | (product == 0), axis=1)
        return weights, inside

    def _interpolated(self, ratios):
        """``weights @ values`` and the inside mask per row of ``ratios``, taking the rows of the last call
        whose ratios are the same to the bit: the collapsed move's conditional and emcee's log posterior of
        the point it proposes ask for the same rows, one after the other."""
        need = np.ones(len(ratios), dtype=bool)
        v, inside = np.empty((len(ratios), self.values.shape[1])), np.empty(len(ratios), dtype=bool)
        last = self._last
        if last is not None:
            n = min(len(ratios), len(last[0]))
            need[:n] = np.any(ratios[:n] != last[0][:n], axis=1)
            v[:n][~need[:n]], inside[:n][~need[:n]] = last[1][:n][~need[:n]], last[2][:n][~need[:n]]
        if need.any():
            weights, inside[need] = self.weights(ratios[need])
            v[need] = weights @ self.values
        self._last = (ratios.copy(), v.copy(), inside.copy())
        return v, inside

    def stats(self, ratios: np.ndarray):
        """Interpolated unit-scale ``A, b, c, logdet`` per row of ``ratios``; with noise groups, per
        row and group (a group axis after the rows')."""
        v, inside = self._interpolated(np.atleast_2d(np.asarray(ratios, dtype=float)))
        p = self.n_params
        if self.groups is None:
            return v[:, :p * p].reshape(-1, p, p), v[:, p * p:p * p + p], v[:, -2], v[:, -1], inside
        v = v.reshape(len(v), self.n_groups, -1)
        return v[..., :p * p].reshape(len(v), self.n_groups, p, p), v[..., p * p:p * p + p], v[..., -2], v[..., -1], inside


def ratio_curvature(noises, ratios, fallback_sd, step=0.02):
    """Standard deviations of the ratios from the REML profile's Hessian; where the profile is
    flat or not convex there (a noise scale the data cannot tell, as when the model misses
    structure far above the noise), ``fallback_sd`` (their prior's), with a warning."""
    shapes = noises if isinstance(noises, NoiseShapes) else NoiseShapes(noises)
    ratios = np.asarray(ratios, dtype=float)
    k = len(ratios)
    f = shapes.profile
    h = np.zeros((k, k))
    f0 = f(ratios)
    e = np.eye(k) * step
    for i in range(k):
        h[i, i] = (f(ratios + e[i]) - 2 * f0 + f(ratios - e[i])) / step**2
    for i in range(k):
        for j in range(i + 1, k):
            h[i, j] = h[j, i] = (f(ratios + e[i] + e[j]) - f(ratios + e[i] - e[j])
                                 - f(ratios - e[i] + e[j]) + f(ratios - e[i] - e[j])) / (4 * step**2)
    fallback = np.broadcast_to(np.asarray(fallback_sd, dtype=float), (k,)).copy()
    if not np.all(np.isfinite(h)) or np.any(np.linalg.eigvalsh(h) <= 0):
        logging.getLogger("gyrocal").warning(
            "the REML profile of the noise ratios is not convex at %s: the grid spans their prior instead", ratios)
        return fallback
    cov = np.linalg.inv(h)
    return np.sqrt(np.clip(np.diag(cov), 1e-10, None))
