"""The day's pipeline: protocol → run sheet → runs → reductions → tare → fits → outputs.

Each stage is a module of its own and data flows one way; this module only wires them. Any
failure confined to one run rejects that run with one sentence and the rest of the day goes on;
a protocol or run-sheet fault stops before anything is written.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.analysis import hull as fit
from towtank.analysis import scaling
from towtank.analysis.captive import captive_runs_from_means, fit_captive
from towtank.analysis.daywide import (
    run_warning_lines,
    sheet_note_sentences,
    temperature_problems,
    unit_label_sentences,
)
from towtank.analysis.fin_analysis import analyse_fins
from towtank.analysis.plausibility import displaced_volume, plausibility_warnings
from towtank.analysis.run_table import run_table
from towtank.analysis.scaling import model_scale
from towtank.analysis.similarity import check_protocol_speeds, medium_at
from towtank.errors import ProtocolError, TowtankError
from towtank.ingest.captive_means import captive_means
from towtank.ingest.inputs import (
    day_inputs,
    day_sheet,
    runs_to_reduce,
    side_files_sha,
    unlisted_warnings,
)
from towtank.ingest.protocol import Protocol, load_protocol
from towtank.ingest.runsheet import CAPTIVE_TESTS
from towtank.messages import Notice, Rejection, Stage, notices
from towtank.reduce.captive import CaptiveRun, protocol_reference_x
from towtank.reduce.run import RunReduction, crashed_record, reduce_record
from towtank.reduce.sanity import sane_reduction
from towtank.reduce.tare import TareModel
from towtank.reduce.tare_policy import apply_tares, tare_models
from towtank.results import (
    CaptiveResult,
    DayResult,
    FinResult,
    HullResult,
    ScalingResult,
    VehicleResult,
    from_fit,
)
from towtank.runtime import parallel
from towtank.runtime.cache import RunCache, protocol_settings, settings_key
from towtank.runtime.pause import pause_at
from towtank.vehicle.compare import day_vehicle

__all__ = ["DayResult", "FinResult", "HullResult", "ScalingResult", "VehicleResult",
           "process_day", "process_sheet", "unlisted_warnings"]

#: What the fitting stages import: loaded while the workers reduce the runs.
ANALYSIS_MODULES = (
    "scipy.stats",
    "statsmodels.regression.linear_model",
    "iapws",
    "scipy.interpolate",
    "towtank.analysis.hull",
    "towtank.analysis.fins",
    "towtank.analysis.similarity",
    "towtank.reference.water",
    "towtank.reference.air",
)


def process_day(
    protocol_path: str | Path,
    *,
    jobs: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    debug: bool = False,
    protocol: Protocol | None = None,
    cache_dir: str | Path | None = None,
) -> DayResult:
    """Run the whole day: everything but writing the outputs.

    Raises ProtocolError for an unusable protocol or run sheet; per-run problems only reject
    those runs.
    """
    if protocol is None:
        protocol = load_protocol(protocol_path)
    sheet = day_sheet(protocol)
    return process_sheet(protocol, sheet, jobs=jobs, progress=progress, debug=debug,
                         cache_dir=cache_dir)


def process_sheet(
    protocol: Protocol,
    sheet: pd.DataFrame,
    *,
    jobs: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    debug: bool = False,
    cache_dir: str | Path | None = None,
    unlisted: list[Notice] | None = None,
) -> DayResult:
    """:func:`process_day` on a run sheet already read (:func:`read_run_sheet`), e.g. the
    rows of a day whose files are complete (``towtank watch``). ``unlisted``: the warnings of
    the data files no row names, default :func:`unlisted_warnings` of ``sheet``."""
    if jobs is None:
        jobs = protocol.processing.jobs  # None too: every core
    todo, sheet_rejected = runs_to_reduce(protocol, sheet)
    reduced = reduce_runs(protocol, sheet, todo, jobs=jobs, progress=progress, debug=debug,
                          cache_dir=cache_dir)
    tares, tare_said = tare_models(protocol, sheet, reduced.reductions)
    reductions, untared = apply_tares(protocol, sheet, reduced.reductions, tares)
    rejected = {**sheet_rejected, **reduced.rejected, **untared}
    ordered = sorted(reductions.values(), key=lambda r: r.run)
    day_warnings = (
        *notices(protocol.warnings, "protocol"),
        *notices(sheet.attrs.get("warnings", []), "sheet"),
        *(unlisted_warnings(protocol, sheet) if unlisted is None else unlisted),
        *notices(sheet_note_sentences(sheet.attrs.get("notes", [])), "sheet"),
        *notices(reduced.warnings, "reduce"),
        *notices(tare_said, "tare"),
        *notices(unit_label_sentences([(r.run, r.file, r.units) for r in ordered]), "reduce"),
        *(Notice(line, "reduce", run, file) for run, file, line in run_warning_lines(
            [(r.run, r.file, w) for r in ordered for w in r.warnings])),
        *(Notice(line, "sheet", run) for run, line in temperature_problems(
            sheet, air=protocol.water.is_air)),
    )
    day = DayResult(
        protocol=protocol, sheet=sheet, reductions=reductions, rejected=rejected, tares=tares,
        runs=run_table(protocol, sheet, reductions, rejected), warnings=day_warnings,
        inputs=day_inputs(protocol, sheet, {r.file: r.sha256 for r in reductions.values()}),
        previews=reduced.previews,
    )
    check_protocol_speeds(protocol)
    return analyse(day)


@dataclass(frozen=True)
class Reduced:
    """What :func:`reduce_runs` gives: the reductions (in sheet order), the rejections, the
    previews of runs read but not reduced, and the warnings (a cache that cannot be used)."""

    reductions: dict[int, RunReduction]
    rejected: dict[int, Rejection]
    previews: dict[int, dict[str, np.ndarray]]
    warnings: tuple[str, ...]


def reduce_runs(
    protocol: Protocol,
    sheet: pd.DataFrame,
    todo: list[dict[str, Any]],
    *,
    jobs: int | None,
    progress: Callable[[int, int], None] | None,
    debug: bool,
    cache_dir: str | Path | None,
) -> Reduced:
    """Every run of ``todo`` reduced (from the cache, or in worker processes), in sheet order,
    with the rejections of those that cannot be and the previews of runs read but not
    reduced."""
    warnings: list[str] = []
    reductions: dict[int, RunReduction] = {}
    cache = RunCache(cache_dir, RunReduction, sane_reduction) if cache_dir is not None \
        else None
    said = cache.problem if cache is not None else None
    if said:
        warnings.append(said)
    common = protocol_settings(protocol) if cache is not None else None
    keys: dict[int, str] = {}
    to_reduce = []
    for rec in todo:
        run = int(rec["run"])
        if cache is not None:
            keys[run] = settings_key(protocol, rec, common,
                                     side_files_sha(protocol, str(rec["file"]), run))
            hit = cache.hit(protocol.campaign.data_dir / str(rec["file"]), str(rec["file"]),
                            keys[run], run)
            if hit is not None:
                reductions[run] = hit
                continue
        to_reduce.append(rec)
    done = len(todo) - len(to_reduce)
    if progress is not None and done:
        progress(done, len(todo))
    previews: dict[int, dict[str, np.ndarray]] = {}
    rejected: dict[int, Rejection] = {}
    for i, (run, red, rejection, preview) in enumerate(
        parallel.map_runs(reduce_record, protocol, to_reduce, jobs=jobs, debug=debug,
                 on_crash=crashed_record, preload=ANALYSIS_MODULES)
    ):
        if red is not None:
            reductions[run] = red
            if cache is not None:
                cache.put(red.sha256, keys[run], red)
                cache.remember_sha(protocol.campaign.data_dir / red.file, red.sha256,
                                   red.file_stamp)
        else:
            assert rejection is not None
            rejected[run] = rejection
            if preview is not None:
                previews[run] = preview
        if progress is not None:
            progress(done + i + 1, len(todo))
        if i == 0:
            pause_at("reduce")  # a test hook (towtank.runtime.pause); returns at once otherwise
    if cache is not None:
        cache.flush()
        if cache.problem and cache.problem != said:  # a problem met while writing
            warnings.append(cache.problem)
    # keep the sheet's order whatever the order of cache hits and fresh reductions
    order = {int(r): k for k, r in enumerate(sheet["run"])}
    return Reduced(dict(sorted(reductions.items(), key=lambda kv: order[kv[0]])), rejected,
                   previews, tuple(warnings))


def analyse(day: DayResult) -> DayResult:
    """The fitting stages on the reduced runs, in order: hull coefficients, fins, scaling,
    vehicle. Each stage returns its result and its warnings; a stage's TowtankError becomes a
    warning of the day. Returns the day with the results (the given day is not changed)."""
    pause_at("fits")  # a test hook (towtank.runtime.pause); returns at once otherwise
    warns = list(day.warnings)
    p = day.protocol
    runs = tow_runs(day.runs)  # the captive runs have a stage of their own
    hull = fin = scaling = vehicle = None
    prototype = None

    def failed(exc: TowtankError, stage: Stage) -> None:
        warns.append(Notice(str(exc), stage))

    try:
        hull, more = hull_stage(p, runs, day.reductions, day.tares)
        warns += notices(more, "hull")
    except TowtankError as exc:
        failed(exc, "hull")
    try:
        fin, more = fin_stage(p, runs)
        warns += notices(more, "fins")
    except TowtankError as exc:
        failed(exc, "fins")
    try:
        scaling, prototype, more = scaling_stage(p, runs, hull)
        warns += notices(more, "scaling")
    except TowtankError as exc:
        failed(exc, "scaling")
    captive: dict[str, CaptiveResult] = {}
    try:
        captive, more = captive_stage(p, day.runs, day.reductions)
        warns += notices(more, "captive")
    except TowtankError as exc:
        failed(exc, "captive")
    try:
        vehicle = vehicle_stage(p, hull, prototype, tuple(captive.values()))
        warns += notices(vehicle.warnings, "vehicle") if vehicle is not None else []
    except TowtankError as exc:
        failed(exc, "vehicle")
    return replace(day, warnings=tuple(warns), hull=hull, fins=fin, scaling=scaling,
                   vehicle=vehicle, prototype_values=prototype,
                   captive=captive.get("horizontal"),
                   captive_vertical=captive.get("vertical"))


def tow_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """runs.csv's rows without the captive runs (``test`` one of
    :data:`towtank.ingest.runsheet.CAPTIVE_TESTS`): the rows the hull, fin and scaling stages
    take."""
    if "test" not in runs.columns:
        return runs
    return runs[~runs["test"].isin(CAPTIVE_TESTS)]


def captive_stage(protocol: Protocol, runs: pd.DataFrame, reductions: dict[int, RunReduction]
                  ) -> tuple[dict[str, CaptiveResult], list[str]]:
    """The captive derivatives (:func:`towtank.analysis.captive.fit_captive`) of the day's
    usable captive runs and, with ``[captive] means``, of the lab's table of means, one result
    per plane (horizontal, vertical) that has runs; ({}, []) with neither."""
    model = protocol.model
    ok = set(runs.loc[runs["status"] == "ok", "run"].astype(int)) if len(runs) else set()
    caps = [CaptiveRun.from_arrays(r.run, r.file, r.captive)
            for run, r in reductions.items() if r.captive and run in ok]
    warns: list[str] = []
    options = protocol.captive
    rho = medium_at(protocol.water)[0]
    if model is None:
        return {}, warns
    ref_x = protocol_reference_x(options, model)
    if options is not None and options.means is not None:
        table, said = captive_means(protocol)
        warns += said
        caps += captive_runs_from_means(
            table, balance_x_m=model.balance_x_m or 0.0, mass_kg=model.mass_kg,
            xg_m=model.xg_m or 0.0, ref_x_m=ref_x)
    roll = options.roll_deg if options is not None else 90.0
    out: dict[str, CaptiveResult] = {}
    for plane in ("horizontal", "vertical"):
        these = [c for c in caps if c.plane == plane]
        if these:
            fitted = fit_captive(these, rho=rho, length_m=model.length_m,
                                 draught_m=model.draught_m, plane=plane, roll_deg=roll,
                                 ref_x_m=ref_x)
            out[plane] = from_fit(CaptiveResult, fitted)
            warns += fitted.warnings
    return out, warns


def hull_stage(protocol: Protocol, runs: pd.DataFrame, reductions: dict[int, RunReduction],
               tares: dict[str, TareModel]) -> tuple[HullResult | None, list[str]]:
    """The hull coefficients (:func:`towtank.analysis.hull.fit_hull`) and their warnings; None
    without a [model] or usable hull runs."""
    model = protocol.model
    if model is None or not ((runs["config"] == "hull") & (runs["status"] == "ok")).any():
        return None, []
    if not math.isfinite(model.frontal_area):
        raise ProtocolError(
            f"{protocol.path.name}: the resistance runs' C_D needs the model's frontal area: "
            "give [model] diameter_m or frontal_area_m2; no hull coefficient was made.")
    hf = fit.fit_hull(
        runs,
        reductions,
        mass=model.mass_kg,
        mass_sd=model.mass_uncertainty_kg,
        length=model.length_m,
        frontal_area=model.frontal_area,
        lateral_area=model.lateral_area,
        alpha_max_deg=protocol.processing.damping_alpha_max_deg,
        tares=tares,
        rho=medium_at(protocol.water)[0],
    )
    ref = fit.load_reference(protocol.campaign.reference)
    table = fit.coefficients_table(hf, ref, model.length_uncertainty_m)
    warns = list(hf.messages)
    warns += plausibility_warnings(
        table, rho=hf.rho,
        volume_m3=displaced_volume(model.length_m, model.diameter_m, model.volume_m3),
        frontal_area_m2=model.frontal_area, lateral_area_m2=model.lateral_area,
        added_mass=not protocol.water.is_air,
    )
    warns += fit.hull_warnings(hf)
    return HullResult(fit=hf, coefficients=table, warnings=tuple(warns)), warns


def vehicle_stage(protocol: Protocol, hull: HullResult | None,
                  prototype_values: pd.DataFrame | None = None,
                  captive: tuple[CaptiveResult, ...] = ()) -> VehicleResult | None:
    """Prediction and model of the protocol's [vehicle]; predicted beside measured (the
    hull's coefficients and the captive derivatives)."""
    if getattr(protocol, "vehicle", None) is None:
        return None
    # coefficients.csv as the scaling stage leaves it
    tables = [scaling.with_prototype_values(hull.coefficients, prototype_values)
              if hull is not None else None,
              *(c.table() for c in captive)]
    present = [t for t in tables if t is not None]
    measured = pd.concat(present, ignore_index=True) if present else None
    prediction, table, warns = day_vehicle(protocol, measured)
    return VehicleResult(prediction=prediction, coefficients=table, warnings=tuple(warns))


def fin_stage(protocol: Protocol, runs: pd.DataFrame) -> tuple[FinResult | None, list[str]]:
    """The fins against the Sandia section data
    (:func:`towtank.analysis.fin_analysis.analyse_fins`); (None, []) without a [fin]."""
    if protocol.fin is None:
        return None, []
    fins, warns = analyse_fins(runs, protocol.fin)
    return (from_fit(FinResult, fins) if fins is not None else None), warns


def scaling_stage(protocol: Protocol, runs: pd.DataFrame, hull: HullResult | None
                  ) -> tuple[ScalingResult | None, pd.DataFrame | None, list[str]]:
    """Scaling to the [prototype] (:func:`towtank.analysis.scaling.scale_to_prototype`) and
    the hull coefficients' prototype values (:func:`towtank.analysis.scaling.prototype_values`);
    (None, None, []) without a [model] and a [prototype]."""
    model, proto = protocol.model, protocol.prototype
    if model is None or proto is None:
        return None, None, []
    scale = model_scale(protocol)
    assert scale is not None
    rho_p, nu_p = medium_at(proto.water)
    rho_m, nu_m = medium_at(protocol.water)
    values = (scaling.prototype_values(hull.coefficients, rho_p, proto.length_m)
              if hull is not None else None)
    result, warns = scaling.scale_to_prototype(
        runs, model, proto, scale=scale, rho_m=rho_m, nu_m=nu_m, rho_p=rho_p, nu_p=nu_p,
        laminar_re=protocol.processing.laminar_re,
        damping_alpha_max_deg=protocol.processing.damping_alpha_max_deg,
        free_surface=not protocol.water.is_air,
    )
    return (from_fit(ScalingResult, result) if result is not None else None), values, warns
