"""The reduced time series of every usable run, for the lab's own tools (``--export``).

Each run is read again and conditioned exactly as the day's reduction did it
(:func:`towtank.reduce.run.reduce_record` with ``keep_series``), and its tare is subtracted
sample by sample (:func:`towtank.reduce.run.apply_tare`): the exported channels are the ones
the coefficients were fitted on, at the file's own sample rate.

========  ==================================================================================
format    files in the output folder's ``export/``
========  ==================================================================================
mat       ``run_NNN.mat`` (MATLAB v5, ``load('run_001.mat')``): vectors ``t, U, a, drag, lift,
          phase``, the cell array ``phase_names`` and the struct ``meta``
hdf5      ``runs.h5``: a group ``run_NNN`` per run with those datasets and ``meta`` as attributes
parquet   ``run_NNN.parquet``: columns ``t, U, a, drag, lift, phase, phase_name``; ``meta``
          as JSON in the schema's metadata (key ``towtank``)
========  ==================================================================================

Units: t [s] from the start of the file, U [m/s], a [m/s²], drag and lift [N] (zeroed,
drift-corrected, low-pass filtered, tare subtracted; SNAME signs as in runs.csv). ``phase`` is
0 still before, 1 acceleration, 2 steady (the window used), 3 deceleration, 4 still after,
−1 between phases.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from towtank.signal.phases import PHASE_NAMES

if TYPE_CHECKING:
    from towtank.pipeline import DayResult
    from towtank.reduce.run import RunReduction

EXPORT_FORMATS = ("mat", "hdf5", "parquet")

#: Units of the exported channels.
UNITS = {"t": "s", "U": "m/s", "a": "m/s^2", "drag": "N", "lift": "N", "phase": "-"}

#: runs.csv columns copied into each run's ``meta``.
META_COLUMNS = ("run", "file", "config", "test", "angle_deg", "status", "speed_mean",
                "accel_mean", "drag_mean", "lift_mean", "tare_drag", "cd", "cl", "re",
                "water_temp_C", "rho", "nu", "tare_group", "fs_hz", "n_samples", "sha256")


def conditioned_runs(day: DayResult) -> tuple[dict[int, RunReduction], list[str]]:
    """Every usable run of the day reduced again with its whole conditioned time series
    (``RunReduction.series``), tare subtracted; and a sentence for each run that could not be
    (its file changed or vanished since the day was reduced)."""
    from towtank.reduce.run import apply_tare, reduce_record

    protocol = day.protocol
    rows = {int(r["run"]): r for r in day.sheet.to_dict("records")}
    out: dict[int, RunReduction] = {}
    missing: list[str] = []
    for run in sorted(day.reductions):
        _, red, reason, _ = reduce_record(protocol, rows[run], keep_series=True)
        if red is None:
            missing.append(f"run {run} is not exported: {reason}")
            continue
        config = str(rows[run]["config"])
        tare = (None if config == "sting" or protocol.tare.source == "none"
                else day.tares.get(str(rows[run]["tare_group"])))
        out[run] = apply_tare(red, tare)
    return out, missing


def _meta(day: DayResult, run: int) -> dict[str, Any]:
    runs = day.runs.set_index("run", drop=False)
    meta: dict[str, Any] = {"campaign": day.protocol.name}
    for col in META_COLUMNS:
        if col in runs.columns:
            v = runs.loc[run, col]
            if isinstance(v, np.generic):
                v = v.item()
            if isinstance(v, float) and not math.isfinite(v):
                v = float("nan")
            meta[col] = "" if v is None else v
    meta["units"] = ", ".join(f"{k} [{u}]" for k, u in UNITS.items())
    return meta


def _write_mat(path: Path, series: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    from scipy.io import savemat

    data: dict[str, Any] = {k: np.asarray(v, dtype=float)[:, None] for k, v in series.items()
                            if k != "phase"}
    data["phase"] = np.asarray(series["phase"], dtype=np.int8)[:, None]
    data["phase_names"] = np.array(PHASE_NAMES, dtype=object)
    data["meta"] = {k: (v if not isinstance(v, bool) else int(v)) for k, v in meta.items()}
    savemat(path, data, do_compression=True, oned_as="column")


def _write_parquet(path: Path, series: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
    import pyarrow as pa
    import pyarrow.parquet as pq

    names = np.array([*PHASE_NAMES, ""], dtype=object)
    columns = {k: pa.array(np.asarray(v)) for k, v in series.items()}
    columns["phase_name"] = pa.array(names[np.asarray(series["phase"], dtype=int)]) \
        .dictionary_encode()
    table = pa.table(columns)
    table = table.replace_schema_metadata(
        {"towtank": json.dumps({"meta": meta, "units": UNITS, "phase_names": PHASE_NAMES},
                               default=str)})
    pq.write_table(table, path)


def export_runs(day: DayResult, folder: str | Path, formats: tuple[str, ...] | list[str]
                ) -> list[str]:
    """Write the reduced time series of the day's usable runs into ``folder/export/``.

    Parameters
    ----------
    day : DayResult
        The processed day.
    folder : path
        The output folder (the writers' temporary folder).
    formats : sequence of str
        Any of :data:`EXPORT_FORMATS`.

    Returns
    -------
    list of str
        A sentence per run that could not be exported (else empty).
    """
    formats = tuple(dict.fromkeys(formats))
    unknown = [f for f in formats if f not in EXPORT_FORMATS]
    if unknown:
        raise ValueError(f"unknown export format(s) {', '.join(unknown)}; use "
                         f"{', '.join(EXPORT_FORMATS)}")
    if not formats:
        return []
    runs, missing = conditioned_runs(day)
    out = Path(folder) / "export"
    out.mkdir(parents=True, exist_ok=True)
    h5 = None
    if "hdf5" in formats:
        import h5py

        h5 = h5py.File(out / "runs.h5", "w")
        h5.attrs["campaign"] = day.protocol.name
        h5.attrs["phase_names"] = ", ".join(PHASE_NAMES)
        h5.attrs["units"] = json.dumps(UNITS)
    try:
        for run, red in runs.items():
            assert red.series is not None
            meta = _meta(day, run)
            name = f"run_{run:03d}"
            if "mat" in formats:
                _write_mat(out / f"{name}.mat", red.series, meta)
            if "parquet" in formats:
                _write_parquet(out / f"{name}.parquet", red.series, meta)
            if h5 is not None:
                g = h5.create_group(name)
                for k, v in red.series.items():
                    g.create_dataset(k, data=np.asarray(v), compression="gzip")
                    g[k].attrs["unit"] = UNITS[k]
                for k, v in meta.items():
                    g.attrs[k] = v if not isinstance(v, bool) else int(v)
    finally:
        if h5 is not None:
            h5.close()
    return missing
