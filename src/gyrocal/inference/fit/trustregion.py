"""scipy's trust-region least squares, step for step, holding one Jacobian.

`trust_region` is `scipy.optimize.least_squares`'s ``trf`` without bounds (its ``trf_no_bounds``),
written out so that it takes the same steps to the bit while keeping a single Jacobian alive
(least_squares held up to six: 1.2 GB at 10x the default campaign). The five helpers it takes its
steps with are scipy's own (``scipy.optimize._lsq.common``, BSD-3-Clause, Copyright (c) 2001-2002
Enthought, Inc. and 2003- SciPy Developers), copied here as far as `trust_region` uses them, because
that module is private. ``tests/test_numerics.py`` checks the steps against ``least_squares`` and
dense references.
"""

import numpy as np
from numpy.linalg import LinAlgError, norm
from scipy.linalg import cho_factor, cho_solve, qr
from scipy.sparse import issparse
from scipy.sparse.linalg import LinearOperator, lsmr

__all__ = ["TERMINATION_MESSAGES", "trust_region"]

TERMINATION_MESSAGES = {
    0: "The maximum number of function evaluations is exceeded.",
    1: "`gtol` termination condition is satisfied.",
    2: "`ftol` termination condition is satisfied.",
    3: "`xtol` termination condition is satisfied.",
    4: "Both `ftol` and `xtol` termination conditions are satisfied.",
}
"""``least_squares``'s message for each ``status`` that `trust_region` returns (its own words)."""


def _jac_scale(J, scale_inv_old=None):
    """The variables' scale from the Jacobian's column norms, never below the last (scipy's ``compute_jac_scale``)."""
    scale_inv = np.asarray(J.power(2).sum(axis=0)).ravel() ** 0.5 if issparse(J) else np.sum(J**2, axis=0) ** 0.5
    if scale_inv_old is None:
        scale_inv[scale_inv == 0] = 1
    else:
        scale_inv = np.maximum(scale_inv, scale_inv_old)
    return 1 / scale_inv, scale_inv


def _trust_region_2d(B, g, Delta):
    """The step minimising ``p B p / 2 + g p`` within ``|p| <= Delta`` in two dimensions: the Newton step
    where it is inside, else the best root of a quartic on the boundary (scipy's ``solve_trust_region_2d``)."""
    try:
        R, lower = cho_factor(B)
        p = -cho_solve((R, lower), g)
        if np.dot(p, p) <= Delta**2:
            return p
    except LinAlgError:
        pass
    a, b, c = B[0, 0] * Delta**2, B[0, 1] * Delta**2, B[1, 1] * Delta**2
    d, f = g[0] * Delta, g[1] * Delta
    t = np.roots(np.array([-b + d, 2 * (a - c + f), 6 * b, 2 * (-a + c + f), -b - d]))
    t = np.real(t[np.isreal(t)])
    p = Delta * np.vstack((2 * t / (1 + t**2), (1 - t**2) / (1 + t**2)))
    value = 0.5 * np.sum(p * B.dot(p), axis=0) + np.dot(g, p)
    return p[:, np.argmin(value)]


def _quadratic(J, g, s):
    """``s J^T J s / 2 + g s`` for one step ``s`` (scipy's ``evaluate_quadratic``)."""
    Js = J.dot(s)
    return 0.5 * np.dot(Js, Js) + np.dot(s, g)


def _update_radius(Delta, actual_reduction, predicted_reduction, step_norm, bound_hit):
    """The next radius and the ratio of the actual to the predicted reduction (scipy's ``update_tr_radius``)."""
    if predicted_reduction > 0:
        ratio = actual_reduction / predicted_reduction
    elif predicted_reduction == actual_reduction == 0:
        ratio = 1
    else:
        ratio = 0
    if ratio < 0.25:
        Delta = 0.25 * step_norm
    elif ratio > 0.75 and bound_hit:
        Delta *= 2.0
    return Delta, ratio


def _termination(dF, F, dx_norm, x_norm, ratio, ftol, xtol):
    """``least_squares``'s status where ``ftol`` or ``xtol`` is met, else None (scipy's ``check_termination``)."""
    ftol_satisfied = dF < ftol * F and ratio > 0.25
    xtol_satisfied = dx_norm < xtol * (xtol + x_norm)
    if ftol_satisfied and xtol_satisfied:
        return 4
    if ftol_satisfied:
        return 2
    if xtol_satisfied:
        return 3
    return None


def _scaled(J, d) -> LinearOperator:
    """``J diag(d)`` as scipy's ``right_multiplied_operator`` makes it, through the same sparse
    products, but with ``J``'s transpose a view of it: scipy's adjoint copies the matrix."""
    transposed = J.T
    return LinearOperator(J.shape, dtype=J.dtype,
                          matvec=lambda x: J.dot((np.ravel(x) * d).reshape(-1, 1)).reshape(-1),
                          matmat=lambda X: J.dot(X * d[:, np.newaxis]),
                          rmatvec=lambda x: d * transposed.dot(np.asarray(x).reshape(-1, 1)).reshape(-1))


def trust_region(fun, jac, x0, ftol: float, xtol: float, gtol: float, max_nfev: int, lsmr_tol: float):
    """Minimise ``|fun(x)|^2 / 2`` step for step and to the bit as `scipy.optimize.least_squares` with
    ``method="trf", x_scale="jac", tr_solver="lsmr"``, no bounds, ``regularize: False`` and LSMR's
    ``atol = btol = lsmr_tol`` (its ``trf_no_bounds``, with scipy's helpers), but holding one Jacobian,
    asked for only where a step is taken. ``least_squares`` held up to six (1.2 GB at 10x).

    Returns ``(x, cost, nfev, status, J)``: ``status`` as ``least_squares``'s, ``J`` at ``x``.
    """
    x = np.atleast_1d(x0).astype(float)
    f = fun(x)
    if not np.all(np.isfinite(f)):
        raise ValueError("Residuals are not finite in the initial point.")
    J, nfev, cost = jac(x), 1, 0.5 * np.dot(f, f)
    g = J.T.dot(f)
    scale, scale_inv = _jac_scale(J)
    Delta, status = norm(x * scale_inv) or 1.0, None
    while True:
        if norm(g, ord=np.inf) < gtol:
            status = 1
        if status is not None or nfev == max_nfev:
            break
        d, g_h = scale, scale * g
        J_h = _scaled(J, d)
        gn_h = lsmr(J_h, f, damp=0.0, atol=lsmr_tol, btol=lsmr_tol)[0]
        S, _ = qr(np.vstack((g_h, gn_h)).T, mode="economic")
        JS = J_h.dot(S)
        B_S = np.dot(JS.T, JS)
        g_S = S.T.dot(g_h)
        actual_reduction = -1
        while actual_reduction <= 0 and nfev < max_nfev:
            p_S = _trust_region_2d(B_S, g_S, Delta)
            step_h = S.dot(p_S)
            predicted_reduction = -_quadratic(J_h, g_h, step_h)
            step = d * step_h
            x_new = x + step
            f_new = fun(x_new)
            nfev += 1
            step_h_norm = norm(step_h)
            if not np.all(np.isfinite(f_new)):
                Delta = 0.25 * step_h_norm
                continue
            cost_new = 0.5 * np.dot(f_new, f_new)
            actual_reduction = cost - cost_new
            Delta_new, ratio = _update_radius(Delta, actual_reduction, predicted_reduction, step_h_norm,
                                              step_h_norm > 0.95 * Delta)
            status = _termination(actual_reduction, cost, norm(step), norm(x), ratio, ftol, xtol)
            if status is not None:
                break
            Delta = Delta_new
        if actual_reduction > 0:
            x, f, cost = x_new, f_new, cost_new
            J = J_h = None  # the last point's Jacobian goes before this one's is made
            J = jac(x)
            g = J.T.dot(f)
            scale, scale_inv = _jac_scale(J, scale_inv)
    return x, cost, nfev, 0 if status is None else status, J

