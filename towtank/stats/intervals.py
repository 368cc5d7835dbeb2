"""Cluster-robust (sandwich) covariance of a least-squares fit with few clusters, and the
Welch–Satterthwaite degrees of freedom of a combined uncertainty.

The samples of one run share its zero, its drift correction and its filtered noise, so a fit
over the pooled samples of several runs has errors correlated within each run (a cluster) and
independent between runs. A towing-tank day has few runs per fit (4 to 12 clusters), where the
usual cluster-robust covariance (CR1, statsmodels' ``cov_type="cluster"``) is biased low,
most where a few runs carry most of the leverage (the accelerated runs of an added-mass fit).
The bias-reduced linearisation (CR2) of Bell & McCaffrey removes that bias under a working
model of independent errors; it is used with Student's t at G − 1 degrees of freedom
(Cameron & Miller 2015, §VI). Only numpy: the tare fit uses it inside the reduction stage.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np


def cr2_covariance(
    x: np.ndarray, resid: np.ndarray, groups: np.ndarray
) -> tuple[np.ndarray, int]:
    """Bell–McCaffrey (CR2) cluster-robust covariance of OLS coefficients.

    .. math::

        V = (X'X)^{-1} \\Big[\\sum_g X_g' A_g e_g e_g' A_g X_g\\Big] (X'X)^{-1},
        \\qquad A_g = (I - H_{gg})^{-1/2},

    with :math:`H_{gg} = X_g (X'X)^{-1} X_g'` the block of the hat matrix of cluster g and
    :math:`e_g` its OLS residuals (Bell & McCaffrey 2002, eq. 3.3; Imbens & Kolesár 2016,
    eq. 3.4). A residual is shrunk by the leverage of its cluster; :math:`A_g` undoes that, so
    that V is unbiased when the errors are independent and homoscedastic, and much less biased
    than CR1 otherwise. :math:`A_g` is applied in the rank-p subspace of :math:`H_{gg}`, so the
    cost is O(n p²) whatever the cluster sizes; directions of leverage 1 (a cluster alone
    determines them) have zero residual and are left as they are.

    Parameters
    ----------
    x : ndarray (n, p)
        Regressors (full column rank).
    resid : ndarray (n,)
        OLS residuals y − X β̂ [unit of y].
    groups : ndarray (n,)
        Cluster label (run number) of each row.

    Returns
    -------
    cov : ndarray (p, p)
        Covariance of β̂.
    dof : int
        G − 1, the degrees of freedom of Student's t for intervals from ``cov``, G the number
        of clusters (Cameron & Miller 2015, §VI.D).

    References
    ----------
    R. M. Bell and D. F. McCaffrey, "Bias reduction in standard errors for linear regression
    with multi-stage samples", Survey Methodology 28(2), 169–181, 2002.
    G. W. Imbens and M. Kolesár, "Robust standard errors in small samples: some practical
    advice", Review of Economics and Statistics 98(4), 701–712, 2016.
    A. C. Cameron and D. L. Miller, "A practitioner's guide to cluster-robust inference",
    Journal of Human Resources 50(2), 317–372, 2015.
    """
    x = np.asarray(x, dtype=float)
    e = np.asarray(resid, dtype=float)
    _, codes = np.unique(np.asarray(groups), return_inverse=True)
    n_groups = int(codes.max()) + 1 if codes.size else 0
    q, r = np.linalg.qr(x)  # X = QR, H = QQ', (X'X)^-1 X_g' = R^-1 Q_g'
    p = x.shape[1]
    meat = np.zeros((p, p))
    for g in range(n_groups):
        i = codes == g
        qg, eg = q[i], e[i]
        lam, v = np.linalg.eigh(qg.T @ qg)  # nonzero eigenvalues of H_gg
        keep = (lam > 1e-12) & (lam < 1.0 - 1e-10)
        w = (qg @ v[:, keep]) / np.sqrt(lam[keep])  # orthonormal: H_gg = W diag(lam) W'
        shrink = 1.0 / np.sqrt(1.0 - lam[keep]) - 1.0
        ae = eg + w @ (shrink * (w.T @ eg))
        s = qg.T @ ae
        meat += np.outer(s, s)
    rinv = np.linalg.inv(r)
    return rinv @ meat @ rinv.T, n_groups - 1


def bm_dof(x: np.ndarray, groups: np.ndarray, ell: np.ndarray) -> float:
    """Bell–McCaffrey degrees of freedom of the CR2 variance of ℓ'β̂ (Imbens & Kolesár 2016).

    With few clusters, or with the leverage on ℓ'β̂ held by a few of them (two or three
    accelerated runs carry an added mass), Student's t at G − 1 is too optimistic. Bell &
    McCaffrey (2002) match the CR2 variance to a scaled χ² under a working model of
    independent homoscedastic errors:

    .. math::

        \\nu_{BM} = \\frac{(\\sum_i \\lambda_i)^2}{\\sum_i \\lambda_i^2},

    λ the eigenvalues of G'G, G the n × G matrix whose column g is
    :math:`(I - H)_{\\cdot g} A_g X_g (X'X)^{-1} \\ell` (Imbens & Kolesár 2016, eq. 3.5 and
    §IV.B). With X = QR, :math:`u_g = A_g Q_g R^{-T} \\ell` and :math:`a_g = Q_g' u_g`, G'G =
    diag(|u_g|²) − [a_g' a_h], a G × G matrix: the cost is O(n p²).

    Parameters
    ----------
    x : ndarray (n, p)
        Regressors (full column rank).
    groups : ndarray (n,)
        Cluster label of each row.
    ell : ndarray (p,)
        The linear combination of the coefficients (e.g. a unit vector for one of them).

    Returns
    -------
    float
        ν_BM [-], at least 1.

    References
    ----------
    G. W. Imbens and M. Kolesár, "Robust standard errors in small samples: some practical
    advice", Review of Economics and Statistics 98(4), 701–712, 2016.
    R. M. Bell and D. F. McCaffrey, Survey Methodology 28(2), 169–181, 2002.
    """
    x = np.asarray(x, dtype=float)
    _, codes = np.unique(np.asarray(groups), return_inverse=True)
    n_groups = int(codes.max()) + 1 if codes.size else 0
    q, r = np.linalg.qr(x)
    z = np.linalg.solve(r.T, np.asarray(ell, dtype=float))  # R^-T ℓ
    norms = np.zeros(n_groups)
    a = np.zeros((n_groups, x.shape[1]))
    for g in range(n_groups):
        qg = q[codes == g]
        lam, v = np.linalg.eigh(qg.T @ qg)
        keep = (lam > 1e-12) & (lam < 1.0 - 1e-10)
        w = (qg @ v[:, keep]) / np.sqrt(lam[keep])
        shrink = 1.0 / np.sqrt(1.0 - lam[keep]) - 1.0
        y = qg @ z
        u = y + w @ (shrink * (w.T @ y))  # A_g Q_g R^-T ℓ
        norms[g] = u @ u
        a[g] = qg.T @ u
    gram = np.diag(norms) - a @ a.T
    lam = np.clip(np.linalg.eigvalsh(gram), 0.0, None)
    if not np.sum(lam**2) > 0:
        return float(max(n_groups - 1, 1))
    return float(max(1.0, np.sum(lam) ** 2 / np.sum(lam**2)))


def welch_satterthwaite(variances: Sequence[float], dofs: Sequence[float]) -> float:
    """Effective degrees of freedom of a sum of independent variance components.

    ν_eff = u_c⁴ / Σ (u_i⁴ / ν_i), u_c² = Σ u_i² (GUM, JCGM 100:2008, G.4.1, eq. G.2b).
    A component with infinite (or non-finite) ν_i, e.g. a stated uncertainty of the weighed
    mass, adds to u_c but not to the sum.

    Parameters
    ----------
    variances : sequence of float
        The components u_i² [unit²].
    dofs : sequence of float
        Their degrees of freedom ν_i [-].

    Returns
    -------
    float
        ν_eff [-]; inf when every component has infinite degrees of freedom, 0 when the total
        variance is 0.
    """
    total = float(sum(variances))
    if total <= 0.0:
        return 0.0
    pairs = [(float(u2), float(nu)) for u2, nu in zip(variances, dofs, strict=True) if u2 > 0.0]
    if any(nu <= 0.0 for _, nu in pairs):
        return 0.0
    denom = sum(u2 * u2 / nu for u2, nu in pairs if math.isfinite(nu))
    return total * total / denom if denom > 0.0 else math.inf
