"""towtank.stats.intervals: the CR2 cluster-robust covariance and the Welch–Satterthwaite
formula."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from towtank.stats.intervals import cr2_covariance, welch_satterthwaite


def _design(seed: int, n_groups: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    """A drag-like design [U|U|, U, a] over runs of unequal size: each run has a plateau
    (a = 0, speed noise only) and a constant-acceleration ramp, as the fit samples of a day."""
    rng = np.random.default_rng(seed)
    u, a, groups = [], [], []
    for g in range(n_groups):
        n_s, n_a = rng.integers(2, size + 1, 2)
        v, acc = rng.uniform(0.5, 2.5), rng.uniform(0.1, 1.0)
        u += [v + 1e-3 * rng.standard_normal(n_s), np.linspace(0.2, 0.9, n_a) * v]
        a += [np.zeros(n_s), np.full(n_a, acc)]
        groups.append(np.full(n_s + n_a, 7 * g + 3))  # arbitrary labels
    uu, aa = np.concatenate(u), np.concatenate(a)
    return np.column_stack([uu * np.abs(uu), uu, aa]), np.concatenate(groups)


def _cr2_by_definition(x: np.ndarray, e: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """(X'X)⁻¹ Σ X_g' A_g e_g e_g' A_g X_g (X'X)⁻¹ with A_g = (I − H_gg)^(-1/2) in full."""
    b = np.linalg.inv(x.T @ x)
    meat = np.zeros((x.shape[1], x.shape[1]))
    for g in np.unique(groups):
        i = groups == g
        w, v = np.linalg.eigh(np.eye(i.sum()) - x[i] @ b @ x[i].T)
        a_g = (v / np.sqrt(w)) @ v.T
        s = x[i].T @ a_g @ e[i]
        meat += np.outer(s, s)
    return b @ meat @ b


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_groups=st.integers(4, 12), size=st.integers(2, 30))
def test_cr2_is_its_definition(seed, n_groups, size):
    x, groups = _design(seed, n_groups, size)
    e = np.random.default_rng(seed + 1).standard_normal(len(x))
    e -= x @ np.linalg.lstsq(x, e, rcond=None)[0]  # OLS residuals
    cov, dof = cr2_covariance(x, e, groups)
    np.testing.assert_allclose(cov, _cr2_by_definition(x, e, groups), rtol=1e-8, atol=1e-14)
    assert dof == n_groups - 1


def test_cr2_is_unbiased_for_independent_errors():
    """Bell & McCaffrey's point: with e = (I − H)ε and ε ~ (0, σ²I), E[V_CR2] = σ²(X'X)⁻¹
    exactly. V is quadratic in e, so E[V] = Σ_k V(m_k), m_k the columns of I − H."""
    x, groups = _design(3, 6, 12)
    m = np.eye(len(x)) - x @ np.linalg.inv(x.T @ x) @ x.T
    expected = sum(cr2_covariance(x, m[:, k], groups)[0] for k in range(len(x)))
    np.testing.assert_allclose(expected, np.linalg.inv(x.T @ x), rtol=1e-9)


def test_cr2_with_one_sample_per_cluster_is_hc2():
    """Singleton clusters: CR2 is MacKinnon & White's HC2, as statsmodels computes it."""
    from statsmodels.regression.linear_model import OLS

    x, _ = _design(5, 10, 6)
    y = x @ [0.2, 0.01, 0.6] + np.random.default_rng(6).standard_normal(len(x)) * 1e-3
    res = OLS(y, x).fit(cov_type="HC2")
    cov, dof = cr2_covariance(x, np.asarray(res.resid), np.arange(len(x)))
    np.testing.assert_allclose(cov, res.cov_params(), rtol=1e-9)
    assert dof == len(x) - 1


def test_welch_satterthwaite():
    """GUM G.4.1: ν_eff = u_c⁴/Σ(u_i⁴/ν_i); stated values (ν = ∞) add to u_c only."""
    assert welch_satterthwaite([1.0, 1.0], [4, 4]) == pytest.approx(8.0)
    assert welch_satterthwaite([4.0, 1.0, 2.0], [8, 11, math.inf]) == pytest.approx(
        49.0 / (16.0 / 8 + 1.0 / 11))
    assert welch_satterthwaite([1.0], [math.inf]) == math.inf
    assert welch_satterthwaite([0.0, 1.0], [0, 5]) == pytest.approx(5.0)  # zero components
    assert welch_satterthwaite([0.0], [3]) == 0.0
