"""The vocabulary every result with estimates speaks, and the one printable table.

A result with estimates (hull coefficients, fin lift slopes, the scaling's resistance fit,
identified coefficients) gives, like a statsmodels fit:

    params              Series by symbol: the estimates [each its unit]
    bse                 Series by symbol: their standard errors [each its unit]
    conf_int(alpha)     DataFrame by symbol, columns ``lower`` and ``upper``
    summary(alpha)      a :class:`Summary`
    to_frame()          the DataFrame its CSV is written from

from one table of its estimates (:meth:`Estimates.estimate_frame`: ``value``, ``std_error``,
``dof``, ``unit`` by symbol); the interval is value ∓ t₁₋α/₂(ν)·u (ν = ∞: the normal one).
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import TypeVar

import numpy as np
import pandas as pd

from towtank.stats.quantiles import interval

R = TypeVar("R")

#: The columns of every ``conf_int``.
CONF_INT_COLUMNS = ["lower", "upper"]
#: The columns of every ``estimate_frame`` (indexed by ``symbol``).
ESTIMATE_COLUMNS = ["value", "std_error", "dof", "unit"]


def esc(text: object) -> str:
    """``text`` escaped for HTML."""
    return html.escape(str(text))


def level_text(alpha: float) -> str:
    """The level of an interval of significance ``alpha`` as text ("95 %")."""
    return f"{100.0 * (1.0 - alpha):g} %"


def bounds_text(alpha: float) -> tuple[str, str]:
    """The column names of the interval's ends in a summary: ``[α/2`` and ``1 − α/2]`` with
    ``alpha`` written as a number."""
    return f"[{alpha / 2:g}", f"{1 - alpha / 2:g}]"


@dataclass(frozen=True)
class Summary:
    """A printable coefficient table: ``print(summary)``, ``summary.table`` (a DataFrame) and
    its HTML form in a notebook."""

    title: str
    table: pd.DataFrame
    notes: tuple[str, ...] = ()

    def as_text(self) -> str:
        """The table as fixed-width text, framed like a statsmodels summary."""
        if not len(self.table):  # no estimates: no pandas "Empty DataFrame" frame
            width = max(60, len(self.title))
            rule = "=" * width
            return "\n".join([self.title.center(width), rule, "(no estimates)", rule,
                              *self.notes])
        body = self.table.to_string(index=False, float_format=lambda v: f"{v:.5g}")
        width = max(max(len(line) for line in body.splitlines()), len(self.title))
        rule = "=" * width
        lines = [self.title.center(width), rule]
        body_lines = body.splitlines()
        lines += [body_lines[0], "-" * width, *body_lines[1:], rule]
        lines += list(self.notes)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.as_text()

    def __repr__(self) -> str:
        return self.as_text()

    def _repr_html_(self) -> str:
        notes = "".join(f"<p>{esc(n)}</p>" for n in self.notes)
        return (f"<p><b>{esc(self.title)}</b></p>"
                + self.table.to_html(index=False, float_format=lambda v: f"{v:.5g}") + notes)


def estimate_frame(symbols: Sequence[str], value: Sequence[float] | np.ndarray,
                   std_error: Sequence[float] | np.ndarray, dof: Sequence[float] | np.ndarray,
                   unit: Sequence[str]) -> pd.DataFrame:
    """The estimates of a result as one table.

    Parameters
    ----------
    symbols : sequence of str
        The index (``symbol``).
    value, std_error : array_like
        The estimates and their standard uncertainties [each its unit].
    dof : array_like
        Degrees of freedom of each standard uncertainty [-] (∞ for a normal interval).
    unit : sequence of str
        Each estimate's unit.

    Returns
    -------
    DataFrame
        Indexed by ``symbol``, columns :data:`ESTIMATE_COLUMNS`.
    """
    return pd.DataFrame(
        {"value": np.asarray(value, dtype=float), "std_error": np.asarray(std_error, dtype=float),
         "dof": np.asarray(dof, dtype=float), "unit": list(unit)},
        index=pd.Index(list(symbols), name="symbol"), columns=ESTIMATE_COLUMNS)


def conf_int_frame(estimates: pd.DataFrame, alpha: float = 0.05) -> pd.DataFrame:
    """Two-sided intervals of level 1 − ``alpha`` of an :func:`estimate_frame`: value ∓
    t₁₋α/₂(ν)·u [each its unit], NaN where u is; columns ``lower``, ``upper`` by symbol."""
    rows = [(math.nan, math.nan) if math.isnan(s) else interval(v, s, d, alpha)
            for v, s, d in zip(estimates["value"], estimates["std_error"], estimates["dof"],
                               strict=True)]
    return pd.DataFrame(rows, index=estimates.index, columns=CONF_INT_COLUMNS, dtype=float)


def estimates_summary(title: str, estimates: pd.DataFrame, ci: pd.DataFrame, alpha: float,
                      notes: tuple[str, ...] = ()) -> Summary:
    """The :class:`Summary` of estimates and their intervals: symbol, value, unit, std err,
    dof and the interval's ends."""
    lo, hi = bounds_text(alpha)
    table = pd.DataFrame({
        "symbol": estimates.index, "value": estimates["value"].to_numpy(),
        "unit": estimates["unit"].to_numpy(), "std err": estimates["std_error"].to_numpy(),
        "dof": estimates["dof"].to_numpy(), lo: ci["lower"].to_numpy(),
        hi: ci["upper"].to_numpy()})
    return Summary(title=title, table=table,
                   notes=(f"{level_text(alpha)} intervals, value ∓ t·std err at each "
                          "estimate's degrees of freedom (normal where dof = inf).", *notes))


def from_fit(cls: type[R], fit: object) -> R:
    """The result ``cls`` (a dataclass deriving from the class of the stage's ``fit``) of
    ``fit``: the same fields, the results vocabulary added."""
    return cls(**{f.name: getattr(fit, f.name) for f in fields(fit)})  # type: ignore[arg-type]


class Estimates:
    """The results vocabulary, from the result's :meth:`estimate_frame`.

    A result class derives from it and gives :meth:`estimate_frame`; it may refine
    :meth:`conf_int` (the hull's 95 % intervals are coefficients.csv's) and :meth:`summary`.
    """

    def estimate_frame(self) -> pd.DataFrame:
        """The estimates: ``value``, ``std_error``, ``dof``, ``unit`` by ``symbol``."""
        raise NotImplementedError

    def to_frame(self) -> pd.DataFrame:
        """The table the result's CSV is written from."""
        raise NotImplementedError

    @property
    def params(self) -> pd.Series:
        """The estimates by symbol [each its unit]."""
        return self.estimate_frame()["value"].rename("params")

    @property
    def bse(self) -> pd.Series:
        """The standard errors of the estimates by symbol [each its unit]."""
        return self.estimate_frame()["std_error"].rename("bse")

    def conf_int(self, alpha: float = 0.05) -> pd.DataFrame:
        """Two-sided intervals of level 1 − ``alpha`` [each estimate's unit].

        Returns
        -------
        DataFrame
            Indexed by symbol, columns ``lower`` and ``upper``.
        """
        return conf_int_frame(self.estimate_frame(), alpha)

    def summary_title(self) -> str:
        """The title of :meth:`summary`."""
        return f"{type(self).__name__} ({len(self.estimate_frame())} estimates)"

    def summary(self, alpha: float = 0.05) -> Summary:
        """The estimates with their standard errors, degrees of freedom and the intervals of
        level 1 − ``alpha``."""
        return estimates_summary(self.summary_title(), self.estimate_frame(),
                                 self.conf_int(alpha), alpha)

    def _repr_html_(self) -> str:
        """In a notebook: the :meth:`summary` table (never the raw frames)."""
        return self.summary()._repr_html_()
