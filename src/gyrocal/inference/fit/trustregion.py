"""scipy's trust-region least squares, step for step, holding one Jacobian.

`trust_region` is `scipy.optimize.least_squares`'s ``trf`` without bounds (its ``trf_no_bounds``),
written out with scipy's own helpers from the private module ``scipy.optimize._lsq.common`` so that
it takes the same steps to the bit while keeping a single Jacobian alive (least_squares held up to
six: 1.2 GB at 10x the default campaign). A private module may move between scipy releases: where
the helpers are missing, `trust_region` calls `scipy.optimize.least_squares` itself with the same
options (the same steps, its memory) and says so once. ``tests/test_numerics.py`` checks both
against ``least_squares`` and dense references.
"""

import warnings

import numpy as np
from numpy.linalg import norm
from scipy.linalg import qr
from scipy.optimize import least_squares
from scipy.sparse.linalg import LinearOperator, lsmr

__all__ = ["HELPERS", "TERMINATION_MESSAGES", "trust_region"]

HELPERS = ("compute_jac_scale", "solve_trust_region_2d", "evaluate_quadratic", "update_tr_radius",
           "check_termination")
"""The functions of ``scipy.optimize._lsq.common`` that `trust_region` takes its steps with."""

try:
    from scipy.optimize._lsq import common as lsq
except ImportError:  # pragma: no cover - depends on the installed scipy
    lsq = None
if lsq is not None and not all(hasattr(lsq, name) for name in HELPERS):  # pragma: no cover
    lsq = None

TERMINATION_MESSAGES = {
    0: "The maximum number of function evaluations is exceeded.",
    1: "`gtol` termination condition is satisfied.",
    2: "`ftol` termination condition is satisfied.",
    3: "`xtol` termination condition is satisfied.",
    4: "Both `ftol` and `xtol` termination conditions are satisfied.",
}
"""``least_squares``'s message for each ``status`` that `trust_region` returns (its own words)."""


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
    if lsq is None:
        return _least_squares(fun, jac, x0, ftol, xtol, gtol, max_nfev, lsmr_tol)
    x = np.atleast_1d(x0).astype(float)
    f = fun(x)
    if not np.all(np.isfinite(f)):
        raise ValueError("Residuals are not finite in the initial point.")
    J, nfev, cost = jac(x), 1, 0.5 * np.dot(f, f)
    g = J.T.dot(f)
    scale, scale_inv = lsq.compute_jac_scale(J)
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
            p_S, _ = lsq.solve_trust_region_2d(B_S, g_S, Delta)
            step_h = S.dot(p_S)
            predicted_reduction = -lsq.evaluate_quadratic(J_h, g_h, step_h)
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
            Delta_new, ratio = lsq.update_tr_radius(Delta, actual_reduction, predicted_reduction, step_h_norm,
                                                    step_h_norm > 0.95 * Delta)
            status = lsq.check_termination(actual_reduction, cost, norm(step), norm(x), ratio, ftol, xtol)
            if status is not None:
                break
            Delta = Delta_new
        if actual_reduction > 0:
            x, f, cost = x_new, f_new, cost_new
            J = J_h = None  # the last point's Jacobian goes before this one's is made
            J = jac(x)
            g = J.T.dot(f)
            scale, scale_inv = lsq.compute_jac_scale(J, scale_inv)
    return x, cost, nfev, 0 if status is None else status, J


def _least_squares(fun, jac, x0, ftol, xtol, gtol, max_nfev, lsmr_tol):
    """`trust_region` through `scipy.optimize.least_squares` itself: the same options, its memory."""
    warnings.warn("scipy.optimize._lsq.common lacks the helpers gyrocal's trust_region takes its steps with "
                  f"({', '.join(HELPERS)}); using scipy.optimize.least_squares instead: the same steps, but it "
                  "holds several Jacobians (more memory on long campaigns)", RuntimeWarning, stacklevel=3)
    result = least_squares(fun, np.atleast_1d(x0).astype(float), jac=jac, method="trf", x_scale="jac",
                           tr_solver="lsmr", tr_options={"regularize": False, "atol": lsmr_tol, "btol": lsmr_tol},
                           ftol=ftol, xtol=xtol, gtol=gtol, max_nfev=max_nfev)
    return result.x, float(result.cost), int(result.nfev), int(result.status), result.jac
