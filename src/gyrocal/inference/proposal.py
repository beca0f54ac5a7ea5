"""The sampler's proposals: a multivariate Student-t (`StudentProposal`) for the start points, and
the collapsed move (`CollapsedProposal`) that emcee runs as an ``MHMove``: the noise scales from a
Student-t fitted to burn-in draws (`fitted_noise_proposal`), the channel offsets from their exact
Gaussian conditional given them."""

import numpy as np

__all__ = ["CollapsedProposal", "SamplingError", "StudentProposal", "fitted_noise_proposal"]


class SamplingError(RuntimeError):
    """The posterior cannot be sampled from this point estimate; the message says why."""


class StudentProposal:
    """A multivariate Student-t, wider than ``cov`` by ``inflate``: the start points' (about the Laplace
    approximation), and the noise part of `CollapsedProposal` (about its block, then fitted to burn-in
    draws, `fitted_noise_proposal`). Heavier-tailed than the posterior, so an independence sampler
    from it does not stick in the tails, and it decorrelates in a few steps where differential-
    evolution moves need ~100 in 27 dimensions.
    """

    def __init__(self, mean, cov, dof=5.0, inflate=1.2):
        self.mean = np.asarray(mean, dtype=float)
        self.chol = np.linalg.cholesky(cov) * inflate
        self.dof = dof

    def log_density(self, x):
        z = np.linalg.solve(self.chol, (x - self.mean).T).T
        return -0.5 * (self.dof + len(self.mean)) * np.log1p(np.sum(z**2, axis=1) / self.dof)

    def draw(self, rng_normal, rng_chisq):
        return self.mean + (rng_normal @ self.chol.T) * np.sqrt(self.dof / rng_chisq)[:, None]

    def __call__(self, x, random):
        """emcee ``MHMove`` proposal: new positions and the log proposal ratio."""
        n, dim = x.shape
        new = self.draw(random.standard_normal((n, dim)), random.chisquare(self.dof, n))
        return new, self.log_density(x) - self.log_density(new)


def fitted_noise_proposal(noise_draws, dof=10.0, inflate=1.1) -> StudentProposal:
    """A Student-t over the noise slots fitted to burn-in draws (their mean and covariance), a little wider
    and heavier-tailed than they are, so that the independence sampler does not stick where it falls short."""
    mean = noise_draws.mean(axis=0)
    cov = np.atleast_2d(np.cov(noise_draws.T))
    eig = np.linalg.eigvalsh(cov)
    if not eig[0] > 1e-12 * eig[-1]:
        raise SamplingError(f"posterior: the noise scales did not move during burn-in (their covariance over "
                            f"{len(noise_draws)} draws is singular), so no proposal can be fitted to them")
    return StudentProposal(mean, cov, dof=dof, inflate=inflate)


class CollapsedProposal:
    """emcee ``MHMove`` proposal that draws the noise slots from an independence proposal ``noise``
    (`StudentProposal`) and the channel offsets from their exact Gaussian conditional given them
    (``conditional``, `posterior.LogPosterior.conditional`).

    The log proposal ratio then leaves in the acceptance only the noise scales' marginal posterior
    against ``noise``: a few dimensions, however many channel parameters there are. A proposal over
    all of them (the offsets' covariance held at the Laplace one) stuck walkers for hundreds of steps
    where that covariance moves with the noise (correlated star-tracker noise: 93 stays over 100 steps
    in 900, autocorrelation times 50-400 steps). The offsets are drawn afresh at every accepted step.
    """

    def __init__(self, conditional, n_params: int, noise: StudentProposal, local_scale: float = 0.0):
        self.conditional, self.n_params, self.noise = conditional, n_params, noise
        self.local_scale = local_scale
        """0: the noise from ``noise`` (independence); else a random walk about the walker's own noise, with
        ``noise``'s scale times this (symmetric, so ``noise``'s density drops out of the ratio): local steps
        that free a walker where the independence proposal falls short of the posterior."""
        self._last = None

    def _log_conditional(self, d, mean, chol):
        """log N(d | mean, precision L L^T), up to the constant both sides share."""
        r = np.einsum("wji,wj->wi", chol, d - mean)
        return np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1) - 0.5 * np.sum(r**2, axis=1)

    def _conditionals(self, eta_new, eta_old):
        """`conditional` at the proposed noise and at the walkers' own, in one call; a walker's own is
        the last call's (proposed and accepted, or kept) wherever its noise is one of them."""
        rows = np.concatenate([eta_new, eta_old])
        need = np.ones(len(rows), dtype=bool)
        out = None
        if self._last is not None:
            keys, *cached = self._last
            match = np.all(eta_old[:, None, :] == keys[None], axis=2)
            hit = match.any(axis=1)
            need[len(eta_new):] = ~hit
            out = [np.empty((len(rows),) + c.shape[1:], dtype=c.dtype) for c in cached]
            for o, c in zip(out, cached):
                o[len(eta_new):][hit] = c[match.argmax(axis=1)[hit]]
        fresh = self.conditional(rows[need])
        if out is None:
            out = list(fresh)
        else:
            for o, f in zip(out, fresh):
                o[need] = f
        self._last = (rows, *out)
        n = len(eta_new)
        return [o[:n] for o in out], [o[n:] for o in out]

    def __call__(self, x, random):
        n, p = len(x), self.n_params
        if self.local_scale:
            eta = x[:, p:] + self.local_scale * random.standard_normal((n, x.shape[1] - p)) @ self.noise.chol.T
        else:
            eta = self.noise.draw(random.standard_normal((n, x.shape[1] - p)), random.chisquare(self.noise.dof, n))
        (mean, chol, ok), (old_mean, old_chol, old_ok) = self._conditionals(eta, x[:, p:])
        z = random.standard_normal((n, p))
        d = mean + np.linalg.solve(np.swapaxes(chol, 1, 2), z[..., None])[..., 0]  # (L^T)^-1 z: precision L L^T
        ratio = self._log_conditional(x[:, :p], old_mean, old_chol) - self._log_conditional(d, mean, chol)
        if not self.local_scale:
            ratio += self.noise.log_density(x[:, p:]) - self.noise.log_density(eta)
        new = np.concatenate([d, eta], axis=1)
        bad = ~(ok & old_ok)  # no valid conditional there: stay (a rejected proposal)
        new[bad], ratio[bad] = x[bad], -np.inf
        return new, ratio
