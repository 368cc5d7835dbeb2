"""The day's tare policy: which tare each run has subtracted (docs/method.md "Sting tare").

``[tare] source`` says where a group's tare comes from: fitted to the group's sting runs
(:func:`fit_tares`, the default), the protocol's tare table (one model for every group) or
none. :func:`apply_tares` then subtracts each model run's group tare; a run whose group has no
usable sting run is rejected. Each function returns new values; nothing given is changed.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from towtank.ingest.protocol_types import Protocol
from towtank.messages import Rejection
from towtank.reduce.run import RunReduction, apply_tare
from towtank.reduce.tare import TareModel, fit_tare_group, table_tare

__all__ = ["apply_tares", "fit_tares", "tare_models"]


def fit_tares(
    sheet: pd.DataFrame, reductions: Mapping[int, RunReduction]
) -> dict[str, TareModel]:
    """One tare model per group from that group's usable sting runs."""
    out: dict[str, TareModel] = {}
    stings = sheet[(sheet["config"] == "sting") & sheet["run"].isin(list(reductions))]
    for group, rows in stings.groupby("tare_group", sort=True):
        reds = [reductions[int(r)] for r in rows["run"]]
        s = {k: np.concatenate([r.samples[k] for r in reds]) for k in ("U", "a", "drag", "lift")}
        has_lift = all(r.has_lift for r in reds)
        out[str(group)] = fit_tare_group(
            str(group),
            [r.run for r in reds],
            s["U"],
            s["a"],
            s["drag"],
            s["lift"] if has_lift else None,
            [r.speed_mean for r in reds],
            sample_runs=np.concatenate([np.full(r.samples["U"].size, r.run) for r in reds]),
        )
    return out


def tare_models(
    protocol: Protocol,
    sheet: pd.DataFrame,
    reductions: Mapping[int, RunReduction],
) -> tuple[dict[str, TareModel], list[str]]:
    """The tare of every group, as ``[tare] source`` says: fitted to the sting runs (default),
    from the tare table (one model for every group of the sheet) or none (empty); and the
    warnings of that choice."""
    source = protocol.tare
    if source.source == "none":
        return {}, ["no tare is subtracted ([tare] source = \"none\"): the forces are those of "
                    "the model and its mounting together."]
    if source.source == "table":
        out = {}
        warnings = []
        for group in sorted({str(g) for g in sheet["tare_group"]}):
            out[group], departure = table_tare(group, source.speeds_m_s, source.drag_N,
                                               source.lift_N or None)
        if departure > 0.02 * max(abs(v) for v in source.drag_N):
            warnings.append(
                f"the tare table {Path(source.table).name} departs from t2·U|U| + t1·U by up to "
                f"{departure:.3g} N; check its points."
            )
        return out, warnings
    return fit_tares(sheet, reductions), []


def apply_tares(
    protocol: Protocol,
    sheet: pd.DataFrame,
    reductions: Mapping[int, RunReduction],
    tares: Mapping[str, TareModel],
) -> tuple[dict[int, RunReduction], dict[int, Rejection]]:
    """Each run's reduction with its group's tare subtracted (a sting run's and every run's
    without a tare: none), in the order of ``reductions``; and the rejections of the model runs
    whose tare group has no usable sting run."""
    config_of = dict(zip(sheet["run"].astype(int), sheet["config"], strict=True))
    group_of = dict(zip(sheet["run"].astype(int), sheet["tare_group"], strict=True))
    tared: dict[int, RunReduction] = {}
    rejected: dict[int, Rejection] = {}
    for run, red in reductions.items():
        if config_of[run] == "sting" or protocol.tare.source == "none" or red.captive:
            # a captive balance carries the model alone: its mounting's load is in the zero
            tared[run] = apply_tare(red, None)
            continue
        tare = tares.get(group_of[run])
        if tare is None:
            rejected[run] = Rejection(
                run, red.file, "tare",
                f"its tare group '{group_of[run]}' has no usable sting (tare) run, so the "
                "mounting's force cannot be removed", "no_tare")
            continue
        tared[run] = apply_tare(red, tare)
    return tared, rejected
