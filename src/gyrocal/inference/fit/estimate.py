"""Deterministic point estimate: full-trajectory weighted least squares (WLS).

Over every maneuver at once, with the exact nonlinear model re-propagated at every
step, weights from the banded noise covariance (`noise`) and the noise scales from
REML; it starts from the paper's method (`classic`).
"""

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np
from scipy import sparse

from gyrocal.inference import errormodel
from gyrocal.inference.fit import identification, noisefit
from gyrocal.inference.fit.likelihood import campaign_stats
from gyrocal.inference.fit.trustregion import TERMINATION_MESSAGES, trust_region
from gyrocal.inference.noise import covariance, segments
from gyrocal.inference.noise.covariance import variances
from gyrocal.maneuvers.preprocess import noise_groups
from gyrocal.model.spec import ModelSpec

__all__ = [
    "PointEstimate", "linearize_all", "point_estimate", "trust_region", "wls"
]


@dataclass
class PointEstimate:
    """Full-trajectory WLS solution and its Jacobian covariance, all SI."""

    spec: ModelSpec
    theta: np.ndarray
    """The parameters in the spec's column order."""
    cov: np.ndarray
    biases: np.ndarray
    """(n_maneuvers, n_channels) rad/s."""
    chi0: np.ndarray
    log_sigma: np.ndarray
    """log [sigma_cross_rad, sigma_about_rad, arw_rad_sqrt_s] used for the weights, and the model's
    other noise scales after them (`covariance.noise_scales`)."""
    cost: float
    nfev: int
    message: str
    correlation_time_s: float = 0.0
    """Correlation time of the star-tracker noise (0: white)."""
    stated_noise: dict = field(default_factory=dict)
    """The noise knowledge the run was given (contract units and ``boresight_body``)."""
    at_estimate: tuple = ()
    """Each maneuver's `errormodel.Linearization` about this estimate, as the WLS's last step left
    it and saved with it: the posterior and the diagnostics start from it, and computing it again
    took 0.6 s in each of their jobs (empty: computed when asked)."""
    at_estimate_keys: tuple = ()
    """`linearization_key` of each saved linearisation: what it was computed from."""
    noise_groups: tuple = ()
    """The campaign's noise groups (`preprocess.noise_groups`) where it has more than one."""
    group_offsets: np.ndarray | None = None
    """Each noise group's ``log sigma_cross`` less the campaign's (``log_sigma[0]``); None: one group."""

    def maneuver_variances(self, m: int, group: int = 0) -> dict:
        """The noise variances of a maneuver in noise group ``group``: the campaign's, times its
        group's level squared (every component: the group's noise is a multiple of the campaign's)."""
        var = variances(self.log_sigma)
        if self.group_offsets is None:
            return var
        factor = np.exp(2.0 * self.group_offsets[group])
        return {k: v * factor for k, v in var.items()}

    @property
    def boresight(self):
        return self.stated_noise["boresight_body"]

    def params(self, m: int):
        return self.spec.channel_params(self.theta, self.biases[m])

    def linearization_key(self, data, m: int) -> str:
        """A digest of what maneuver ``m``'s linearisation is computed from: the maneuver (id, times,
        gyro increments, star-tracker attitudes, the Gauss-Markov clock where it has one), the specification,
        ``theta`` and its biases."""
        digest = hashlib.sha256(self.spec.to_json().encode())
        clock = (np.float64(data.gm_clock_s_per_rad),) if data.gm_clock_s_per_rad > 0 else ()
        for part in (data.id.encode(), data.gyro_time, data.increments, data.st_time, data.st_quat,
                     data.attitude0_quat, self.theta, self.biases[m], *clock):
            digest.update(np.ascontiguousarray(part).tobytes() if isinstance(part, (np.ndarray, np.floating)) else part)
        return digest.hexdigest()

    def linearize(self, maneuvers, m: int):
        """Maneuver ``m``'s linearisation about the estimate: the saved one where it was computed
        from this maneuver, specification, ``theta`` and biases (`linearization_key`), else
        computed."""
        data = maneuvers[m]
        if m < len(self.at_estimate) and self.at_estimate_keys[m] == self.linearization_key(data, m):
            return self.at_estimate[m]
        return errormodel.linearize(data, self.spec, self.theta, self.biases[m])

    def save(self, handle):
        lins = {k: v for m, lin in enumerate(self.at_estimate) for k, v in lin.arrays(f"lin{m}_").items()}
        lins.update({f"lin{m}_key": np.asarray(key) for m, key in enumerate(self.at_estimate_keys)})
        if self.group_offsets is not None:
            lins.update(noise_groups=json.dumps(list(self.noise_groups)), group_offsets=self.group_offsets)
        np.savez(handle, theta=self.theta, cov=self.cov, biases=self.biases, chi0=self.chi0,
                 log_sigma=self.log_sigma, cost=self.cost, nfev=self.nfev, message=self.message,
                 correlation_time_s=self.correlation_time_s, spec=self.spec.to_json(),
                 stated_noise=json.dumps(self.stated_noise), n_linearized=len(self.at_estimate), **lins)

    @classmethod
    def load(cls, path, known_effects=None, linearizations: bool = True) -> "PointEstimate":
        """Read `save`; ``known_effects`` (library and plugins, by name) are needed by the
        steps that evaluate the model's effects again. ``linearizations=False`` leaves the saved
        linearisations on disk (160 MB at 10x the default campaign), for steps that never ask."""
        z = np.load(path, allow_pickle=False)
        n_lin = int(z["n_linearized"]) if "n_linearized" in z.files and linearizations else 0  # none: older files
        return cls(ModelSpec.from_json(str(z["spec"]), known_effects), z["theta"], z["cov"], z["biases"],
                   z["chi0"], z["log_sigma"], float(z["cost"]), int(z["nfev"]), str(z["message"]),
                   float(z["correlation_time_s"]), json.loads(str(z["stated_noise"])),
                   tuple(errormodel.Linearization.from_arrays(z, f"lin{m}_") for m in range(n_lin)),
                   tuple(str(z[f"lin{m}_key"]) for m in range(n_lin)),
                   tuple(json.loads(str(z["noise_groups"]))) if "group_offsets" in z.files else (),
                   z["group_offsets"] if "group_offsets" in z.files else None)


def _unpack(x, theta0, free, n_man, n_ch):
    """The full parameter vector (prior-only entries held at ``theta0``), initial errors and biases."""
    n_free = int(free.sum())
    theta = theta0.copy()
    theta[free] = x[:n_free]
    nuis = x[n_free:].reshape(n_man, 3 + n_ch)
    return theta, nuis[:, :3], nuis[:, 3:]


class _Jacobian:
    """The WLS's whitened Jacobian, written maneuver by maneuver into a CSR matrix's arrays: entry for
    entry ``hstack([csr_array(vstack(shared)), block_diag(own)])`` (exact zeros left out, as there),
    without their intermediate copies (0.7 GB at once on a campaign ten times the default)."""

    def __init__(self, n_rows: int, n_par: int, n_man: int, n_own: int):
        self.n_par, self.n_own, self.shape = n_par, n_own, (n_rows, n_par + n_man * n_own)
        room = n_rows * (n_par + n_own)
        index = np.int32 if max(room, self.shape[1]) < np.iinfo(np.int32).max else np.int64
        self.data = np.empty(room)
        self.indices = np.empty(room, dtype=index)
        self.indptr = np.zeros(n_rows + 1, dtype=index)
        self.row = self.nnz = 0

    def add(self, m: int, white: np.ndarray):
        """Maneuver ``m``'s whitened rows: the shared columns, then minus its own columns."""
        n = white.shape[0]
        rows = np.empty(white.shape)
        rows[:, :self.n_par] = white[:, :self.n_par]
        np.negative(white[:, self.n_par:], out=rows[:, self.n_par:])
        kept = rows != 0
        k = int(kept.sum())
        cols = np.nonzero(kept)[1]
        cols[cols >= self.n_par] += m * self.n_own
        self.data[self.nnz:self.nnz + k] = rows[kept]
        self.indices[self.nnz:self.nnz + k] = cols
        self.indptr[self.row + 1:self.row + n + 1] = self.nnz + np.cumsum(kept.sum(axis=1))
        self.row, self.nnz = self.row + n, self.nnz + k

    def matrix(self) -> sparse.csr_array:
        return sparse.csr_array((self.data[:self.nnz], self.indices[:self.nnz], self.indptr), shape=self.shape)


class _Whitened:
    """The WLS's residual and Jacobian at a point, whitened by the noise's banded factors, keeping
    one point's linearisations (the last asked for: the estimate's at the end). Whitened apart, they
    are the same to the bit as together: LAPACK's banded solve takes right-hand sides one by one."""

    def __init__(self, maneuvers, spec: ModelSpec, theta0, free, chols, x0, lins0, filters):
        self.maneuvers, self.spec, self.theta0, self.free, self.chols = maneuvers, spec, theta0, free, chols
        self.filters = filters
        self.n_man, self.n_ch, self.n_par = len(maneuvers), len(spec.channels), int(free.sum())
        self.n_rows = sum(chol.shape[1] for chol in chols)
        self.point, self.lins = x0.tobytes(), lins0

    def linearizations(self, x) -> list:
        if x.tobytes() != self.point:
            self.lins = None
            theta, _, biases = _unpack(x, self.theta0, self.free, self.n_man, self.n_ch)
            self.lins = [errormodel.linearize(d, self.spec, theta, biases[m]) for m, d in enumerate(self.maneuvers)]
            self.point = x.tobytes()
        return self.lins

    def _z(self, x) -> list:
        """Each maneuver's ``z`` at ``x``: the kept linearisation's where it is at ``x``, else `errormodel.residuals`
        (the same bits, without the Jacobian: a trial step that is not taken never needs one)."""
        if x.tobytes() == self.point:
            return [lin.z for lin in self.lins]
        theta, _, biases = _unpack(x, self.theta0, self.free, self.n_man, self.n_ch)
        return [errormodel.residuals(d, self.spec, theta, biases[m]) for m, d in enumerate(self.maneuvers)]

    def residual(self, x) -> np.ndarray:
        _, chi0, _ = _unpack(x, self.theta0, self.free, self.n_man, self.n_ch)
        out, row = np.empty(self.n_rows), 0
        for m, (z, chol) in enumerate(zip(self._z(x), self.chols)):
            n = chol.shape[1]
            r = covariance.transformed(z - chi0[m], self.filters[m]).reshape(n, 1)
            out[row:row + n] = covariance.whiten(chol, np.asfortranarray(r))[:, 0]
            row += n
        return out

    def jacobian(self, x) -> sparse.csr_array:
        jac = _Jacobian(self.n_rows, self.n_par, self.n_man, 3 + self.n_ch)
        for m, (lin, chol) in enumerate(zip(self.linearizations(x), self.chols)):
            n = chol.shape[1]
            nuis = covariance.transformed(covariance.nuisance_design(lin), self.filters[m]).reshape(n, -1)
            j_theta = -covariance.transformed(lin.design[..., self.free], self.filters[m]).reshape(n, -1)
            jac.add(m, covariance.whiten(chol, np.asfortranarray(np.concatenate([j_theta, nuis], axis=1))))
        return jac.matrix()


def wls(maneuvers, spec: ModelSpec, stated_noise: dict, log_sigma, theta0=None, biases0=None, chi00=None,
        correlation_time_s=0.0, lins0=None, groups=None) -> PointEstimate:
    """Weighted least squares over every maneuver: `scipy.optimize.least_squares`'s trust region
    (`trust_region`, its steps to the bit).

    Unknowns: the model's parameters, and per maneuver the initial attitude error and
    the bias of each channel. Each maneuver's unknowns touch only its own rows, so the
    Jacobian is sparse and the trust-region steps come from LSMR, solved to 1e-12 so that
    its Gauss-Newton directions are exact (as many iterations as the dense solver here):
    the cost grows linearly with the number of maneuvers, where a dense Jacobian's SVD
    grows with its cube. It stops once a step lowers the cost by less than 1e-8 of it: with a
    chi-square of n, the parameters are then within ``sqrt(1e-8 n)`` (0.02 on MOM) of their
    sd from the optimum. The exact nonlinear model is re-propagated at every step; weights
    come from the banded noise covariance (star tracker across and about its
    boresight, gyro random walk). Prior-only parameters stay at ``theta0``; their rows of
    the covariance are NaN. ``lins0``, the maneuvers' linearisations at the start (a caller that
    has them), is not computed again: the noise structure and the first step both use it; a list is
    taken over (emptied), so they go once the WLS moves on. Memory: one point's linearisations and
    Jacobian, and the noise's banded factors (under 1 GB at 10x, where least_squares took 3.4 GB).
    """
    n_ch, n_man = len(spec.channels), len(maneuvers)
    free = spec.free
    n_par = int(free.sum())
    boresight = stated_noise["boresight_body"]
    theta0 = np.zeros(len(spec)) if theta0 is None else np.asarray(theta0, dtype=float)
    biases0 = np.zeros((n_man, n_ch)) if biases0 is None else biases0
    chi00 = np.zeros((n_man, 3)) if chi00 is None else chi00
    x0 = np.concatenate([theta0[free], np.column_stack([chi00, biases0]).ravel()])
    levels = PointEstimate(spec, None, None, None, None, np.asarray(log_sigma, dtype=float), 0.0, 0, "", 0.0, {},
                           noise_groups=() if groups is None else tuple(groups[0]),
                           group_offsets=None if groups is None else groups[2])
    index = np.zeros(n_man, dtype=int) if groups is None else groups[1]
    if lins0 is None:
        lins0 = [errormodel.linearize(d, spec, theta0, biases0[m]) for m, d in enumerate(maneuvers)]
    # only the factors are kept of the noise: its right-hand sides are the REML's, not the WLS's
    chols, filters = [], []
    for lin in lins0:
        nz = covariance.build(lin, boresight, correlation_time_s, spec.jitter_noise)
        chols.append(nz.factor(levels.maneuver_variances(len(chols), index[len(chols)])))
        filters.append(nz.filter)
        del nz
    problem = _Whitened(maneuvers, spec, theta0, free, chols, x0, list(lins0), filters)
    if isinstance(lins0, list):
        lins0.clear()  # taken over: freed once the WLS has moved on from the start
    x, cost, nfev, status, jac = trust_region(problem.residual, problem.jacobian, x0, ftol=1e-8, xtol=1e-8,
                                              gtol=1e-10, max_nfev=30, lsmr_tol=1e-12)
    at_estimate = problem.linearizations(x)
    del problem, chols  # the noise's factors go before the Jacobian's product, its largest step
    cov_free = np.linalg.inv((jac.T @ jac).toarray())[:n_par, :n_par]
    cov = np.full((len(spec), len(spec)), np.nan)
    cov[np.ix_(free, free)] = cov_free
    theta, chi0, biases = _unpack(x, theta0, free, n_man, n_ch)
    estimate = PointEstimate(spec, theta, cov, biases, chi0,
                             np.asarray(log_sigma, dtype=float), float(2 * cost), int(nfev),
                             TERMINATION_MESSAGES[status], float(correlation_time_s), dict(stated_noise),
                             noise_groups=levels.noise_groups, group_offsets=levels.group_offsets)
    estimate.at_estimate = tuple(at_estimate)
    estimate.at_estimate_keys = tuple(estimate.linearization_key(d, m) for m, d in enumerate(maneuvers))
    return estimate


def linearize_all(maneuvers, estimate: PointEstimate):
    """Linearisations and noise structures of every maneuver about a point estimate."""
    lins = [estimate.linearize(maneuvers, m) for m in range(len(maneuvers))]
    return lins, [covariance.build(lin, estimate.boresight, estimate.correlation_time_s, estimate.spec.jitter_noise)
                  for lin in lins]


def point_estimate(maneuvers, spec: ModelSpec, stated_noise: dict, theta0, estimate_scales=True,
                   check=None) -> PointEstimate:
    """REML noise scales about a starting point (the classic estimate), then WLS from it.

    Parameters the maneuvers cannot inform are marked prior-only first and held at their
    prior mean (`identification`). Where the classic method gave nothing (maneuvers that turn
    both ways, or have no holds), a WLS with the stated noise gives the start. The classic
    estimate is within a few tens of ppm of the optimum, so the model is linear enough about
    it for the noise scales; the WLS then needs a few steps. A model with correlated
    star-tracker noise estimates its Gauss-Markov part there too (always: its sd and correlation
    time are what the model is for), from the residuals' correlation time as a start. ``check``, where
    given, is called with the specification once every prior-only parameter is marked, before the
    noise scales and the WLS: a caller's test of it that may stop there (the pipeline skips a variant
    whose additions the data cannot inform, without fitting what it would discard).
    """
    spec = spec.with_prior_only(identification.unflown(maneuvers, spec, stated_noise))
    log_sigma = covariance.log_sigma_of(stated_noise, spec.jitter_noise)
    n_man, n_ch = len(maneuvers), len(spec.channels)

    def start_at(spec):
        theta = np.where(spec.free, theta0, spec.prior_mean_si)
        return PointEstimate(spec, theta, None, np.zeros((n_man, n_ch)), None, log_sigma, np.nan, 0, "classic",
                             0.0, stated_noise)

    start = start_at(spec)
    if not np.any(theta0):
        start = wls(maneuvers, spec, stated_noise, log_sigma, start.theta)
    lins, noises = linearize_all(maneuvers, start)
    weak = identification.uninformed(campaign_stats(noises, variances(log_sigma)), spec)
    if weak:
        start = start_at(spec.with_prior_only(weak))
    if check is not None:
        check(start.spec)  # the specification the WLS will have: nothing below marks a parameter prior-only
    if weak:
        lins, noises = linearize_all(maneuvers, start)
    tau, offsets = 0.0, None
    names, index = noise_groups(maneuvers)
    index = index if len(names) > 1 else None
    if spec.correlated_noise:
        noises = None
        log_sigma, offsets = noisefit.estimate_correlated_noise(lins, start.boresight, log_sigma,
                                                                  noisefit.tau_start_s(lins), index,
                                                                  segments.Chains.of(maneuvers))
        tau = covariance.correlation_time_of(covariance.ratios_of(log_sigma))
    elif estimate_scales:
        log_sigma, offsets = noisefit.estimate_noise(noises, log_sigma, index)
    del noises  # the REML's right-hand sides: as large as the linearisations, and the WLS needs neither
    groups = None if offsets is None else (names, index, offsets)
    return wls(maneuvers, start.spec, stated_noise, log_sigma, start.theta, start.biases, start.chi0,
               correlation_time_s=tau, lins0=lins, groups=groups)
