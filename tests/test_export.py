"""--export (issue 16): every usable run's reduced time series for the lab's own tools, the
same channels the coefficients were fitted on: MATLAB .mat, HDF5 and Parquet agree with each
other and with runs.csv."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.report import write_outputs
from towtank.signal.phases import PHASE_NAMES


@pytest.fixture(scope="session")
def exported(hull_day, tmp_path_factory):
    folder = tmp_path_factory.mktemp("export") / "out"
    write_outputs(hull_day.result, folder, report=False, export=("mat", "hdf5", "parquet"))
    return hull_day, folder


@pytest.mark.heavy
def test_the_steady_mean_of_the_export_is_the_runs_table(exported):
    from scipy.io import loadmat

    day, out = exported
    runs = pd.read_csv(out / "runs.csv").set_index("run")
    ok = runs[runs["status"] == "ok"]
    files = sorted((out / "export").glob("run_*.mat"))
    assert len(files) == len(ok)
    for run, row in ok.iterrows():
        mat = loadmat(out / "export" / f"run_{run:03d}.mat", squeeze_me=True)
        steady = mat["phase"] == PHASE_NAMES.index("steady")
        assert steady.sum() > 10
        assert float(np.mean(mat["drag"][steady])) == pytest.approx(row["drag_mean"], rel=1e-9,
                                                                     abs=1e-12)
        assert float(np.mean(mat["U"][steady])) == pytest.approx(row["speed_mean"], rel=1e-12)
        assert mat["t"].size == row["n_samples"]
        assert list(mat["phase_names"]) == list(PHASE_NAMES)
        assert mat["meta"]["config"].item() == row["config"]
        assert mat["meta"]["tare_group"].item() == str(row["tare_group"])
        phases_seen = [p for p in dict.fromkeys(mat["phase"].tolist()) if p >= 0]
        assert phases_seen == sorted(phases_seen)  # still, accel, steady, decel, still: in order


def test_hdf5_and_parquet_hold_the_same_series(exported):
    import h5py
    import pyarrow.parquet as pq
    from scipy.io import loadmat

    _, out = exported
    with h5py.File(out / "export" / "runs.h5", "r") as h5:
        names = sorted(h5)
        assert names and all(n.startswith("run_") for n in names)
        for name in names[:5]:
            mat = loadmat(out / "export" / f"{name}.mat", squeeze_me=True)
            table = pq.read_table(out / "export" / f"{name}.parquet")
            meta = json.loads(table.schema.metadata[b"towtank"])
            assert meta["units"]["drag"] == "N" and meta["meta"]["run"] == int(name[4:])
            for k in ("t", "U", "a", "drag", "lift", "phase"):
                np.testing.assert_array_equal(h5[name][k][()], mat[k])
                np.testing.assert_array_equal(table.column(k).to_numpy(), mat[k])
            assert h5[name]["drag"].attrs["unit"] == "N"


@pytest.mark.heavy
def test_export_from_the_command_line_is_an_output_like_the_others(tmp_path, capsys):
    from towtank.testing import synthetic as syn

    syn.make_hull_day(tmp_path, seed=5, file_format="csv", sheet_format="csv")
    protocol = syn.write_protocol(tmp_path / "p.toml",
                                  **syn.hull_protocol_sections(".", "out", sheet_format="csv"))
    assert main(["process", str(protocol), "--no-report", "-q", "--export", "parquet"]) == 0
    out = tmp_path / "out"
    assert len(list((out / "export").glob("*.parquet"))) > 30
    listed = json.loads((out / ".towtank-outputs.json").read_text(encoding="utf-8"))
    assert any("export/run_001.parquet" in str(k) for k in json.dumps(listed).split('"'))
    # asked for again without --export: the day is processed again and export/ goes away
    assert main(["process", str(protocol), "--no-report", "-q"]) == 0
    assert not (out / "export").exists()
