"""Does a manoeuvre record fit the model ``identify`` fitted to it? (docs/method.md, "Model
adequacy"; fit.csv in docs/formats.md).

Three tests per measured state, each against a stated threshold:

- ``whiteness``: the Ljung–Box statistic Q of the state's normalised innovations over
  :data:`LB_LAGS` lags (statsmodels' ``acorr_ljungbox``; Ljung & Box 1978): with the right
  model the innovations of a filter, or the output-error residuals of least squares, are white
  and Q ~ chi^2(lags); a model that misses a term leaves a slow, correlated error.
- ``nis``: the mean normalised innovation squared, ``mean(e_k^2)``; with the right model
  ``n mean ~ chi^2(n)`` (Bar-Shalom, Li & Kirubarajan 2001, sec. 5.4); its upper limit. A mean
  well below 1 (the noise overstated) is not a failure of the model.
- ``holdout`` (or ``validation``): the model with the coefficients from the first part of the
  record (or the whole record) simulated along the held-out rest (or a second record,
  ``--validate``): the mean squared residual over each state's noise variance against its
  chi^2 upper limit.

Each threshold is the 1 - a quantile with ``a = FAMILY_ALPHA / (number of tests)``
(Bonferroni). The noise sd that normalises the innovations is estimated from the record
(:func:`towtank.vehicle.identify_log.noise_sd`, the median absolute second difference): a
mean square over it is the ratio of two mean squares, ``F(n, nu)`` (Snedecor's F) with ``nu``
:data:`NOISE_DOF_PER_SAMPLE` times the record's samples, not ``chi^2(n)/n`` — whose quantile
is the limit when the noise is given (``nu`` infinite). The rates of false alarms these
thresholds give on records the model made are measured by
:mod:`towtank.testing.adequacy_study`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy.stats import chi2, f
from statsmodels.stats.diagnostic import acorr_ljungbox

from towtank.vehicle.identify_log import MIN_ROWS, STATE_COLUMNS

__all__ = ["LB_LAGS", "FAMILY_ALPHA", "NOISE_DOF_PER_SAMPLE", "FIT_COLUMNS", "TEST_NAMES",
           "adequacy_table", "whiteness", "mean_square", "mean_square_limit", "noise_dof",
           "failure_sentence"]

#: Lags of the Ljung–Box statistic [samples] (fewer when a state has under 5 times as many
#: values).
LB_LAGS = 20
#: Probability that a record the model made fails at least one test [-].
FAMILY_ALPHA = 0.05
#: Degrees of freedom per sample of the noise variance in a mean square over it [-]. The
#: variance is estimated from the record (:func:`towtank.vehicle.identify_log.noise_sd`: alone
#: about 0.25 per sample, the median absolute deviation's efficiency times that of correlated
#: second differences) and from the very samples whose squares are averaged, so the two move
#: together: the mean square over it spreads as ``F(m, 0.45 n)`` (m values averaged, n in the
#: record), measured on white noise (0.39-0.49 for n = 100-1200 with m = n, 0.31-0.46 with
#: m = n/4; the 1 % quantile exceeded 0.7-1.2 % of the time).
NOISE_DOF_PER_SAMPLE = 0.45
#: fit.csv's columns.
FIT_COLUMNS = ("test", "state", "statistic", "threshold", "passed")
#: What each test is called in the sentence of a failure.
TEST_NAMES = {
    "whiteness": "the whiteness of {state}'s normalised innovations (Ljung-Box Q over {lags} "
                 "lags)",
    "nis": "the normalised innovation squared of {state} (mean over the record)",
    "holdout": "{state} of the model re-simulated along the held-out last part of the record "
               "(mean squared residual over the noise variance)",
    "validation": "{state} of the model simulated along the validation record (mean squared "
                  "residual over the noise variance)",
}


def whiteness(e: np.ndarray, lags: int = LB_LAGS) -> tuple[float, int]:
    """Ljung–Box Q [-] of the finite values of ``e`` and the lags used (at most ``lags``, at
    most a fifth of the values)."""
    x = e[np.isfinite(e)]
    lag = int(max(1, min(lags, len(x) // 5)))
    q = acorr_ljungbox(x - x.mean(), lags=[lag], return_df=True)["lb_stat"].iloc[0]
    return float(q), lag


def mean_square(e: np.ndarray) -> tuple[float, int]:
    """Mean of the squares of the finite values of ``e`` [-] and how many there are."""
    x = e[np.isfinite(e)]
    return float(np.mean(x ** 2)) if len(x) else float("nan"), int(len(x))


def noise_dof(counts: np.ndarray, given: np.ndarray) -> np.ndarray:
    """Degrees of freedom of each state's noise variance [-]: :data:`NOISE_DOF_PER_SAMPLE`
    times its ``counts`` (samples of the record) where estimated, infinite where ``given``."""
    return np.where(given, np.inf, NOISE_DOF_PER_SAMPLE * np.asarray(counts, dtype=float))


def mean_square_limit(n: int, dof: float, a: float) -> float:
    """Upper ``1 - a`` limit of the mean of ``n`` squared unit normal values over a noise
    variance estimated with ``dof`` degrees of freedom [-]: the ``F(n, dof)`` quantile,
    ``chi^2(n)/n``'s when ``dof`` is infinite."""
    if not np.isfinite(dof):
        return float(chi2.ppf(1 - a, n) / n)
    return float(f.ppf(1 - a, n, dof))


def adequacy_table(innovation: np.ndarray, check: np.ndarray | None,
                   check_test: str = "holdout", states: list[int] | None = None,
                   family_alpha: float = FAMILY_ALPHA, dof: np.ndarray | None = None,
                   check_dof: np.ndarray | None = None) -> pd.DataFrame:
    """fit.csv: one row per test and measured state.

    Parameters
    ----------
    innovation : ndarray
        (n, 12) normalised innovations (the filter's, or least squares' residuals over the
        noise sd) [-], NaN where a state is not measured
    check : ndarray or None
        (m, 12) normalised residuals of the model simulated along the held-out part or the
        validation record [-]; None: no such test (a record too short to hold a part out)
    check_test : {"holdout", "validation"}
    states : list of int, optional
        The states tested (indices of :data:`STATE_COLUMNS`); default every one with values
    family_alpha : float
        Probability that a record the model made fails any test [-]
    dof, check_dof : ndarray, optional
        (12,) degrees of freedom of the noise variance that normalises ``innovation``
        (``check``) (:func:`noise_dof`) [-]; default infinite (the noise given)

    Returns
    -------
    DataFrame
        Columns :data:`FIT_COLUMNS`; ``state`` the state's column (``r_deg_s``).
    """
    pick = range(innovation.shape[1]) if states is None else states
    tested = [i for i in pick if np.isfinite(innovation[:, i]).sum() >= MIN_ROWS]
    checked = [] if check is None else [i for i in pick
                                        if np.isfinite(check[:, i]).sum() >= MIN_ROWS]
    ntests = max(2 * len(tested) + len(checked), 1)
    a = family_alpha / ntests
    nu = np.full(innovation.shape[1], np.inf) if dof is None else np.asarray(dof, float)
    nu_check = nu if check_dof is None else np.asarray(check_dof, float)
    rows = []
    for i in tested:
        q, lag = whiteness(innovation[:, i])
        rows.append(("whiteness", STATE_COLUMNS[i], q, float(chi2.ppf(1 - a, lag))))
    for i in tested:
        ms, n = mean_square(innovation[:, i])
        rows.append(("nis", STATE_COLUMNS[i], ms, mean_square_limit(n, nu[i], a)))
    for i in checked:
        assert check is not None
        ms, n = mean_square(check[:, i])
        rows.append((check_test, STATE_COLUMNS[i], ms, mean_square_limit(n, nu_check[i], a)))
    table = pd.DataFrame(rows, columns=list(FIT_COLUMNS[:4]))
    table["passed"] = table["statistic"] <= table["threshold"]
    return table


def failure_sentence(table: pd.DataFrame) -> str | None:
    """One sentence naming the test that failed by most (statistic over threshold), or None
    when every test passed."""
    bad = table[~table["passed"].astype(bool)]
    if bad.empty:
        return None
    ratio = bad["statistic"] / bad["threshold"]
    worst = bad.loc[ratio.idxmax()]
    lags = LB_LAGS
    what = TEST_NAMES[str(worst["test"])].format(state=worst["state"], lags=lags)
    more = len(bad) - 1
    return (f"the model does not fit the record: {what} is {worst['statistic']:.4g}, "
            f"{worst['statistic'] / worst['threshold']:.3g} times its threshold "
            f"{worst['threshold']:.4g}"
            + (f" ({more} more of the {len(table)} tests failed, fit.csv)" if more else
               f" (1 of the {len(table)} tests, fit.csv)")
            + "; every coefficient's verdict is 'model does not fit'.")
