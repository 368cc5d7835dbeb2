"""The day's pipeline: protocol → run sheet → runs → reductions → tare → fits → outputs.

Each stage is a module of its own and data flows one way; this module only wires them. Any
failure confined to one run rejects that run with one sentence and the rest of the day goes on;
a protocol or run-sheet fault stops before anything is written.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from towtank.ingest.protocol import Protocol, load_protocol, model_geometry
from towtank.ingest.runsheet import read_run_sheet, unlisted_files
from towtank.ingest.speedlog import log_path, log_sha
from towtank.reduce.run import (
    RunReduction,
    apply_tare,
    crashed_record,
    force_coefficient,
    reduce_record,
)
from towtank.reduce.tare import TareModel, fit_tare_group
from towtank.reference.sets import BUILTIN_REFERENCES
from towtank.runtime.cache import RunCache, protocol_settings, settings_key
from towtank.runtime.pause import pause_at

G = 9.80665

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


@dataclass
class DayResult:
    """Everything computed for a day; the report stage only formats it."""

    protocol: Protocol
    sheet: pd.DataFrame
    reductions: dict[int, RunReduction]
    rejected: dict[int, str]
    tares: dict[str, TareModel]
    runs: pd.DataFrame
    warnings: list[str] = field(default_factory=list)
    hull: Any = None  # HullResult: .fit (towtank.analysis.hull.HullFit), .coefficients
    fin_result: Any = None  # FinResult: table, curves, control, aspect ratio
    scaling_result: Any = None  # ScalingResult: table, scale, prototype water, form factor
    inputs: dict[str, str] = field(default_factory=dict)  # path -> sha256
    report_date: str | None = None
    # rejected runs that were read: calibrated speed and forces at 10 Hz, for the report
    previews: dict[int, dict[str, np.ndarray]] = field(default_factory=dict)
    vehicle: Any = None  # towtank.vehicle.stage.VehiclePrediction of a [vehicle] section

    @property
    def n_rejected(self) -> int:
        """Number of rejected runs."""
        return len(self.rejected)

    @property
    def coefficients(self) -> pd.DataFrame:
        """coefficients.csv of the day: one row per hull coefficient (empty without hull runs)."""
        if self.hull is not None:
            return self.hull.coefficients
        from towtank.analysis.hull import COEFFICIENT_COLUMNS, COEFFICIENT_EXTRA_COLUMNS

        return pd.DataFrame(columns=COEFFICIENT_COLUMNS + COEFFICIENT_EXTRA_COLUMNS)

    @property
    def fins(self) -> pd.DataFrame:
        """fins.csv of the day: one row per fin run (empty without fin runs)."""
        if self.fin_result is not None:
            return self.fin_result.table
        from towtank.analysis.fins import FIN_TABLE_COLUMNS

        return pd.DataFrame(columns=list(FIN_TABLE_COLUMNS))

    @property
    def scaling(self) -> pd.DataFrame:
        """scaling.csv of the day: one row per prototype speed (empty when not scaled)."""
        if self.scaling_result is not None:
            return self.scaling_result.table
        from towtank.analysis.similarity import SCALING_COLUMNS, SCALING_RECOMMENDED_COLUMNS

        return pd.DataFrame(columns=list(SCALING_COLUMNS + SCALING_RECOMMENDED_COLUMNS))


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
        from towtank.reduce.tare import table_tare

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


def water_at(temperature_C: float, water_type: str, salinity: float | None,
             pressure_Pa: float | None = None,
             relative_humidity_pct: float | None = None) -> tuple[float, float]:
    """(rho [kg/m³], nu [m²/s]) of the tank's or the prototype's medium.

    Water (``fresh``, ``sea``): ITTC 7.5-02-01-03 (:mod:`towtank.reference.water`). Air:
    CIPM-2007 density at ``pressure_Pa`` [Pa] (default 101325) and ``relative_humidity_pct``
    [%] (default 50), Sutherland viscosity (:mod:`towtank.reference.air`).

    Out-of-range warnings (WaterPropertyWarning) are silenced here: the protocol's unit checks
    already put a temperature or salinity outside the ITTC range of [water] and
    [prototype.water] into the day's warnings, and each run's temperature is checked in
    :func:`process_day`.
    """
    if water_type == "air":
        from towtank.reference.air import (
            DEFAULT_RELATIVE_HUMIDITY_PCT,
            STANDARD_PRESSURE_PA,
            air_properties,
        )

        a = air_properties(
            temperature_C,
            STANDARD_PRESSURE_PA if pressure_Pa is None else pressure_Pa,
            DEFAULT_RELATIVE_HUMIDITY_PCT if relative_humidity_pct is None
            else relative_humidity_pct)
        return float(a.rho), float(a.nu)
    from towtank.reference.water import water_properties

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        w = water_properties(temperature_C, water_type, salinity)
    return float(w.rho), float(w.nu)


def medium_at(water: Any, temperature_C: float | None = None) -> tuple[float, float]:
    """(rho [kg/m³], nu [m²/s]) of a protocol's [water] or [prototype.water] medium.

    ``water`` is a :class:`towtank.ingest.protocol.Water`; ``temperature_C`` [°C] a run's
    temperature, default the section's own (see :func:`water_at`).
    """
    t = water.temperature_C if temperature_C is None else temperature_C
    return water_at(t, water.type, water.salinity_g_kg, water.pressure_Pa,
                    water.relative_humidity_pct)


def model_scale(protocol: Protocol) -> float | None:
    """λ = L_p / L_m: [model] scale, else [prototype] length_m / [model] length_m, else None."""
    model, proto = protocol.model, protocol.prototype
    if model is None:
        return None
    if model.scale is not None:
        return model.scale
    return proto.length_m / model.length_m if proto is not None else None


def geometry_used(day: DayResult) -> list[dict[str, Any]]:
    """The day's hull geometry with where each quantity came from; empty without a [model].

    See :func:`towtank.ingest.protocol.model_geometry`; the prototype's wetted area λ²·S_m is listed
    when the scale ratio is known.
    """
    model = day.protocol.model
    if model is None:
        return []
    sr = day.scaling_result
    scale = sr.scale if sr is not None else model_scale(day.protocol)
    return model_geometry(model, scale)


def check_prototype_speeds(protocol: Protocol) -> None:
    """Raise ProtocolError unless every [prototype] speed is finite, > 0 and gives Re_p >= 1e3.

    Needs the prototype water's viscosity, so it runs once the analysis libraries are loaded
    (after the reductions), not in :func:`towtank.ingest.protocol.load_protocol`.
    """
    from towtank.analysis import similarity
    from towtank.errors import ProtocolError

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


#: A hull run within this of α = 90° is a transverse tow [deg] (the hull fit's angle tolerance):
#: its drag coefficient is on the lateral area, as C_D,90 of Y_v|v|.
TRANSVERSE_TOL_DEG = 0.5

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
    """runs.csv: one row per run of the sheet (docs/formats.md §5), then extension columns."""
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
            ref_len = None
            if rec["config"] == "hull" and model is not None:
                area, ref_len = model.frontal_area, model.length_m
                row["cd"] = force_coefficient(red.drag_mean, rho, area, u)
                row["cl"] = force_coefficient(red.lift_mean, rho, area, u)
                row["cd_lateral"] = force_coefficient(red.drag_mean, rho, model.lateral_area, u)
                if abs(float(rec["angle_deg"]) - 90.0) <= TRANSVERSE_TOL_DEG:  # a transverse tow
                    row.update(cd_ref=row["cd_lateral"], ref_area="lateral",
                               ref_area_m2=model.lateral_area)
                else:
                    row.update(cd_ref=row["cd"], ref_area="frontal", ref_area_m2=area)
            elif rec["config"] == "fin" and fin is not None:
                area, ref_len = fin.area, fin.chord_m
                row["cd"] = force_coefficient(red.drag_mean, rho, area, u)
                row["cl"] = force_coefficient(red.lift_mean, rho, area, u)
                row.update(cd_ref=row["cd"], ref_area="fin", ref_area_m2=area)
            elif model is not None:
                ref_len = model.length_m
            elif fin is not None:
                ref_len = fin.chord_m
            if ref_len:
                row["re"] = u * ref_len / nu
                row["fn"] = u / math.sqrt(G * ref_len)
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
    if jobs is None:
        jobs = protocol.processing.jobs  # None too: every core
    sheet = read_run_sheet(protocol.campaign.run_sheet, protocol.water.temperature_C,
                           protocol.sheet, air=protocol.water.is_air)
    day_warnings = list(protocol.warnings) + list(sheet.attrs.get("warnings", [])) + \
        unlisted_warnings(protocol, sheet)
    notes = sheet.attrs.get("notes", [])
    if notes:
        shown = "; ".join(repr(n if len(n) <= 80 else n[:77] + "...") for n in notes[:3])
        shown += "; ..." if len(notes) > 3 else ""
        day_warnings.append(f"the run sheet's {len(notes)} line(s) of text among or below the "
                            f"table are read as notes, not runs: {shown}.")
    todo, rejected = runs_to_reduce(protocol, sheet)
    reductions, previews = reduce_runs(protocol, sheet, todo, rejected, jobs=jobs,
                                       progress=progress, debug=debug, cache_dir=cache_dir,
                                       warnings_out=day_warnings)
    tares = tare_models(protocol, sheet, reductions, day_warnings)
    apply_tares(protocol, sheet, reductions, tares, rejected)
    from towtank.analysis.daywide import group_run_warnings, unit_label_sentences

    ordered = sorted(reductions.values(), key=lambda r: r.run)
    day_warnings.extend(unit_label_sentences([(r.run, r.file, r.units) for r in ordered]))
    day_warnings.extend(group_run_warnings([(r.run, r.file, w) for r in ordered
                                            for w in r.warnings]))
    for rec in sheet.to_dict("records"):
        temp = rec["water_temp_C"]
        if rec["status"] != "void" and not 0.0 <= temp <= 40.0:
            day_warnings.append(
                f"run {rec['run']}: air temperature {temp:g} °C is outside 0–40 °C, the usual "
                "range of a test rig in air (a unit mistake?)." if protocol.water.is_air else
                f"run {rec['run']}: water temperature {temp:g} °C is outside 0–40 °C, where the "
                "ITTC water properties are extrapolated (a unit mistake?)."
            )
    runs = run_table(protocol, sheet, reductions, rejected)
    day = DayResult(
        protocol=protocol, sheet=sheet, reductions=reductions, rejected=rejected, tares=tares,
        runs=runs, warnings=day_warnings, inputs=day_inputs(protocol, sheet, reductions),
        previews=previews,
    )
    check_prototype_speeds(protocol)
    _analyse(day)
    return day


def _side_files(protocol: Protocol) -> list[Any]:
    """The protocol's per-run side files: carriage log ([speed_log]), zeros file ([zeros])."""
    return [spec for spec in (protocol.speed_log, protocol.zeros) if spec is not None]


def unlisted_warnings(protocol: Protocol, sheet: pd.DataFrame) -> list[str]:
    """A warning per data file that no sheet row names (side files of the runs aside)."""
    logs = {log_path(spec, Path("."), str(f), int(r)).as_posix()
            for spec in _side_files(protocol)
            for r, f in zip(sheet["run"], sheet["file"], strict=True)}
    return [f"{f} is in the data folder but not in the run sheet; it is ignored."
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
        try:
            path = (protocol.campaign.data_dir / str(rec["file"])).resolve()
        except (OSError, RuntimeError) as exc:  # a symlink loop; a name too long
            reason = "a symlink loop" if isinstance(exc, RuntimeError) else exc.strerror or exc
            rejected[int(rec["run"])] = (
                f"run {rec['run']}: {rec['file']} cannot be opened ({reason}).")
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
    from towtank.runtime.parallel import map_runs

    if warnings_out is None:
        warnings_out = []
    reductions: dict[int, RunReduction] = {}
    cache = RunCache(cache_dir, RunReduction, _sound_reduction) if cache_dir is not None \
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
            # a hit is this file's reduction (else a miss); its stamp: the file as the cached
            # reduction read it
            if (known is not None and hit is not None and hit.sha256 == known[0]
                    and hit.file == str(rec["file"])):
                reductions[run] = replace(hit, run=run, file_stamp=known[1])
                continue
        to_reduce.append(rec)
    done = len(todo) - len(to_reduce)
    if progress is not None and done:
        progress(done, len(todo))
    previews: dict[int, dict[str, np.ndarray]] = {}
    for i, (run, red, reason, preview) in enumerate(
        map_runs(reduce_record, protocol, to_reduce, jobs=jobs, debug=debug,
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


def _sound_reduction(red: RunReduction) -> bool:
    """Whether a reduction read back from the cache is whole: its sample tables' columns of
    one length, finite sample rate and sample count, known phase windows."""
    from towtank.runtime.records import same_lengths

    tables = [red.samples, red.thumb] + ([red.series] if red.series is not None else [])
    return (all(same_lengths(t) for t in tables) and math.isfinite(red.fs) and red.fs > 0
            and red.n_samples >= 0
            and all(w is None or (len(w) == 2 and w[0] <= w[1]) for w in red.windows.values()))


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
        elif str(file) and path.is_file():
            inputs[str(path)] = _sha(path)
    for spec in _side_files(protocol):  # the carriage logs and zeros files are inputs too
        for run, file in zip(sheet["run"], sheet["file"], strict=True):
            log = log_path(spec, protocol.campaign.data_dir, str(file), int(run))
            if log.is_file():
                inputs[str(log)] = _sha(log)
    return inputs


def _sha(path: Path) -> str:
    """sha256 of a file, or "" when it cannot be read (its run is rejected anyway)."""
    from towtank.ingest.runfile import sha256_bytes

    try:
        return sha256_bytes(path.read_bytes())
    except OSError:
        return ""


def _analyse(day: DayResult) -> None:
    """The fitting stages: hull coefficients, fins, similarity (each on the reduced runs)."""
    from towtank.errors import TowtankError

    pause_at("fits")  # a test hook (towtank.runtime.pause); returns at once otherwise
    for stage in (_hull_stage, _fin_stage, _scaling_stage, _vehicle_stage):
        try:
            stage(day)
        except TowtankError as exc:
            day.warnings.append(str(exc))


@dataclass
class HullResult:
    fit: Any  # towtank.analysis.hull.HullFit
    coefficients: pd.DataFrame


@dataclass
class FinResult:
    table: pd.DataFrame  # fins.csv
    curves: pd.DataFrame
    force_vs_speed: pd.DataFrame
    aspect_ratio: float
    oswald_e: float
    control: pd.DataFrame | None
    warnings: list[str]


@dataclass
class ScalingResult:
    table: pd.DataFrame  # scaling.csv
    resistance: tuple[float, float]  # k2 [N s²/m²], k1 [N s/m] of R = k2·U|U| + k1·U
    tested_speed_range: tuple[float, float]
    form_factor: Any  # towtank.analysis.similarity.FormFactor or None
    statement: str
    rho_p: float
    nu_p: float
    rho_m: float
    nu_m: float
    scale: float
    length_prototype: float = math.nan  # [m]
    wetted_area_prototype: float | None = None  # λ²·S_m [m²], None when S_m is not known
    delta_cf: float = 0.0
    #: towtank.analysis.similarity.ResistanceRecommendation: which column is R_p, and why
    recommendation: Any = None
    #: towtank.analysis.similarity.FormFactorTrend of 1 + k against Re (None without 1 + k)
    form_factor_trend: Any = None
    form_factor_trend_text: str = ""


def _hull_stage(day: DayResult) -> None:
    from towtank.analysis import hull as fit

    model = day.protocol.model
    runs = day.runs
    if model is None or not ((runs["config"] == "hull") & (runs["status"] == "ok")).any():
        return
    hf = fit.fit_hull(
        runs,
        day.reductions,
        mass=model.mass_kg,
        mass_sd=model.mass_uncertainty_kg,
        length=model.length_m,
        frontal_area=model.frontal_area,
        lateral_area=model.lateral_area,
        alpha_max_deg=day.protocol.processing.damping_alpha_max_deg,
        tares=day.tares,
        rho=medium_at(day.protocol.water)[0],
    )
    ref = fit.load_reference(day.protocol.campaign.reference)
    table = fit.coefficients_table(hf, ref, model.length_uncertainty_m)
    day.hull = HullResult(fit=hf, coefficients=table)
    day.warnings.extend(hf.messages)
    from towtank.analysis.plausibility import displaced_volume, plausibility_warnings

    day.warnings.extend(plausibility_warnings(
        table, rho=hf.rho,
        volume_m3=displaced_volume(model.length_m, model.diameter_m, model.volume_m3),
        frontal_area_m2=model.frontal_area, lateral_area_m2=model.lateral_area,
        added_mass=not day.protocol.water.is_air,
    ))
    for sym, am in hf.added_mass.items():
        if am.estimate.agreement.startswith("DISAGREE"):
            day.warnings.append(
                f"{sym}: the curve-difference estimate {am.estimate.alt_value:.4g} kg and the "
                f"joint regression {am.estimate.value:.4g} kg disagree "
                f"({am.estimate.agreement[10:]})."
            )
    if hf.damping is not None and hf.damping.outliers:
        dm = hf.damping
        t = dm.runs.set_index("run")
        flagged = ", ".join(
            f"{r} (studentized residual {t.loc[r, 'student']:+.3g}, Cook's distance "
            f"{t.loc[r, 'cooks']:.2g})" for r in dm.outliers)
        one = len(dm.outliers) == 1
        day.warnings.append(
            f"C_D(α) fit: {'run' if one else 'runs'} {flagged} "
            f"{'is' if one else 'are'} flagged as {'an outlier' if one else 'outliers'} "
            f"(|studentized residual| > 3 or Cook's distance > {max(4.0 / len(t), 0.5):.2g}); "
            f"{'it is' if one else 'they are'} still in the fit: check "
            f"{'it' if one else 'them'} before trusting X_u|u|, X_uv, X_v|v| and Y_uv."
        )


def _vehicle_stage(day: DayResult) -> None:
    """Prediction and model of the protocol's [vehicle]; predicted beside measured."""
    if getattr(day.protocol, "vehicle", None) is None:
        return
    from towtank.vehicle.compare import day_vehicle

    day.vehicle, table, warnings = day_vehicle(
        day.protocol, day.hull.coefficients if day.hull is not None else None)
    if table is not None:
        day.hull.coefficients = table
    day.warnings.extend(warnings)


def _fin_stage(day: DayResult) -> None:
    fin = day.protocol.fin
    runs = day.runs
    sel = runs[(runs["config"] == "fin") & (runs["status"] == "ok")]
    if fin is None or sel.empty:
        return
    from towtank.analysis import fins
    from towtank.reference import sandia

    warn: list[str] = []
    beyond = sel["angle_deg"].abs() > 180.0  # the section data stop there (ValueError)
    for run, angle in zip(sel.loc[beyond, "run"], sel.loc[beyond, "angle_deg"], strict=True):
        warn.append(f"run {run}: fin angle {angle:g}° is outside −180…180°, the range of the "
                    "Sandia section data; the run is left out of the fin analysis.")
    sel = sel[~beyond]
    if sel.empty:
        day.warnings.extend(warn)
        return
    ar = float(fins.effective_aspect_ratio(fin.span_m, fin.chord_m, fin.mounting))
    linear_max = fin.linear_max_deg
    # Sandia's Re clamp (Re outside 1e4-1e7) goes to the day's warnings, so that the report
    # and provenance carry it; any other warning goes on as a Python warning
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table = fins.fin_table(sel, ar, fin.oswald_e)
        curves = fins.fin_curves(table, linear_max, aspect_ratio=ar, e=fin.oswald_e)
    for w in caught:
        if issubclass(w.category, sandia.SandiaRangeWarning):
            text = f"fin: {w.message}"
            if text not in warn:
                warn.append(text)
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    warn += fins.low_reynolds_warnings(table)
    warn += fins.lift_slope_warnings(curves, linear_max)
    warn += fins.two_dimensional_warning(curves, ar)
    control = None
    if fin.x_m is not None and len(curves):
        slope, source = fins.control_lift_slope(curves, linear_max)
        if np.isfinite(slope):
            rho = float(sel["rho"].mean())
            control = fins.control_derivatives(slope, fin.area, fin.x_m, rho, source)
        else:
            warn.append(f"fin control derivatives: {source}; fin_control.csv is not written.")
    day.fin_result = FinResult(
        table=table, curves=curves, force_vs_speed=fins.force_vs_speed(table),
        aspect_ratio=ar, oswald_e=fin.oswald_e, control=control, warnings=warn,
    )
    day.warnings.extend(warn)


def _scaling_stage(day: DayResult) -> None:
    from statsmodels.regression.linear_model import OLS

    from towtank.analysis import similarity

    p = day.protocol
    model, proto = p.model, p.prototype
    if model is None or proto is None:
        return
    scale = model_scale(p)
    assert scale is not None
    rho_p, nu_p = medium_at(proto.water)
    rho_m, nu_m = medium_at(p.water)
    if day.hull is not None:
        coef = day.hull.coefficients
        kinds = coef["symbol"].map(lambda s: "added_mass" if s.endswith("dot") else "damping")
        coef["prototype_value"] = [
            float(similarity.prototype_value(pr, rho_p, proto.length_m, k))
            for pr, k in zip(coef["prime"], kinds, strict=True)
        ]
    runs = day.runs
    zero = runs[(runs["config"] == "hull") & (runs["status"] == "ok")
                & (np.abs(runs["angle_deg"]) <= 0.5)]
    if len(zero) < 2:
        day.warnings.append(
            "scaling.csv needs two or more steady hull runs at α = 0 for the resistance curve."
        )
        return
    u = zero["speed_mean"].to_numpy(float)
    r = zero["drag_mean"].to_numpy(float)
    res = OLS(r, np.column_stack([u * np.abs(u), u])).fit()
    k2, k1 = (float(v) for v in res.params)
    ff = None
    one_plus_k = math.nan
    if model.wetted_area_m2 is not None:
        try:
            ff = similarity.form_factor(
                r, u, model.wetted_area_m2, float(zero["rho"].mean()),
                float(zero["nu"].mean()), model.length_m, re_min=p.processing.laminar_re,
            )
            one_plus_k = float(ff.one_plus_k)
        except ValueError as exc:
            day.warnings.append(f"form factor: {exc}")
    else:
        day.warnings.append(
            "drag_ittc57 needs the model's wetted area ([model] wetted_area_m2 or a Myring "
            "description); it is left empty and no form factor is found."
        )
    table = similarity.scaling_table(
        np.asarray(proto.speeds_m_s),
        scale=scale,
        length_model=model.length_m,
        length_prototype=proto.length_m,
        rho_m=rho_m, nu_m=nu_m, rho_p=rho_p, nu_p=nu_p,
        resistance_model=lambda um: k2 * um * abs(um) + k1 * um,
        tested_speed_range=(float(u.min()), float(u.max())),
        wetted_area_model=model.wetted_area_m2,
        one_plus_k=one_plus_k,
        delta_cf=proto.delta_cf,
    )
    hull_runs = runs[(runs["config"] == "hull") & (runs["status"] == "ok")
                     & (np.abs(runs["angle_deg"]) <= p.processing.damping_alpha_max_deg)]
    # a run towed backwards (negative speed) has no Reynolds range of its own to compare
    re_ok = hull_runs["re"][np.isfinite(hull_runs["re"]) & (hull_runs["re"] > 0)]
    if len(re_ok) == 0:  # only backward tows: their size is the Reynolds number
        re_ok = np.abs(zero["re"])[np.isfinite(zero["re"]) & (zero["re"] != 0)]
    re_model = (float(re_ok.min()), float(re_ok.max()))
    re_proto = (float(table["re_prototype"].min()), float(table["re_prototype"].max()))
    air = p.water.is_air  # no free surface: no waves, no depth, no Froude similarity
    depth = model.depth_m if model.diameter_m is not None and not air else None
    statement = similarity.similarity_statement(
        re_model, re_proto, depth, model.diameter_m if depth is not None else None,
        turbulent_re=p.processing.laminar_re, free_surface=not air,
    )
    deep_ratio = depth / model.diameter_m if depth is not None and model.diameter_m else None
    recommendation = similarity.recommend_resistance(
        deep_ratio, bool(np.isfinite(table["drag_ittc57"]).any()), free_surface=not air)
    table["drag_recommended"] = (table[recommendation.column] if recommendation.column in table
                                 else math.nan)
    table["recommended"] = recommendation.column
    trend, trend_text = None, ""
    if ff is not None:
        trend = similarity.form_factor_trend(ff.speed_reynolds, ff.speed_values)
        trend_text = similarity.form_factor_trend_statement(trend, ff.one_plus_k)
    day.scaling_result = ScalingResult(
        recommendation=recommendation, form_factor_trend=trend,
        form_factor_trend_text=trend_text,
        table=table, resistance=(k2, k1), tested_speed_range=(float(u.min()), float(u.max())),
        form_factor=ff, statement=statement, rho_p=rho_p, nu_p=nu_p, rho_m=rho_m, nu_m=nu_m,
        scale=scale, length_prototype=proto.length_m,
        wetted_area_prototype=(model.wetted_area_m2 * scale**2
                               if model.wetted_area_m2 is not None else None),
        delta_cf=proto.delta_cf,
    )
    outside = table.loc[~table["froude_in_tested_range"], "speed_prototype"].tolist()
    deep = air or (depth is not None and model.diameter_m is not None
                   and depth / model.diameter_m > similarity.DEEP_SUBMERGENCE_DEPTH_RATIO)
    if outside and not deep:  # deeply submerged, Froude scaling is not what counts
        day.warnings.append(
            "Froude-scaled drag is extrapolated beyond the tested model speeds for prototype "
            "speeds " + ", ".join(f"{v:g}" for v in outside) + " m/s" + (
                " (the model ran near the surface, where Froude similarity is needed)."
                if depth is not None else
                " (give [model] depth_m: deeply submerged, Froude similarity is not needed).")
        )
    laminar = table.loc[table["re_prototype"] < p.processing.laminar_re, "speed_prototype"]
    if len(laminar):
        day.warnings.append(
            "prototype speeds " + ", ".join(f"{v:g}" for v in laminar) + " m/s give Re below "
            f"{p.processing.laminar_re:g} ([processing] laminar_re), where the flow need not be "
            "turbulent: the ITTC-57 drag there is indicative only."
        )
