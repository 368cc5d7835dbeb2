"""The result of ``towtank identify``: the coefficients a manoeuvre record gives.

:func:`towtank.vehicle.identify.identify` returns an
:class:`~towtank.vehicle.identify.IdentifyFit`; ``from_fit(IdentifyResult, fit)`` adds the
results vocabulary (``params``, ``bse``, ``conf_int``, ``summary``, ``to_frame``), the
identifiability verdicts and identified.csv.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from towtank.results.summary import CONF_INT_COLUMNS, Estimates, Summary, estimate_frame
from towtank.stats.quantiles import normal_quantile
from towtank.vehicle.identify import IDENTIFIABLE_RATIO, IdentifyFit
from towtank.vehicle.predict import coefficient_unit

#: The normal quantile of a 95 % interval: an identifiable coefficient's interval half-width,
#: SIGN_Z·sd, is below its size (:meth:`IdentifyResult.identifiable`).
SIGN_Z = normal_quantile(0.05)
#: An identified value more than this many times the model's, or less than its inverse, is
#: named (:meth:`IdentifyResult.against_model`): predictions of a hull and fins hold their
#: coefficients within a factor of 2 to 3, a unit slip moves them by 57 (deg, rad) or 10^n.
MODEL_FACTOR = 10.0

__all__ = ["IdentifyResult", "MISFIT"]

#: The verdict of every coefficient when the record does not fit the model.
MISFIT = "model does not fit"


@dataclass(frozen=True, repr=False)
class IdentifyResult(IdentifyFit, Estimates):
    """What :func:`towtank.identify` found: the :class:`~towtank.vehicle.identify.IdentifyFit`
    (``symbols``, ``value``, ``sd``, ``covariance``, ``check``, ``history``, ``measured``,
    ``resimulated``, ``notes``) with its estimates by symbol (normal intervals: the filter's
    and least squares' standard deviations have no degrees of freedom)."""

    def estimate_frame(self, method: str | None = None) -> pd.DataFrame:
        """The estimates of ``method`` (None: the primary one; ``"ls"``: the cross-check)
        [each its unit] with their standard deviations (dof = ∞)."""
        val, sd = self._pair(method)
        return estimate_frame(self.symbols, val, sd, np.full(len(self.symbols), np.inf),
                              [coefficient_unit(s) for s in self.symbols])

    def conf_int(self, alpha: float = 0.05, method: str | None = None) -> pd.DataFrame:
        """Two-sided normal intervals of level 1 − ``alpha`` of ``method``'s estimates
        (None: the primary method's) [each its unit]: value ∓ z₁₋α/₂·sd.

        Returns
        -------
        DataFrame
            Indexed by symbol, columns ``lower`` and ``upper``.
        """
        z = normal_quantile(alpha)
        val, sd = self._pair(method)
        return pd.DataFrame(np.column_stack([val - z * sd, val + z * sd]),
                            index=pd.Index(self.symbols, name="symbol"),
                            columns=CONF_INT_COLUMNS)

    def _pair(self, method: str | None) -> tuple[np.ndarray, np.ndarray]:
        if method in (None, self.method):
            return self.value, self.sd
        if method == "ls" and self.check is not None:
            return self.check["value"], self.check["sd"]
        raise ValueError(f"no {method} estimates in this result.")

    def identifiable(self, method: str | None = None) -> np.ndarray:
        """True where the record constrains the coefficient: its sd below
        :data:`~towtank.vehicle.identify.IDENTIFIABLE_RATIO` of its prior sd (and finite),
        and its 95 % interval's half-width, :data:`SIGN_Z` sd, below its size, the larger of
        its estimate and its starting value: the record fixes its sign and its order of
        magnitude. The
        prior's scale, 3 max(|value|, 1), is wide for a coefficient far below 1 in SI (a roll
        damping K_p|p| of −0.0055 kg·m² on REMUS): by the prior alone an estimate 21 times the
        truth with an interval across zero was called identifiable."""
        value, sd = self._pair(method)
        size = np.maximum(np.abs(value), np.abs(self.start))
        return (np.isfinite(sd) & (sd < IDENTIFIABLE_RATIO * self.prior_sd)
                & (SIGN_Z * sd < size))

    def verdict(self, identifiable: bool) -> str:
        """identified.csv's verdict: ``model does not fit`` when a test of the record's fit
        to the model failed (:attr:`adequacy`), else ``identifiable`` or ``not
        identifiable``."""
        if not self.fits():
            return MISFIT
        return "identifiable" if identifiable else "not identifiable"

    def agree(self, alpha: float = 0.05) -> np.ndarray | None:
        """Filter and least squares agree where their difference is within its interval:
        ``|a - b| <= z sqrt(sd_a^2 + sd_b^2)``; None without the cross-check."""
        if self.check is None:
            return None
        z = normal_quantile(alpha)
        diff = np.abs(self.value - self.check["value"])
        return diff <= z * np.hypot(self.sd, self.check["sd"])

    def table(self, alpha: float = 0.05) -> pd.DataFrame:
        """identified.csv: symbol, start, value, ci_low, ci_high, method, unit, verdict, agree
        (the primary method's rows, then the cross-check's)."""
        rows = []
        agree = self.agree(alpha)
        methods = [self.method] + (["ls"] if self.check is not None else [])
        for m in methods:
            val, _ = self._pair(m)
            ci = self.conf_int(alpha, m)
            ok = self.identifiable(m)
            for j, s in enumerate(self.symbols):
                rows.append({
                    "symbol": s, "start": self.start[j], "value": val[j],
                    "ci_low": ci["lower"].iloc[j], "ci_high": ci["upper"].iloc[j],
                    "method": m, "unit": coefficient_unit(s),
                    "verdict": self.verdict(ok[j]),
                    "agree": "" if agree is None else ("yes" if agree[j] else "no")})
        return pd.DataFrame(rows)

    def to_frame(self) -> pd.DataFrame:
        """identified.csv (:meth:`table` at 95 %)."""
        return self.table()

    def verdicts(self, alpha: float = 0.05) -> list[str]:
        """One line per coefficient for the terminal."""
        lines = []
        ci = self.conf_int(alpha)
        ok = self.identifiable()
        agree = self.agree(alpha)
        pct = round(100 * (1 - alpha))
        for j, s in enumerate(self.symbols):
            lo, hi = ci["lower"].iloc[j], ci["upper"].iloc[j]
            if not self.fits():
                line = (f"{s}: {MISFIT}, {self.value[j]:.4g} {coefficient_unit(s)} "
                        f"({pct} % interval {lo:.4g} to {hi:.4g}, {self.method}, not to be "
                        "trusted: the record does not fit the model, fit.csv)")
            elif ok[j]:
                line = (f"{s}: identifiable, {self.value[j]:.4g} {coefficient_unit(s)} "
                        f"({pct} % interval {lo:.4g} to {hi:.4g}, {self.method})")
            elif self.sd[j] < IDENTIFIABLE_RATIO * self.prior_sd[j]:  # narrow, yet not its sign
                size = max(abs(self.value[j]), abs(self.start[j]))
                line = (f"{s}: NOT identifiable from this record: 95 % interval {lo:.4g} to "
                        f"{hi:.4g}, ±{SIGN_Z * self.sd[j]:.3g}, wider than the coefficient's "
                        f"size {size:.3g} (the larger of its estimate and its start): the "
                        "record does not fix its sign; the manoeuvre does not excite it enough")
            else:
                line = (f"{s}: NOT identifiable from this record: {pct} % interval {lo:.4g} "
                        f"to {hi:.4g}, its sd {self.sd[j]:.3g} still "
                        f"{self.sd[j] / self.prior_sd[j]:.0%} of the prior's "
                        f"{self.prior_sd[j]:.3g} (identifiable below "
                        f"{IDENTIFIABLE_RATIO:.0%}); the manoeuvre does not excite it enough")
            if agree is not None and self.check is not None:
                lv = self.check["value"][j]
                line += ("; least squares agrees" if agree[j] else
                         "; least squares DISAGREES") + f" ({lv:.4g})"
            lines.append(line)
        return lines

    def against_model(self, model_values: Mapping[str, float]) -> list[str]:
        """One sentence per coefficient whose estimate, its 95 % interval clear of zero,
        contradicts the model's value ``model_values[symbol]`` (SI): the opposite sign, or a
        size more than :data:`MODEL_FACTOR` times larger or smaller (identifiable or not: the
        prior, scaled by the model's value, is too narrow for a value 57 times it). For a
        control derivative (δr, δs) that is the record's control in other units or with its
        sign reversed: a ratio near 180/π is a control angle in radians under a *_deg column
        (its derivatives 57 times too large)."""
        out = []
        ci = self.conf_int()
        for j, s in enumerate(self.symbols):
            ref = float(model_values.get(s, 0.0) or 0.0)
            v = float(self.value[j])
            if ref == 0.0 or not abs(v) > SIGN_Z * float(self.sd[j]):
                continue  # no model value, or a sign the record does not fix
            control = s.endswith(("dr", "ds"))
            what = ("the rudder's" if s.endswith("dr") else "the stern plane's") if control \
                else ""
            lo, hi = float(ci["lower"].iloc[j]), float(ci["upper"].iloc[j])
            if v * ref < 0 and (lo > 0 or hi < 0):
                hint = (f"is {what} sign convention reversed in the record?" if control else
                        "is a sign convention of the record (an axis, a positive turn) "
                        "reversed?")
                out.append(f"{s} = {v:.4g} {coefficient_unit(s)} has the opposite sign of "
                           f"the model's {ref:.4g}: {hint}")
                continue
            ratio = abs(v / ref)
            if ratio > MODEL_FACTOR or ratio < 1.0 / MODEL_FACTOR:
                rad = abs(math.log(ratio / (180.0 / math.pi))) < 0.2
                hint = (f"is {what} angle in radians under its _deg column?" if control and rad
                        else f"is {what} angle in other units?" if control
                        else "is a column of the record in other units?")
                out.append(f"{s} = {v:.4g} {coefficient_unit(s)} is {ratio:.3g} times the "
                           f"model's {ref:.4g}: {hint}")
        return out

    def summary(self, alpha: float = 0.05) -> Summary:
        """The identified coefficients (identified.csv's rows) with the verdicts as notes."""
        return Summary(title=f"Identified coefficients ({self.method}, "
                             f"{len(self.symbols)} estimates)",
                       table=self.table(alpha), notes=tuple(self.verdicts(alpha)))

    def __repr__(self) -> str:
        return f"IdentifyResult({', '.join(self.symbols)} by {self.method})"
