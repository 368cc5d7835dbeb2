"""False-alarm study of identify's model-adequacy tests (docs/method.md, "Model adequacy").

Records the model made (REMUS, neutrally buoyant, a sine rudder of 10 deg and 10 s at
1.5 m/s, white noise on the paper's measured states ``u, v, r, psi, x, y``) are identified
with that model; each record's fit.csv rows are kept, with the arrays the tests were computed
from (:attr:`towtank.vehicle.identify.IdentifyFit.residuals`), so that thresholds can be
derived from them. :func:`false_alarms` gives the rate of records that failed any test with
its Clopper–Pearson 95 % interval.

Run from the command line (one process; hours at most)::

    nice python -m towtank.testing.adequacy_study --records 100 --out study
"""

from __future__ import annotations

import argparse
import io
import json
import tempfile
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from towtank.commands.cli import main
from towtank.live.state import atomic_write_bytes
from towtank.runtime.manifest import atomic_write_text
from towtank.vehicle.adequacy import adequacy_table, noise_dof
from towtank.vehicle.identify import identify
from towtank.vehicle.identify_log import log_from_frame
from towtank.vehicle.simulate import simulate

ROOT = Path(__file__).resolve().parents[2]
#: The coefficients identified (the paper's): N_ur, N_rdot, N_uudr.
PAPER = ["N_ur", "N_rdot", "N_uudr"]
#: Measurement noise sd of each measured state [the column's unit].
NOISE = {"u_m_s": 0.01, "v_m_s": 0.01, "r_deg_s": 0.2, "psi_deg": 0.5, "x_m": 0.05,
         "y_m": 0.05}
#: The record's columns.
KEEP = ["t_s", "x_m", "y_m", "psi_deg", "u_m_s", "v_m_s", "r_deg_s", "rudder_deg",
        "sternplane_deg"]
#: The record: duration [s] and sample rate [Hz].
DURATION_S = 30.0
SAMPLE_HZ = 10.0
#: The methods studied: the default (filter and smoother) and least squares alone.
METHODS = ("ukf", "ls")


def predict_remus(out_dir: Path, extra: str = "") -> dict[str, Any]:
    """model.json of protocols/remus_vehicle.toml with the lines ``extra`` added to its vehicle
    section, predicted into ``out_dir``."""
    text = (ROOT / "protocols" / "remus_vehicle.toml").read_text()
    text = text.replace("fin_limit_deg = 20.0", "fin_limit_deg = 20.0\n" + extra)
    (out_dir / "p.toml").write_text(text)
    if main(["predict", str(out_dir / "p.toml"), "--out", str(out_dir / "p")]) != 0:
        raise RuntimeError("towtank predict failed on the REMUS protocol")
    return json.loads((out_dir / "p" / "model.json").read_text())


def remus_models(work: Path) -> dict[str, dict[str, Any]]:
    """REMUS as shipped (7 N buoyant, ``buoyant``), the same neutral (``neutral``), and
    Prestero's reading of added mass, damping and fin lift, neutral (``prestero``)."""
    (work / "remus").mkdir(parents=True, exist_ok=True)
    (work / "prestero").mkdir(parents=True, exist_ok=True)
    buoyant = predict_remus(work / "remus")
    prestero = predict_remus(work / "prestero", 'added_mass = "prestero"\n'
                             'damping = "prestero"\nfin_lift = "prestero"\n')
    neutral = dict(buoyant, buoyancy_N=buoyant["weight_N"])
    prestero["buoyancy_N"] = prestero["weight_N"]
    return {"buoyant": buoyant, "neutral": neutral, "prestero": prestero}


def sine_record(model: dict[str, Any], seed: int, duration_s: float = DURATION_S,
                sample_hz: float = SAMPLE_HZ, **kw: Any) -> pd.DataFrame:
    """A sine-rudder record of ``model`` (10 deg, 10 s, 1.5 m/s) with white noise
    :data:`NOISE` (seed ``seed``) on the measured states, only :data:`KEEP` kept; ``kw`` to
    :func:`towtank.vehicle.simulate.simulate` (e.g. ``net_buoyancy_n``)."""
    clean = simulate(model, "sine", 1.5, rudder_deg=10.0, period_s=10.0,
                     duration_s=duration_s, sample_hz=sample_hz, **kw)
    rng = np.random.default_rng(seed)
    df = clean[KEEP].copy()
    for col, sd in NOISE.items():
        df[col] = df[col] + rng.normal(0.0, sd, len(df))
    return df


def record_statistics(model: dict[str, Any], record: pd.DataFrame, method: str,
                      **kw: Any) -> tuple[pd.DataFrame, dict[str, Any]]:
    """Identify :data:`PAPER` from ``record`` with ``model`` by ``method``: its fit.csv rows
    (with ``ratio``, statistic over threshold, and ``cpu_s``, the identification's CPU time
    [s]) and the arrays they were computed from."""
    t0 = time.process_time()
    res = identify(model, log_from_frame(record, "study"), PAPER, method=method, **kw)
    assert res.adequacy is not None and res.residuals is not None
    table = res.adequacy.copy()
    table["ratio"] = table["statistic"] / table["threshold"]
    table["cpu_s"] = time.process_time() - t0
    return table, res.residuals


def false_alarms(stats: pd.DataFrame) -> pd.DataFrame:
    """Per method: records, records that failed any test, the rate and its Clopper–Pearson
    95 % interval. ``stats``: rows of :func:`run` (``method``, ``seed``, ``passed``)."""
    rows = []
    for method, g in stats.groupby("method"):
        failed = ~g.groupby("seed")["passed"].all()
        k, n = int(failed.sum()), int(len(failed))
        ci = binomtest(k, n).proportion_ci(0.95, method="exact")
        rows.append({"method": method, "records": n, "failed": k, "rate": k / n,
                     "low": ci.low, "high": ci.high})
    return pd.DataFrame(rows)


def rescore(arrays: Mapping[str, np.ndarray]) -> pd.DataFrame:
    """The fit.csv rows of every record of :func:`run`'s ``arrays.npz`` recomputed by the
    current :func:`towtank.vehicle.adequacy.adequacy_table` (thresholds changed, the same
    identifications), with ``seed``, ``method`` and ``ratio``."""
    frames = []
    for key in sorted(k for k in arrays if k.endswith("_innovation")):
        method, seed, _ = key.split("_")
        innovation = arrays[key]
        # the noise estimated from every sample; the first has no innovation
        dof = noise_dof(np.isfinite(innovation).sum(axis=0) + 1, np.zeros(12, dtype=bool))
        table = adequacy_table(innovation, arrays.get(f"{method}_{seed}_check"), dof=dof)
        frames.append(table.assign(ratio=table["statistic"] / table["threshold"],
                                   seed=int(seed), method=method))
    return pd.concat(frames, ignore_index=True)


def run(seeds: Iterable[int], methods: Iterable[str] = METHODS,
        out: Path | None = None, work: Path | None = None) -> pd.DataFrame:
    """The study: for each seed a matched record of the neutral REMUS, identified by each of
    ``methods``. Returns the fit.csv rows of every record with ``seed`` and ``method``; with
    ``out``, writes them (``stats.csv``, after each record) and the arrays (``arrays.npz``)."""
    with tempfile.TemporaryDirectory() as tmp:
        model = remus_models(Path(work or tmp))["neutral"]
    frames, arrays = [], {}
    for seed in seeds:
        record = sine_record(model, seed)
        for method in methods:
            # the filter's cross-check by least squares does not enter the tests
            table, inputs = record_statistics(model, record, method, check=False)
            frames.append(table.assign(seed=seed, method=method))
            arrays[f"{method}_{seed}_innovation"] = inputs["innovation"]
            if inputs["check"] is not None:
                arrays[f"{method}_{seed}_check"] = inputs["check"]
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            # each file replaced whole: a study stopped midway leaves the last records' files
            atomic_write_text(out / "stats.csv", pd.concat(frames).to_csv(index=False))
            buf = io.BytesIO()
            np.savez_compressed(buf, **arrays)
            atomic_write_bytes(out / "arrays.npz", buf.getvalue())
    return pd.concat(frames, ignore_index=True)


def _main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=100)
    parser.add_argument("--first-seed", type=int, default=5000)
    parser.add_argument("--methods", default=",".join(METHODS))
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    stats = run(range(args.first_seed, args.first_seed + args.records),
                args.methods.split(","), args.out)
    print(false_alarms(stats).to_string(index=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(_main())
