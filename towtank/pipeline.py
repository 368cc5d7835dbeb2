"""The day's pipeline: protocol → run sheet → runs → reductions → tare → fits → outputs.

Each stage is a module of its own and data flows one way; this module only wires them. Any
failure confined to one run rejects that run with one sentence and the rest of the day goes on;
a protocol or run-sheet fault stops before anything is written.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.analysis import hull as fit
from towtank.analysis import scaling, similarity
from towtank.analysis.daywide import (
    run_warning_lines,
    sheet_note_sentences,
    temperature_problems,
    unit_label_sentences,
)
from towtank.analysis.fin_analysis import analyse_fins
from towtank.analysis.plausibility import displaced_volume, plausibility_warnings
from towtank.analysis.run_coefficients import run_coefficients
from towtank.analysis.scaling import geometry_used, model_scale  # noqa: F401 - re-exported
from towtank.analysis.similarity import medium_at
from towtank.errors import ProtocolError, TowtankError
from towtank.ingest.protocol import (
    Protocol,
    SpeedLog,
    ZeroFile,
    load_protocol,
)
from towtank.ingest.runfile import sha256_bytes
from towtank.ingest.runsheet import read_run_sheet, unlisted_files
from towtank.ingest.speedlog import log_path, log_sha
from towtank.reduce.run import (
    RunReduction,
    apply_tare,
    crashed_record,
    reduce_record,
)
from towtank.reduce.sanity import sane_reduction
from towtank.reduce.tare import TareModel, fit_tare_group, table_tare
from towtank.reference.sets import BUILTIN_REFERENCES
from towtank.results import (
    DayResult,
    FinResult,
    HullResult,
    Notice,
    ScalingResult,
    Stage,
    VehicleResult,
    notices,
)
from towtank.runtime import parallel
from towtank.runtime.cache import RunCache, protocol_settings, settings_key
from towtank.runtime.pathcheck import is_regular_file, resolved
from towtank.runtime.pause import pause_at
from towtank.vehicle.compare import day_vehicle

__all__ = ["DayResult", "FinResult", "HullResult", "ScalingResult", "VehicleResult",
           "process_day", "process_sheet"]

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


def fit_tares(
    sheet: pd.DataFrame, reductions: dict[int, RunReduction]
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
    reductions: dict[int, RunReduction],
    day_warnings: list[str],
) -> dict[str, TareModel]:
    """The tare of every group, as ``[tare] source`` says: fitted to the sting runs (default),
    from the tare table (one model for every group of the sheet) or none (empty)."""
    source = protocol.tare
    if source.source == "none":
        day_warnings.append("no tare is subtracted ([tare] source = \"none\"): the forces are "
                            "those of the model and its mounting together.")
        return {}
    if source.source == "table":
        out = {}
        for group in sorted({str(g) for g in sheet["tare_group"]}):
            out[group], departure = table_tare(group, source.speeds_m_s, source.drag_N,
                                               source.lift_N or None)
        if departure > 0.02 * max(abs(v) for v in source.drag_N):
            day_warnings.append(
                f"the tare table {Path(source.table).name} departs from t2·U|U| + t1·U by up to "
                f"{departure:.3g} N; check its points."
            )
        return out
    return fit_tares(sheet, reductions)


def check_prototype_speeds(protocol: Protocol) -> None:
    """Raise ProtocolError unless every [prototype] speed is finite, > 0 and gives Re_p >= 1e3.

    Needs the prototype water's viscosity, so it runs once the analysis libraries are loaded
    (after the reductions), not in :func:`towtank.ingest.protocol.load_protocol`.
    """
    proto = protocol.prototype
    if protocol.model is None or proto is None:
        return
    _, nu_p = medium_at(proto.water)
    try:
        similarity.check_prototype_speeds(proto.speeds_m_s, proto.length_m, nu_p)
    except ValueError as exc:
        raise ProtocolError(
            f"{protocol.path.name}: 'speeds_m_s' in [prototype] cannot be scaled: {exc}"
        ) from None


RUN_COLUMNS = [
    "run", "file", "config", "angle_deg", "status", "reason", "speed_mean", "accel_mean",
    "drag_mean", "lift_mean", "tare_drag", "cd", "cl", "re", "fn",
]
EXTRA_COLUMNS = [
    "test", "tare_group", "speed_nominal", "accel_nominal", "water_temp_C", "rho", "nu",
    "speed_std", "speed_source", "speed_u", "drag_std", "lift_tare", "cd_lateral", "cd_ref",
    "ref_area", "ref_area_m2", "zero_drag", "drift_drag", "zero_lift",
    "drift_lift", "still_pre_start_s", "still_pre_end_s", "accel_start_s", "accel_end_s",
    "steady_start_s", "steady_end_s", "decel_start_s", "decel_end_s", "window_source",
    "fs_hz", "n_samples", "sha256", "notes", "remarks",
]


def run_table(
    protocol: Protocol,
    sheet: pd.DataFrame,
    reductions: dict[int, RunReduction],
    rejected: dict[int, str],
) -> pd.DataFrame:
    """runs.csv: one row per run of the sheet (docs/formats.md §5), then extension columns;
    each usable run's coefficients from
    :func:`towtank.analysis.run_coefficients.run_coefficients`."""
    rows = []
    model, fin = protocol.model, protocol.fin
    for rec in sheet.to_dict("records"):
        run = int(rec["run"])
        status = "void" if rec["status"] == "void" else "ok"
        reason = rec["remarks"] if status == "void" else ""
        if run in rejected:
            status, reason = "rejected", rejected[run]
        row: dict[str, Any] = {c: math.nan for c in RUN_COLUMNS + EXTRA_COLUMNS}
        row.update(
            run=run, file=rec["file"], config=rec["config"], angle_deg=rec["angle_deg"],
            status=status, reason=reason, test=rec["test"], tare_group=rec["tare_group"],
            speed_nominal=rec["speed_nominal"], accel_nominal=rec["accel_nominal"],
            water_temp_C=rec["water_temp_C"], remarks=rec["remarks"], notes="",
            window_source="", sha256="", ref_area="",
        )
        red = reductions.get(run)
        if red is not None and status == "ok":
            rho, nu = medium_at(protocol.water, rec["water_temp_C"])
            u = red.speed_mean
            row.update(
                speed_mean=u, accel_mean=red.accel_mean, drag_mean=red.drag_mean,
                lift_mean=red.lift_mean, tare_drag=red.tare_drag, lift_tare=red.tare_lift,
                rho=rho, nu=nu, speed_std=red.speed_std, speed_source=red.speed_source,
                speed_u=red.speed_u, drag_std=red.drag_std,
                zero_drag=red.zero_drag, drift_drag=red.drift_drag, zero_lift=red.zero_lift,
                drift_lift=red.drift_lift, window_source=red.window_source, fs_hz=red.fs,
                n_samples=red.n_samples, sha256=red.sha256, notes="; ".join(red.notes),
            )
            for name in ("still_pre", "accel", "steady", "decel"):
                w = red.windows.get(name)
                if w is not None:
                    row[f"{name}_start_s"], row[f"{name}_end_s"] = w
            row.update(run_coefficients(str(rec["config"]), float(rec["angle_deg"]),
                                        red.drag_mean, red.lift_mean, u, rho, nu, model, fin))
        rows.append(row)
    df = pd.DataFrame(rows, columns=RUN_COLUMNS + EXTRA_COLUMNS)
    extra = [c for c in sheet.columns if c not in df.columns and c not in ("sheet_row",
                                                                           "sheet_error",
                                                                           "window_start_s",
                                                                           "window_end_s")]
    for c in extra:
        df[c] = sheet[c].to_numpy()
    if "segment" in df.columns:  # whole numbers from 1 (a run's acquisition), empty for none
        df["segment"] = pd.to_numeric(df["segment"], errors="coerce").round().astype("Int64")
    for c in ("window_start_s", "window_end_s"):
        if sheet[c].notna().any():
            df[c] = sheet[c].to_numpy()
    return df


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
    sheet = read_run_sheet(protocol.campaign.run_sheet, protocol.water.temperature_C,
                           protocol.sheet, air=protocol.water.is_air)
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
    day_warnings = [*notices(protocol.warnings, "protocol"),
                    *notices(sheet.attrs.get("warnings", []), "sheet"),
                    *(unlisted_warnings(protocol, sheet) if unlisted is None else unlisted)]
    day_warnings += notices(sheet_note_sentences(sheet.attrs.get("notes", [])), "sheet")
    todo, rejected = runs_to_reduce(protocol, sheet)
    said: list[str] = []
    reductions, previews = reduce_runs(protocol, sheet, todo, rejected, jobs=jobs,
                                       progress=progress, debug=debug, cache_dir=cache_dir,
                                       warnings_out=said)
    day_warnings += notices(said, "reduce")
    said = []
    tares = tare_models(protocol, sheet, reductions, said)
    day_warnings += notices(said, "tare")
    apply_tares(protocol, sheet, reductions, tares, rejected)
    ordered = sorted(reductions.values(), key=lambda r: r.run)
    day_warnings += notices(unit_label_sentences([(r.run, r.file, r.units) for r in ordered]),
                            "reduce")
    day_warnings += [Notice(line, "reduce", run, file) for run, file, line in run_warning_lines(
        [(r.run, r.file, w) for r in ordered for w in r.warnings])]
    day_warnings += [Notice(line, "sheet", run) for run, line in temperature_problems(
        sheet, air=protocol.water.is_air)]
    runs = run_table(protocol, sheet, reductions, rejected)
    day = DayResult(
        protocol=protocol, sheet=sheet, reductions=reductions, rejected=rejected, tares=tares,
        runs=runs, warnings=day_warnings, inputs=day_inputs(protocol, sheet, reductions),
        previews=previews,
    )
    check_prototype_speeds(protocol)
    return analyse(day)


def _side_files(protocol: Protocol) -> list[SpeedLog | ZeroFile]:
    """The protocol's per-run side files: carriage log ([speed_log]), zeros file ([zeros])."""
    return [spec for spec in (protocol.speed_log, protocol.zeros) if spec is not None]


def unlisted_warnings(protocol: Protocol, sheet: pd.DataFrame) -> list[Notice]:
    """A warning per data file that no sheet row names (side files of the runs aside)."""
    logs = {log_path(spec, Path("."), str(f), int(r)).as_posix()
            for spec in _side_files(protocol)
            for r, f in zip(sheet["run"], sheet["file"], strict=True)}
    return [Notice(f"{f} is in the data folder but not in the run sheet; it is ignored.",
                   "sheet", file=f)
            for f in unlisted_files(sheet, protocol.campaign.data_dir) if f not in logs]


def runs_to_reduce(protocol: Protocol, sheet: pd.DataFrame) -> tuple[
        list[dict[str, Any]], dict[int, str]]:
    """The sheet rows to reduce, and the rejections the sheet alone decides (a row's own
    error, a file named by two rows); void rows are neither."""
    rejected: dict[int, str] = {}
    todo = []
    first_run_of: dict[Path, int] = {}
    for rec in sheet.to_dict("records"):
        if rec["status"] == "void":  # listed, never used: a void row's faults do not matter
            continue
        if rec["sheet_error"]:
            rejected[int(rec["run"])] = f"run {rec['run']}: {rec['sheet_error']}"
            continue
        path = resolved(protocol.campaign.data_dir / str(rec["file"]))
        if isinstance(path, str):  # a loop of symbolic links; a name too long
            rejected[int(rec["run"])] = (
                f"run {rec['run']}: {rec['file']} cannot be opened ({path}).")
            continue
        if path in first_run_of:  # one recording cannot be two runs: a copy-paste in the sheet
            rejected[int(rec["run"])] = (
                f"run {rec['run']}: {rec['file']} is also the file of run {first_run_of[path]} "
                "in the sheet; a recording is one run (a copied cell?)"
            )
            continue
        first_run_of[path] = int(rec["run"])
        todo.append(rec)
    return todo, rejected


def reduce_runs(
    protocol: Protocol,
    sheet: pd.DataFrame,
    todo: list[dict[str, Any]],
    rejected: dict[int, str],
    *,
    jobs: int | None,
    progress: Callable[[int, int], None] | None,
    debug: bool,
    cache_dir: str | Path | None,
    warnings_out: list[str] | None = None,
) -> tuple[dict[int, RunReduction], dict[int, dict[str, np.ndarray]]]:
    """Every run of ``todo`` reduced (from the cache, or in worker processes), in sheet order,
    and the previews of runs read but not reduced; rejections are added to ``rejected``, a
    cache that cannot be used to ``warnings_out``."""
    if warnings_out is None:
        warnings_out = []
    reductions: dict[int, RunReduction] = {}
    cache = RunCache(cache_dir, RunReduction, sane_reduction) if cache_dir is not None \
        else None
    if cache is not None and cache.problem:
        warnings_out.append(cache.problem)
    common = protocol_settings(protocol) if cache is not None else None
    sides = _side_files(protocol)
    keys: dict[int, str] = {}
    to_reduce = []
    for rec in todo:
        run = int(rec["run"])
        if cache is not None:
            side = "".join(log_sha(spec, protocol.campaign.data_dir, str(rec["file"]), run)
                           for spec in sides)
            keys[run] = settings_key(protocol, {**rec, "side_files_sha": side} if side else rec,
                                     common)
            path = protocol.campaign.data_dir / str(rec["file"])
            known = cache.known_file(path)
            hit = cache.get(known[0], keys[run]) if known is not None else None
            if hit is not None and known is not None and (
                    hit.sha256 != known[0] or hit.file != str(rec["file"])):
                hit = None  # an entry that is not this file's reduction: a miss
            if hit is not None and known is not None:  # its stamp: the file as it was read
                reductions[run] = replace(hit, run=run, file_stamp=known[1])
                continue
        to_reduce.append(rec)
    done = len(todo) - len(to_reduce)
    if progress is not None and done:
        progress(done, len(todo))
    previews: dict[int, dict[str, np.ndarray]] = {}
    for i, (run, red, reason, preview) in enumerate(
        parallel.map_runs(reduce_record, protocol, to_reduce, jobs=jobs, debug=debug,
                 on_crash=crashed_record, preload=ANALYSIS_MODULES)
    ):
        if red is not None:
            reductions[run] = red
            if cache is not None:
                cache.put(red.sha256, keys[run], red)
                cache.remember_sha(protocol.campaign.data_dir / red.file, red.sha256,
                                   getattr(red, "file_stamp", None))
        else:
            assert reason is not None
            rejected[run] = reason
            if preview is not None:
                previews[run] = preview
        if progress is not None:
            progress(done + i + 1, len(todo))
        if i == 0:
            pause_at("reduce")  # a test hook (towtank.runtime.pause); returns at once otherwise
    if cache is not None:
        cache.flush()
        if cache.problem and cache.problem not in warnings_out:
            warnings_out.append(cache.problem)
    # keep the sheet's order whatever the order of cache hits and fresh reductions
    order = {int(r): k for k, r in enumerate(sheet["run"])}
    return dict(sorted(reductions.items(), key=lambda kv: order[kv[0]])), previews


def apply_tares(
    protocol: Protocol,
    sheet: pd.DataFrame,
    reductions: dict[int, RunReduction],
    tares: dict[str, TareModel],
    rejected: dict[int, str],
) -> None:
    """Each model run's tare subtracted (in ``reductions``); a run whose tare group has no
    usable sting run is moved to ``rejected``."""
    config_of = dict(zip(sheet["run"].astype(int), sheet["config"], strict=True))
    group_of = dict(zip(sheet["run"].astype(int), sheet["tare_group"], strict=True))
    for run in list(reductions):
        if config_of[run] == "sting" or protocol.tare.source == "none":
            reductions[run] = apply_tare(reductions[run], None)
            continue
        tare = tares.get(group_of[run])
        if tare is None:
            rejected[run] = (
                f"run {run}: {reductions[run].file}: its tare group '{group_of[run]}' has no "
                "usable sting (tare) run, so the mounting's force cannot be removed"
            )
            del reductions[run]
            continue
        reductions[run] = apply_tare(reductions[run], tare)


def day_inputs(protocol: Protocol, sheet: pd.DataFrame,
               reductions: dict[int, RunReduction]) -> dict[str, str]:
    """sha256 of every input of the day: protocol, sheet, a reference CSV, every file the
    sheet names (rejected runs' too) and the runs' side files."""
    inputs = {str(protocol.path): _sha(protocol.path),
              str(protocol.campaign.run_sheet): _sha(protocol.campaign.run_sheet)}
    if protocol.campaign.reference not in BUILTIN_REFERENCES:  # a user CSV is an input too
        inputs[str(protocol.campaign.reference)] = _sha(Path(protocol.campaign.reference))
    shas = {red.file: red.sha256 for red in reductions.values()}
    for file in sheet["file"]:
        path = protocol.campaign.data_dir / str(file)
        if str(file) in shas:
            inputs[str(path)] = shas[str(file)]
        elif str(file) and is_regular_file(path):
            inputs[str(path)] = _sha(path)
    for spec in _side_files(protocol):  # the carriage logs and zeros files are inputs too
        for run, file in zip(sheet["run"], sheet["file"], strict=True):
            log = log_path(spec, protocol.campaign.data_dir, str(file), int(run))
            if is_regular_file(log):
                inputs[str(log)] = _sha(log)
    return inputs


def _sha(path: Path) -> str:
    """sha256 of a file, or "" when it cannot be read (its run is rejected anyway)."""
    try:
        return sha256_bytes(path.read_bytes())
    except OSError:
        return ""


def analyse(day: DayResult) -> DayResult:
    """The fitting stages on the reduced runs, in order: hull coefficients, fins, scaling,
    vehicle. Each stage returns its result and its warnings; a stage's TowtankError becomes a
    warning of the day. Returns the day with the results (the given day is not changed)."""
    pause_at("fits")  # a test hook (towtank.runtime.pause); returns at once otherwise
    warns = list(day.warnings)
    p, runs = day.protocol, day.runs
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
    try:
        vehicle = vehicle_stage(p, hull, prototype)
        warns += notices(vehicle.warnings, "vehicle") if vehicle is not None else []
    except TowtankError as exc:
        failed(exc, "vehicle")
    return replace(day, warnings=warns, hull=hull, fin_result=fin, scaling_result=scaling,
                   vehicle=vehicle, prototype_values=prototype)


def hull_stage(protocol: Protocol, runs: pd.DataFrame, reductions: dict[int, RunReduction],
               tares: dict[str, TareModel]) -> tuple[HullResult | None, list[str]]:
    """The hull coefficients (:func:`towtank.analysis.hull.fit_hull`) and their warnings; None
    without a [model] or usable hull runs."""
    model = protocol.model
    if model is None or not ((runs["config"] == "hull") & (runs["status"] == "ok")).any():
        return None, []
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
                  prototype_values: pd.DataFrame | None = None) -> VehicleResult | None:
    """Prediction and model of the protocol's [vehicle]; predicted beside measured."""
    if getattr(protocol, "vehicle", None) is None:
        return None
    measured = None
    if hull is not None:
        measured = hull.coefficients
        if prototype_values is not None:  # coefficients.csv as the scaling stage leaves it
            measured = measured.copy()
            measured["prototype_value"] = prototype_values["prototype_value"].to_numpy()
    prediction, table, warns = day_vehicle(protocol, measured)
    return VehicleResult(prediction=prediction, coefficients=table, warnings=tuple(warns))


def fin_stage(protocol: Protocol, runs: pd.DataFrame) -> tuple[FinResult | None, list[str]]:
    """The fins against the Sandia section data
    (:func:`towtank.analysis.fin_analysis.analyse_fins`); (None, []) without a [fin]."""
    if protocol.fin is None:
        return None, []
    return analyse_fins(runs, protocol.fin)


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
    return result, values, warns
