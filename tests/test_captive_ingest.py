"""Captive manoeuvring tests, ingest (issue 35): the protocol's [model] and [captive] keys, the
run sheet's captive columns, the run files' balance and PMM channels, the lab's table of
static means, and a ship's [model] given by its frontal area (no diameter)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import JOBS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.analysis.hull import LATERAL_AREA_UNKNOWN, fit_transverse
from towtank.commands import cli
from towtank.errors import ProtocolError, RunError
from towtank.ingest.captive_means import (
    captive_means,
    means_in_si,
    prime_magnitude_warning,
    read_means_table,
)
from towtank.ingest.protocol import Captive, ChannelMap, Model, load_protocol
from towtank.ingest.runfile import load_run
from towtank.ingest.runsheet import read_run_sheet
from towtank.ingest.sections import captive_model_missing, check_captive_runs
from towtank.testing import synthetic as syn

# ------------------------------------------------------------------ a ship: no diameter_m
SHIP_PLAN = [
    syn.RunSpec("sting", 0.0, 1.0, 0.5), syn.RunSpec("sting", 0.0, 1.4, 0.5),
    syn.RunSpec("sting", 90.0, 0.6, 0.5), syn.RunSpec("sting", 90.0, 0.9, 0.5),
    syn.RunSpec("hull", 0.0, 1.0, 0.5), syn.RunSpec("hull", 0.0, 1.4, 0.5),
    syn.RunSpec("hull", 10.0, 1.0, 0.5), syn.RunSpec("hull", 10.0, 1.4, 0.5),
    syn.RunSpec("hull", 90.0, 0.6, 0.5), syn.RunSpec("hull", 90.0, 0.9, 0.5),
]


def _ship_day(day: Path) -> Path:
    """A generated hull day whose [model] gives frontal_area_m2 and no diameter, no lateral
    area and no Myring description (as a ship's would)."""
    syn.make_hull_day(day, seed=5, sheet_format="csv", channel_style="canonical",
                      runs=SHIP_PLAN)
    sections = syn.hull_protocol_sections(".", "out", sheet_format="csv",
                                          channel_style="canonical")
    model = sections["model"]
    for key in ("diameter_m", "myring", "lateral_area_m2"):
        model.pop(key)
    model["frontal_area_m2"] = math.pi * 0.05**2 / 4.0
    return syn.write_protocol(day / "p.toml", **sections)


def test_frontal_area_without_diameter_processes_the_day(tmp_path, capsys):
    protocol = _ship_day(tmp_path)
    out = tmp_path / "out"
    code = cli.main(["process", str(protocol), "--out", str(out), "--jobs", str(JOBS),
                     "--no-report"])
    said = capsys.readouterr()
    err = said.err + said.out
    assert code == 0, err
    assert "internal error" not in err
    coef = pd.read_csv(out / "coefficients.csv").set_index("symbol")
    assert math.isfinite(coef.loc["Y_v|v|", "value"])  # the area cancels in it
    assert math.isfinite(coef.loc["X_u|u|", "value"])
    runs = pd.read_csv(out / "runs.csv")
    assert runs.loc[runs["config"] == "hull", "cd_lateral"].isna().all()
    assert LATERAL_AREA_UNKNOWN in err


def test_transverse_tows_without_lateral_area_give_y_vv_and_no_cd90():
    runs = pd.DataFrame({"run": [1, 2, 3], "status": "ok", "config": "hull",
                         "angle_deg": 90.0, "speed_mean": [0.5, 0.8, 1.0],
                         "drag_mean": [2.0, 5.12, 8.0], "rho": 1000.0})
    known = fit_transverse(runs, 1000.0, 0.02)
    est, cd90, cd90_se, table, notes = fit_transverse(runs, 1000.0, math.nan)
    assert est.value == pytest.approx(known[0].value) == pytest.approx(-8.0)
    assert math.isnan(cd90) and math.isnan(cd90_se)
    assert table is None  # no C_D,90 panel in the report, no table in the workbook
    assert notes == [LATERAL_AREA_UNKNOWN]


# ------------------------------------------------------------------ [model] and [captive]
def _protocol(tmp_path: Path, model: str = "", captive: str | None = "",
              campaign: str = 'run_sheet = "sheet.csv"\ndata_dir = "data"') -> Path:
    (tmp_path / "data").mkdir(exist_ok=True)
    (tmp_path / "sheet.csv").write_text("run,file,config,angle_deg\n1,a.csv,hull,0\n")
    text = (f'[campaign]\nname = "c"\n{campaign}\n[water]\ntemperature_C = 15.0\n'
            f"[model]\nlength_m = 2.0\ndiameter_m = 0.2\nmass_kg = 50.0\n{model}\n")
    if captive is not None:
        text += f"[captive]\n{captive}\n"
    path = tmp_path / "p.toml"
    path.write_text(text)
    return path


CAPTIVE_MODEL = "izz_kg_m2 = 12.0\niyy_kg_m2 = 12.5\nxg_m = -0.02\nbalance_x_m = 0.1\n" \
    "draught_m = 0.15"


def test_model_and_captive_keys_are_read(tmp_path):
    p = load_protocol(_protocol(tmp_path, CAPTIVE_MODEL, 'moment_ref = "balance"\n'
                                "roll_deg = -90\nmin_cycles = 4\namplitude_tolerance = 0.03"))
    m = p.model
    assert (m.izz_kg_m2, m.iyy_kg_m2, m.xg_m, m.balance_x_m, m.draught_m) == \
        (12.0, 12.5, -0.02, 0.1, 0.15)
    assert p.captive == Captive(moment_ref="balance", roll_deg=-90.0, min_cycles=4,
                                amplitude_tolerance=0.03)
    assert load_protocol(_protocol(tmp_path, "", "")).captive == Captive()
    plain = load_protocol(_protocol(tmp_path, "", None))
    assert plain.captive is None and plain.model.izz_kg_m2 is None


@pytest.mark.parametrize(("model", "captive", "said"), [
    ("izz_kg_m2 = -1.0", "", "'izz_kg_m2' in [model] must be positive"),
    ("draught_m = 0.0", "", "'draught_m' in [model] must be positive"),
    ("xg_m = 20.0", "", "'xg_m' in [model] is 20 m from the origin"),
    ("balance_x_m = -100.0", "", "'balance_x_m' in [model] is -100 m"),
    ("", 'moment_ref = "cg"', "'moment_ref' in [captive] is 'cg'"),
    ("", "roll_deg = 45", "'roll_deg' in [captive] is 45"),
    ("", "min_cycles = 2", "'min_cycles' in [captive] is 2"),
    ("", "amplitude_tolerance = 5.0", "'amplitude_tolerance' in [captive] is 5"),
    ("", "cycles = 3", "unknown key 'cycles' in [captive]"),
    ("", "means_prime = true", "'means_prime' in [captive] describes the means table"),
    ("", 'means = "none.csv"', "none.csv"),
])
def test_bad_captive_keys_are_one_sentence(tmp_path, model, captive, said):
    with pytest.raises(ProtocolError, match=re.escape(said)):
        load_protocol(_protocol(tmp_path, model, captive))


def test_means_protocol_needs_no_run_sheet_nor_data_folder(tmp_path):
    (tmp_path / "means.csv").write_text(MEANS_CSV)
    path = _protocol(tmp_path, "balance_x_m = 0.0", 'means = "means.csv"\nmeans_prime = true',
                     campaign="")
    p = load_protocol(path)
    assert not p.campaign.sheet_given
    assert p.captive.means == (tmp_path / "means.csv").resolve()
    assert p.campaign.run_sheet == p.captive.means  # an input no output may replace
    table, _ = captive_means(p)
    rho = 999.1026  # fresh water at 15 °C
    row = table.set_index("run").loc[2]
    assert row["fy"] == pytest.approx(0.0166 * 0.5 * rho * 2.0**2 * 1.2**2, rel=1e-4)
    assert row["mz"] == pytest.approx(0.0033 * 0.5 * rho * 2.0**3 * 1.2**2, rel=1e-4)
    with pytest.raises(ProtocolError, match="needs balance_x_m in \\[model\\]"):
        load_protocol(_protocol(tmp_path, "", 'means = "means.csv"\nmeans_prime = true',
                                campaign=""))


def test_captive_runs_name_the_missing_model_keys():
    model = Model(length_m=2.0, diameter_m=0.2, mass_kg=50.0)
    assert captive_model_missing(model, None) == ["izz_kg_m2", "xg_m", "balance_x_m"]
    assert captive_model_missing(model, Captive(moment_ref="balance"), ()) == []
    vertical = Model(length_m=2.0, diameter_m=0.2, mass_kg=50.0, iyy_kg_m2=3.0, xg_m=0.0,
                     balance_x_m=0.0)
    assert captive_model_missing(vertical, None, ("vertical",)) == []
    assert captive_model_missing(vertical, None, ("horizontal", "vertical")) == ["izz_kg_m2"]


# ------------------------------------------------------------------ the means table
MEANS_CSV = """Run No.,beta(deg),delta(deg),r,Speed(m/s),X',Y',N',test type
1,0,10,0,1.2,-1.2E-04,5.4E-04,-2.7E-04,rudder angle
2,30 ,0,0,1.2 ,7.8E-04,1.66E-02,3.3E-03,drift angle
3,-30,0,0,1.2,8.4E-04,-1.64E-02,-3.2E-03,drift angle
2,30,0,0,1.2,7.8E-04,1.66E-02,3.3E-03,drift + rudder angle
"""


def test_means_table_reads_the_labs_columns(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text(MEANS_CSV)
    table, notes = read_means_table(path)
    assert table["run"].tolist() == [1, 2, 3]
    assert table.loc[1, "drift_deg"] == 30.0 and table.loc[1, "speed"] == 1.2
    assert table.loc[1, "test_type"] == "drift angle"
    assert table["radius_m"].isna().all()
    assert any("1 run(s) again" in n for n in notes)
    assert any("column(s) r are not read" in n for n in notes)


@pytest.mark.parametrize(("edit", "said"), [
    (lambda t: t.replace("2,30,0,0,1.2,7.8E-04,1.66E-02", "2,30,0,0,1.2,7.8E-04,1.70E-02"),
     "run 2 is listed twice in the means table m.csv with different fy (rows 3 and 5)"),
    (lambda t: t.replace("3,-30,", "3,-130,"), "drift_deg = -130 is beyond ±90°"),
    (lambda t: t.replace("1,0,10,0,1.2,", "1,0,10,0,120,"), "speed = 120 is not a speed"),
    (lambda t: t.replace("5.4E-04", "five"), "row 2 of the means table m.csv has 'five'"),
    (lambda t: t.replace("N'", "moment"), "has no column for mz"),
])
def test_bad_means_tables_are_one_sentence(tmp_path, edit, said):
    path = tmp_path / "m.csv"
    path.write_text(edit(MEANS_CSV))
    with pytest.raises(ProtocolError, match=re.escape(said)):
        read_means_table(path)


def test_primes_read_as_newtons_stop_the_protocol(tmp_path):
    """A table whose load columns are headed X', Y', N' (primes, as the KVLCC2 table's) and a
    protocol without means_prime: read as newtons they would give derivatives 10^4 times too
    small (Y_uv' −1.3e-6 for −0.0197 on the real table), so the protocol stops in one sentence
    naming the columns; with means_prime it loads. A column with a unit (Y (N)) read as a
    prime stops it too."""
    (tmp_path / "means.csv").write_text(MEANS_CSV)
    with pytest.raises(ProtocolError, match=re.escape(
            "load column(s) X', Y', N' are named as primes")) as caught:
        load_protocol(_protocol(tmp_path, "balance_x_m = 0.0", 'means = "means.csv"',
                                campaign=""))
    assert "set means_prime = true" in str(caught.value)
    load_protocol(_protocol(tmp_path, "balance_x_m = 0.0",
                            'means = "means.csv"\nmeans_prime = true', campaign=""))
    (tmp_path / "means.csv").write_text(MEANS_CSV.replace("Y'", "Y (N)"))
    with pytest.raises(ProtocolError, match=re.escape("Y (N) carry a unit, but")):
        load_protocol(_protocol(tmp_path, "balance_x_m = 0.0",
                                'means = "means.csv"\nmeans_prime = true', campaign=""))


@pytest.mark.parametrize(("prime", "scale", "said"), [
    (False, 1.0, "are they primes?"),  # primes under names without a mark, read as N
    (True, 0.5 * 998.0 * 1.2**2 * 2.0**2, "are they in N and N m?"),  # N read as primes
    (False, 0.5 * 998.0 * 1.2**2 * 2.0**2, None),
    (True, 1.0, None),
])
def test_loads_whose_size_contradicts_means_prime_are_named(prime, scale, said):
    """The same primes (|Y'| up to 0.0166 at 1.2 m/s on a 2 m model), given as they are or
    times ½ρU²L² (forces in N, and N·L for the moments), read with and without means_prime:
    one sentence when the reading makes them implausible, none when it is right."""
    y = np.array([5.4e-4, 1.66e-2, -1.64e-2])
    n = np.array([-2.7e-4, 3.3e-3, -3.2e-3])
    table = pd.DataFrame({"speed": 1.2, "fx": 0.0, "fy": y * scale, "mz": n * scale * 2.0})
    si = means_in_si(table, prime=prime, rho=998.0, length_m=2.0)
    got = prime_magnitude_warning(si, prime=prime, rho=998.0, length_m=2.0, name="m.csv")
    assert (got is None) if said is None else (said in got), got


_value = st.floats(-1e3, 1e3, allow_nan=False).map(lambda v: float(f"{v:.6g}"))


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=st.lists(st.tuples(st.floats(-89, 89).map(round), st.floats(-35, 35).map(round),
                               st.floats(0.1, 5).map(lambda v: round(v, 3)),
                               _value, _value, _value), min_size=1, max_size=8),
       pad=st.lists(st.sampled_from(["", " ", "  "]), min_size=7, max_size=7),
       repeats=st.integers(0, 2), sep=st.sampled_from([",", ";", "\t"]))
def test_stray_blanks_and_repeated_blocks_read_to_one_table(tmp_path, rows, pad, repeats,
                                                            sep):
    def text(blanks: bool, times: int) -> str:
        def cell(v: object, k: int) -> str:
            return f"{pad[k]}{v}{pad[k]}" if blanks else str(v)

        head = sep.join(["Run No.", "beta(deg)", "delta(deg)", "Speed(m/s)", "X", "Y", "N"])
        lines = [sep.join(cell(v, k) for k, v in enumerate((i + 1, *row)))
                 for i, row in enumerate(rows)]
        return "\n".join([head, *(lines * times)]) + "\n"

    plain, messy = tmp_path / "plain.csv", tmp_path / "messy.csv"
    plain.write_text(text(False, 1))
    messy.write_text(text(True, 1 + repeats))
    a, _ = read_means_table(plain)
    b, _ = read_means_table(messy)
    cols = ["run", "drift_deg", "rudder_deg", "radius_m", "speed", "fx", "fy", "mz"]
    pd.testing.assert_frame_equal(a[cols], b[cols])
    assert len(a) == len(rows)


KVLCC2 = (Path(__file__).resolve().parents[2] / "shared" / "real" / "kvlcc2_hmri_captive"
          / "captive.csv")  # ../shared beside the repository


@pytest.mark.skipif(not KVLCC2.is_file(), reason="the real KVLCC2 means are not here")
def test_real_kvlcc2_means():
    table, notes = read_means_table(KVLCC2)
    assert len(table) == 63  # 81 rows: 18 drift runs listed again in the other blocks
    assert table["run"].is_unique
    drift = table[table["rudder_deg"] == 0]
    by_beta = drift.groupby("drift_deg")["fy"].first()
    assert by_beta[30.0] > 0 and by_beta[-30.0] < 0  # Y' with the sign of beta
    n_by_beta = drift.groupby("drift_deg")["mz"].first()
    assert n_by_beta[30.0] > 0 and n_by_beta[-30.0] < 0
    rudder = table[(table["drift_deg"] == 0) & (table["speed"] == 1.1702)]
    assert (np.sign(rudder["fy"]) == np.sign(rudder["rudder_deg"]))[rudder["rudder_deg"]
                                                                      .abs() >= 5].all()
    assert table["speed"].between(0.33, 1.18).all()
    assert any("18 run(s) again" in n for n in notes)


# ------------------------------------------------------------------ the run sheet
SHEET = """run,file,config,test,angle_deg,drift_deg,rudder_deg,radius_m,pmm_amplitude_m,\
pmm_frequency_hz,plane
1,r1.csv,hull,static drift,,10,,,,,
2,r2.csv,hull,rudder angle,4,,-20,,,,
3,r3.csv,hull,rotating arm,,0,,-12.5,,,
4,r4.csv,hull,pure sway,,,,,0.05,0.2,
5,r5.csv,hull,yaw and drift,,6,,,0.05,0.25,vertical
6,r6.csv,hull,pure yaw,,,,,,0.2,
7,r7.csv,hull,arm,,,,0,,,
8,r8.csv,sting,drift,,10,,,,,
9,r9.csv,hull,drift,5,10,,,,,
10,r10.csv,hull,drift,,120,,,,,
11,r11.csv,hull,sway,,,,,0.05,0.2,sideways
12,r12.csv,hull,steady,0,,,,,,
"""


def _sheet(tmp_path: Path, text: str = SHEET) -> pd.DataFrame:
    path = tmp_path / "sheet.csv"
    path.write_text(text)
    return read_run_sheet(path, 15.0).set_index("run")


def test_captive_rows_are_read(tmp_path):
    s = _sheet(tmp_path)
    assert s.loc[[1, 2, 3, 4, 5], "test"].tolist() == ["drift", "rudder", "arm", "sway",
                                                       "yaw_drift"]
    assert s.loc[[1, 2, 3, 4, 5], "sheet_error"].eq("").all()
    assert (s.loc[1, "drift_deg"], s.loc[1, "angle_deg"], s.loc[1, "rudder_deg"]) == \
        (10.0, 10.0, 0.0)
    assert (s.loc[2, "drift_deg"], s.loc[2, "rudder_deg"]) == (4.0, -20.0)
    assert s.loc[3, "radius_m"] == -12.5
    assert (s.loc[4, "pmm_amplitude_m"], s.loc[4, "pmm_frequency_hz"]) == (0.05, 0.2)
    assert s.loc[5, "plane"] == "vertical" and s.loc[4, "plane"] == "horizontal"
    assert s.loc[12, "sheet_error"] == ""


@pytest.mark.parametrize(("run", "said"), [
    (6, "a PMM run (yaw) needs pmm_amplitude_m"),
    (7, "an arm run needs radius_m"),
    (8, "test 'drift' is a captive test of the hull, but config is 'sting'"),
    (9, "drift_deg (10) and angle_deg (5) differ"),
    (10, "drift_deg 120 is beyond ±90°"),
    (11, "plane 'sideways' is not one of horizontal, vertical"),
])
def test_bad_captive_rows_have_their_sentence(tmp_path, run, said):
    error = _sheet(tmp_path).loc[run, "sheet_error"]
    assert error.startswith(f"row {run + 1} of sheet.csv: ") and said in error


def test_a_resistance_sheet_gains_no_captive_columns(tmp_path):
    s = _sheet(tmp_path, "run,file,config,angle_deg\n1,a.csv,hull,0\n")
    assert "drift_deg" not in s and "plane" not in s


def test_captive_runs_without_inertia_stop_the_day(tmp_path):
    sheet = _sheet(tmp_path).reset_index()
    model = Model(length_m=2.0, diameter_m=0.2, mass_kg=50.0, balance_x_m=0.0)
    with pytest.raises(ProtocolError, match=re.escape(
            "p.toml: the run sheet has 11 captive run(s) (runs 1, 2, 3, 4, 5 and 6 more), "
            "which need izz_kg_m2 and xg_m in [model]")):
        check_captive_runs(sheet, model, None, "p.toml")
    full = Model(length_m=2.0, diameter_m=0.2, mass_kg=50.0, balance_x_m=0.0, xg_m=0.0,
                 izz_kg_m2=3.0)
    check_captive_runs(sheet, full, None, "p.toml")


# ------------------------------------------------------------------ captive run files
def _captive_file(*, drop: tuple[str, ...] = (), spike: bool = False, yaw_rad: bool = False,
                  fs: float = 100.0) -> bytes:
    """A PMM yaw run: Fx in kN, Fy in N, Mz in N mm, sway in mm, yaw in deg (or rad)."""
    t = np.arange(0.0, 20.0, 1.0 / fs)
    rng = np.random.default_rng(1)
    w = 2 * np.pi * 0.25
    cols = {
        "time": t,
        "speed": np.clip(t / 2.0, 0.0, 1.0),
        "Fx (kN)": -0.004 - 1e-5 * rng.standard_normal(t.size),
        "Fy (N)": 3.0 * np.sin(w * t) + 0.02 * rng.standard_normal(t.size),
        "Mz (N mm)": 800.0 * np.cos(w * t) + 5.0 * rng.standard_normal(t.size),
        "sway (mm)": 50.0 * np.sin(w * t),
        "yaw (rad)" if yaw_rad else "yaw (deg)": (np.radians(5.0) if yaw_rad else 5.0)
        * np.cos(w * t),
    }
    if spike:
        cols["Fy (N)"][700] += 80.0
    frame = pd.DataFrame({k: v for k, v in cols.items() if k.split(" ")[0] not in drop})
    return frame.to_csv(index=False).encode()


def _load(data: bytes, test: str = "yaw", mapping: dict | None = None):
    return load_run(Path("run_007.csv"), mapping or {}, data=data, test=test)


def test_captive_channels_are_read_in_si():
    raw = _load(_captive_file(spike=True))
    assert sorted(raw.extra) == ["fx", "fy", "mz", "sway", "yaw"]
    assert np.median(raw.extra["fx"]) == pytest.approx(-4.0, abs=0.05)
    np.testing.assert_allclose(raw.drag, -raw.extra["fx"])  # drag from fx
    assert np.max(np.abs(raw.extra["mz"])) == pytest.approx(0.8, abs=0.03)
    assert np.max(raw.extra["sway"]) == pytest.approx(0.05, rel=1e-3)
    assert np.max(raw.extra["yaw"]) == pytest.approx(5.0, rel=1e-3)
    assert abs(raw.extra["fy"][700] - 3.0 * np.sin(2 * np.pi * 0.25 * 7.0)) < 0.2
    assert "1 spike(s) removed from fy" in raw.notes
    assert "drag taken as −fx (the file has no drag channel)" in raw.notes
    assert raw.units["mz"] == ("N mm", "file")
    rad = _load(_captive_file(yaw_rad=True))
    assert np.max(rad.extra["yaw"]) == pytest.approx(5.0, rel=1e-3)


def test_other_runs_do_not_read_captive_channels():
    data = _captive_file()
    raw = load_run(Path("run_007.csv"), {"drag": ChannelMap(column="Fx (kN)")}, data=data)
    assert raw.extra == {}
    assert "fy" not in raw.units


@pytest.mark.parametrize(("drop", "test", "said"), [
    (("Mz",), "drift", "the mz channel is missing, which a drift run needs"),
    (("Fy", "Mz"), "rudder", "the mz and fy channels are missing"),
    (("sway",), "sway", "the sway channel is missing, which a sway run needs"),
    (("yaw",), "yaw_drift", "the yaw channel is missing, which a yaw_drift run needs"),
])
def test_a_captive_run_without_its_channels_is_rejected(drop, test, said):
    with pytest.raises(RunError, match=re.escape(said)):
        _load(_captive_file(drop=drop), test)


def test_a_drift_run_may_record_drag_and_lift():
    data = _captive_file(drop=("Fy", "sway", "yaw"))
    mapping = {"drag": ChannelMap(column="Fx (kN)"), "lift": ChannelMap(column="Mz (N mm)")}
    raw = _load(data, "drift", {**mapping, "mz": ChannelMap(column="Mz (N mm)")})
    assert "fy" not in raw.extra and raw.lift is not None


def test_a_sway_channel_in_the_wrong_unit_is_one_sentence():
    data = _captive_file().replace(b"sway (mm)", b"sway")  # mm read as m
    with pytest.raises(RunError, match=re.escape("the sway channel reaches 50 m")):
        _load(data, "sway")


def test_the_labs_captive_column_names_are_read(tmp_path):
    s = _sheet(tmp_path, "Run #,File,Config,Test type,Drift angle (deg),Rudder (rad),"
                         "PMM amplitude (mm),PMM frequency (Hz)\n"
                         "1,a.csv,hull,PMM sway,0,0.1,40,0.3\n")
    assert s.loc[1, "sheet_error"] == ""
    assert s.loc[1, "rudder_deg"] == pytest.approx(math.degrees(0.1))
    assert (s.loc[1, "pmm_amplitude_m"], s.loc[1, "pmm_frequency_hz"]) == (0.04, 0.3)
