"""The sampler's proposals: a multivariate Student-t (`StudentProposal`) for the start points, and
the collapsed move (`CollapsedProposal`) that emcee runs as an ``MHMove``: the noise scales from a
Student-t fitted to burn-in draws (`fitted_noise_proposal`), the channel offsets from their exact
Gaussian conditional given them."""

import numpy as np

__all__ = ["CollapsedProposal", "ConditionalCache", "SamplingError", "StudentProposal", "fitted_noise_proposal"]


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


class ConditionalCache:
    """The offsets' conditionals (`posterior.LogPosterior.conditional`) of each walker's last proposed noise and
    its own, shared by the collapsed moves: a walker's own noise is, after either move, one of the two (its
    proposal accepted or kept), so only a walker that another move (DE) has shifted costs a fresh conditional.
    Taken only where the noise is equal to the bit: a walker's conditional is the one computed at its very noise."""

    def __init__(self, conditional):
        self.conditional = conditional
        self._keys = None
        """(2, W, k): each walker's last proposed and own noise."""
        self._values = None
        """Their ``(mean, chol, ok)``, each with the same two leading axes."""

    def __call__(self, eta_new, eta_old, z):
        """``(mean, chol, ok, draw)`` at the proposed noise (draws ``mean + L^-T z``) and ``(mean, chol, ok)`` at
        the walkers' own, computing only what the last call does not hold."""
        n = len(eta_new)
        need = np.ones(n, dtype=bool)
        old = None
        if self._keys is not None and self._keys.shape[1:] == eta_old.shape:
            match = np.all(self._keys == eta_old[None], axis=2)
            need = ~match.any(axis=0)
            which = match.argmax(axis=0)
            old = [v[which, np.arange(n)] for v in self._values]
        fresh = self.conditional(np.concatenate([eta_new, eta_old[need]]),
                                 np.concatenate([z, np.zeros((need.sum(), z.shape[1]))]))
        new = [f[:n] for f in fresh]
        if old is None:
            old = [f[n:] for f in fresh[:3]]
        else:
            for o, f in zip(old, fresh[:3]):
                o[need] = f[n:]
        self._keys = np.stack([eta_new, eta_old])
        self._values = [np.stack([a, b]) for a, b in zip(new[:3], old)]
        return new, old


class CollapsedProposal:
    """emcee ``MHMove`` proposal that draws the noise slots from an independence proposal ``noise``
    (`StudentProposal`) and the channel offsets from their exact Gaussian conditional given them
    (``conditionals``, a `ConditionalCache` over `posterior.LogPosterior.conditional`).

    The log proposal ratio then leaves in the acceptance only the noise scales' marginal posterior
    against ``noise``: a few dimensions, however many channel parameters there are. A proposal over
    all of them (the offsets' covariance held at the Laplace one) stuck walkers for hundreds of steps
    where that covariance moves with the noise (correlated star-tracker noise: 93 stays over 100 steps
    in 900, autocorrelation times 50-400 steps). The offsets are drawn afresh at every accepted step.
    """

    def __init__(self, conditionals: ConditionalCache, n_params: int, noise: StudentProposal, local_scale: float = 0.0):
        self.conditionals, self.n_params, self.noise = conditionals, n_params, noise
        self.local_scale = local_scale
        """0: the noise from ``noise`` (independence); else a random walk about the walker's own noise, with
        ``noise``'s scale times this (symmetric, so ``noise``'s density drops out of the ratio): local steps
        that free a walker where the independence proposal falls short of the posterior."""

    @staticmethod
    def _log_conditional(d, mean, chol):
        """log N(d | mean, precision L L^T), up to the constant both sides share."""
        r = np.einsum("wji,wj->wi", chol, d - mean)
        return _log_diagonal(chol) - 0.5 * np.sum(r**2, axis=1)

    def __call__(self, x, random):
        n, p = len(x), self.n_params
        if self.local_scale:
            eta = x[:, p:] + self.local_scale * random.standard_normal((n, x.shape[1] - p)) @ self.noise.chol.T
        else:
            eta = self.noise.draw(random.standard_normal((n, x.shape[1] - p)), random.chisquare(self.noise.dof, n))
        z = random.standard_normal((n, p))
        (_, chol, ok, d), (old_mean, old_chol, old_ok) = self.conditionals(eta, x[:, p:], z)
        # the draw's own density: L^T (d - mean) = z
        ratio = self._log_conditional(x[:, :p], old_mean, old_chol) - (_log_diagonal(chol) - 0.5 * np.sum(z**2, axis=1))
        if not self.local_scale:
            ratio += self.noise.log_density(x[:, p:]) - self.noise.log_density(eta)
        new = np.concatenate([d, eta], axis=1)
        bad = ~(ok & old_ok)  # no valid conditional there: stay (a rejected proposal)
        new[bad], ratio[bad] = x[bad], -np.inf
        return new, ratio


def _log_diagonal(chol):
    """sum log diag L per walker: log det of the precision L L^T, halved."""
    return np.sum(np.log(np.diagonal(chol, axis1=1, axis2=2)), axis=1)
