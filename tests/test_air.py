"""A rig in air (issue 23 item 9): ``[water] type = "air"`` with the air's own properties.

The CIPM-2007 density and Sutherland viscosity against published values; the protocol keys
(pressure_Pa, relative_humidity_pct) and their nonsense stopped with one sentence; a 1 kg model
in air not stopped by the water-only mass check; a synthetic day in air (forces made at
the air's density) processed with exit 0 and its truth recovered; the report and workbook name
the medium.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.analysis.plausibility import plausibility_warnings
from towtank.analysis.similarity import recommend_resistance, similarity_statement
from towtank.commands import cli
from towtank.errors import ProtocolError
from towtank.ingest.protocol import AIR_NOTE, load_protocol
from towtank.reference.air import (
    air_density,
    air_properties,
    air_viscosity,
    saturation_vapour_pressure,
)
from towtank.testing import synthetic as syn


# ----------------------------------------------------------------------------- properties
def test_cipm2007_density_at_20c_50pct_matches_published_value():
    """20 °C, 101325 Pa, 50 % RH: 1.1992 kg/m³, the published density of moist air of 0.04 %
    CO2 (the CIPM-2007 equation, Picard et al. 2008, Metrologia 45, 149; as tabulated for 50 %
    RH in NPL's Kay & Laby *Tables of Physical and Chemical Constants*), within 0.05 %."""
    assert air_density(20.0, 101325.0, 50.0) == pytest.approx(1.1992, rel=5e-4)


def test_dry_air_at_15c_is_the_standard_atmosphere():
    """Dry air at 15 °C and 101325 Pa: 1.2250 kg/m³, the sea-level density of the ISO 2533
    (1975) standard atmosphere, within 0.1 % (the standard's air has no CO2 correction)."""
    assert air_density(15.0, 101325.0, 0.0) == pytest.approx(1.2250, rel=1e-3)


def test_density_follows_pressure_and_humidity():
    """The ideal-gas law: ρ ∝ p at fixed composition (to the compressibility, < 0.1 %), and
    humid air is lighter than dry air (water vapour, M_v = 18 g/mol, replaces M_a = 29 g/mol)."""
    rho = air_density(20.0, 101325.0, 0.0)
    assert air_density(20.0, 90000.0, 0.0) == pytest.approx(rho * 90000.0 / 101325.0, rel=1e-3)
    assert air_density(20.0, 101325.0, 100.0) < air_density(20.0, 101325.0, 50.0) < rho
    # the vapour pressure at 20 °C: 2339 Pa (IAPWS), the CIPM-2007 fit within 0.1 %
    assert saturation_vapour_pressure(20.0) == pytest.approx(2339.0, rel=1e-3)


def test_sutherland_viscosity_at_20c():
    """Sutherland's law (White, Viscous Fluid Flow, Table 1-2): 1.716e-5 Pa s at 0 °C by
    construction and 1.81e-5 Pa s at 20 °C (tables: 1.813e-5), within 1 %; ν = μ/ρ."""
    assert air_viscosity(0.0) == pytest.approx(1.716e-5, rel=1e-9)
    assert air_viscosity(20.0) == pytest.approx(1.81e-5, rel=0.01)
    props = air_properties(20.0)
    assert props.nu == pytest.approx(props.mu / props.rho)
    assert props.nu == pytest.approx(1.51e-5, rel=0.01)


def test_air_properties_reject_nonsense():
    for bad in ({"relative_humidity_pct": 150.0}, {"pressure_Pa": -1.0},
                {"pressure_Pa": math.nan}):
        with pytest.raises(ValueError):
            air_properties(20.0, **bad)
    with pytest.raises(ValueError):
        air_density(-300.0)


# ------------------------------------------------------------------------------- protocol
def _protocol(folder: Path, water: dict[str, Any], *, mass: float = 1.0,
              length: float = 2.0, diameter: float = 0.2, **extra: Any) -> Path:
    """A protocol of a large light model (a kite-sized body): 1 kg in 0.05 m³."""
    (folder / "data").mkdir(parents=True, exist_ok=True)
    (folder / "sheet.csv").write_text("run,file,config,angle_deg\n")
    sections: dict[str, Any] = {
        "campaign": {"name": "air rig", "run_sheet": "sheet.csv", "data_dir": "data",
                     "output_dir": "out"},
        "water": water,
        "model": {"length_m": length, "diameter_m": diameter, "mass_kg": mass},
        **extra,
    }
    return syn.write_protocol(folder / "p.toml", **sections)


def test_one_kg_model_in_air_is_no_longer_stopped(tmp_path):
    """The same 1 kg, 2 m × 0.2 m body: in water it is 0.02 times the displaced water's mass, a
    unit slip (exit 2); in air the mass check is skipped, with the day's note saying so."""
    with pytest.raises(ProtocolError, match="mass_kg"):
        load_protocol(_protocol(tmp_path / "w", {"type": "fresh", "temperature_C": 20.0}))
    p = load_protocol(_protocol(tmp_path / "a", {"type": "air", "temperature_C": 20.0}))
    assert p.model is not None and p.model.mass_kg == 1.0
    assert p.water.is_air and p.water.medium == "air"
    assert p.water.pressure_Pa == 101325.0 and p.water.relative_humidity_pct == 50.0
    assert AIR_NOTE in p.warnings
    # the prototype's medium defaults to sea water: said, so that an air prototype is asked for
    p = load_protocol(_protocol(tmp_path / "b", {"type": "air", "temperature_C": 20.0},
                                prototype={"length_m": 8.0, "speeds_m_s": [10.0]}))
    assert any("[prototype.water] is not given" in w for w in p.warnings)
    assert p.prototype is not None and p.prototype.water.type == "sea"


def test_air_section_built_in_code_has_its_defaults():
    from towtank.ingest.protocol import Water

    w = Water(type="air", temperature_C=20.0)
    assert (w.pressure_Pa, w.relative_humidity_pct) == (101325.0, 50.0)
    assert Water().pressure_Pa is None


def test_water_keeps_its_keys_and_default(tmp_path):
    """Every existing [water] key works as before; water has no pressure or humidity."""
    p = load_protocol(_protocol(tmp_path, {"type": "sea", "temperature_C": 15.0,
                                           "salinity_g_kg": 35.0}, mass=60.0))
    assert p.water.type == "sea" and p.water.salinity_g_kg == 35.0
    assert p.water.pressure_Pa is None and not p.water.is_air
    assert p.water.medium == "sea water" and AIR_NOTE not in p.warnings


@pytest.mark.parametrize("water, words", [
    ({"type": "air", "temperature_C": 20.0, "pressure_Pa": 1013.25}, ["pressure_Pa", "hPa"]),
    ({"type": "air", "temperature_C": 20.0, "pressure_Pa": 101.3}, ["pressure_Pa", "kPa"]),
    ({"type": "air", "temperature_C": 20.0, "relative_humidity_pct": 150.0},
     ["relative_humidity_pct", "0–100"]),
    ({"type": "air", "temperature_C": 20.0, "salinity_g_kg": 35.0}, ["salinity_g_kg", "air"]),
    ({"type": "air", "temperature_C": 293.15}, ["temperature_C", "kelvin"]),
    ({"type": "fresh", "temperature_C": 20.0, "pressure_Pa": 101325.0},
     ["pressure_Pa", "only air"]),
    ({"type": "gas", "temperature_C": 20.0}, ["type", "air"]),
])
def test_nonsense_is_one_sentence_and_exit_2(tmp_path, capsys, water, words):
    path = _protocol(tmp_path, water)
    with pytest.raises(ProtocolError) as err:
        load_protocol(path)
    msg = str(err.value)
    assert all(w in msg for w in words), msg
    assert "\n" not in msg
    assert cli.main(["process", str(path), "--quiet", "--no-report"]) == 2
    assert msg in capsys.readouterr().err


def test_fraction_for_humidity_is_warned(tmp_path):
    p = load_protocol(_protocol(tmp_path, {"type": "air", "temperature_C": 20.0,
                                           "relative_humidity_pct": 0.5}))
    assert any("as a fraction" in w for w in p.warnings)


def test_vehicle_needs_water(tmp_path):
    path = _protocol(tmp_path, {"type": "air", "temperature_C": 20.0},
                     vehicle={"name": "v", "hull": "myring", "speed_m_s": 1.0})
    with pytest.raises(ProtocolError, match=r"\[vehicle\].*air"):
        load_protocol(path)


_numbers = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                     st.integers(-10**6, 10**6), st.text(max_size=5), st.booleans())


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(kind=st.one_of(st.sampled_from(["air", "fresh", "sea", "Air", ""]), st.text(max_size=6)),
       values=st.dictionaries(
           st.sampled_from(["temperature_C", "pressure_Pa", "relative_humidity_pct",
                            "salinity_g_kg"]), _numbers, max_size=4))
def test_medium_keys_never_crash(tmp_path, kind, values):
    """Any value of the medium's keys: a Protocol whose air has a finite state, or one sentence
    (ProtocolError), never another exception."""
    water = {"type": kind, "temperature_C": 20.0, **values}
    path = _protocol(tmp_path, water)
    try:
        p = load_protocol(path)
    except ProtocolError as exc:
        msg = str(exc)
        assert msg.strip() and "\n" not in msg
        return
    if p.water.is_air:
        rho = air_density(p.water.temperature_C, p.water.pressure_Pa,
                          p.water.relative_humidity_pct)
        assert math.isfinite(rho) and rho > 0
        assert math.isfinite(air_viscosity(p.water.temperature_C))


# ------------------------------------------------------------------- water-only checks
def test_added_mass_checks_are_skipped_in_air():
    """A positive X_udot (noise, in air) is named in water, not in air; C_D checks stay."""
    table = pd.DataFrame({"symbol": ["X_udot", "X_u|u|"], "value": [1e-5, -2.5e-4]})
    kw: dict[str, Any] = {"volume_m3": 5.5e-4, "frontal_area_m2": 0.00196,
                          "lateral_area_m2": 0.0152}
    water = plausibility_warnings(table, rho=998.0, **kw)
    air = plausibility_warnings(table, rho=1.2, added_mass=False, **kw)
    assert any("X_udot" in w for w in water)
    assert not any("X_udot" in w for w in air)
    # C_D = 2.5e-4/(0.6·0.00196) = 0.21: plausible at the air's density, not at the water's
    assert not any("C_D" in w for w in air)
    assert any("C_D at α = 0" in w for w in water)


def test_no_free_surface_in_air():
    rec = recommend_resistance(0.5, True, free_surface=False)
    assert rec.column == "drag_ittc57" and "air" in rec.rule
    assert recommend_resistance(0.5, True).column == "none"  # near a free surface: none
    text = similarity_statement((1e5, 2e5), (1e6, 2e6), 0.1, 0.05, free_surface=False)
    assert "no free surface" in text and "depth" not in text


# ------------------------------------------------------------------------- an air day
@pytest.fixture(scope="session")
def air_day(tmp_path_factory) -> dict[str, Any]:
    """The SUT-2 hull plan in air at 20 °C (20 times the speeds: 2-40 m/s), forces at the air's
    density, a 1 kg model, lab channels in volts; the prototype in air. Processed by
    ``towtank process``; its report is the workbook alone (``[report] pdf = false, figures =
    false``: the tests read the workbook and the PDF's text functions, not its pages). ``day``:
    the DayResult the command wrote."""
    import towtank.runner

    d = tmp_path_factory.mktemp("air_day")
    truth = syn.make_air_hull_day(d, file_format="csv", sheet_format="csv")
    sections = syn.air_protocol_sections(".", "out", sheet_format="csv")
    sections["report"] = {"pdf": False, "figures": False}
    protocol = syn.write_protocol(d / "p.toml", **sections)
    rho = air_density(20.0)
    out = d / "out"
    runs = []
    run_day = towtank.runner.run_day

    def kept_run_day(*args: Any, **kwargs: Any) -> Any:
        runs.append(run_day(*args, **kwargs))
        return runs[-1]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(towtank.runner, "run_day", kept_run_day)
        code = cli.main(["process", str(protocol), "--quiet", "--jobs", "1", "--out", str(out)])
    return {"dir": d, "truth": truth, "code": code, "out": out, "rho": rho,
            "day": runs[0].day}


@pytest.mark.heavy
def test_air_day_exits_0_and_recovers_its_truth(air_day):
    assert air_day["code"] == 0
    out = air_day["out"]
    truth = syn.load_truth(air_day["dir"])
    assert truth["water"]["type"] == "air"
    assert truth["water"]["rho"] == pytest.approx(air_day["rho"], rel=1e-3)
    runs = pd.read_csv(out / "runs.csv")
    ok = runs[runs["status"] == "ok"]
    assert (runs["status"] != "rejected").all()
    # each run normalised with the air at its own temperature (CIPM-2007, Sutherland)
    for _, row in ok.iterrows():
        t = truth["runs"][str(int(row["run"]))]["water_temp_C"]
        assert row["rho"] == pytest.approx(air_density(t), rel=1e-6)
        assert row["nu"] == pytest.approx(air_properties(t).nu, rel=1e-6)
    hull = ok[ok["config"] == "hull"]
    for _, row in hull.iterrows():
        expected = truth["runs"][str(int(row["run"]))]["drag_model"]
        assert row["drag_mean"] == pytest.approx(expected, rel=0.01, abs=2e-3), row["run"]
    coef = pd.read_csv(out / "coefficients.csv").set_index("symbol")
    primes = truth["primes"]
    # the damping primes (on ½ρ_air L²) are the SUT-2 table's: the air's density cancels
    for sym in ("X_u|u|", "Y_v|v|"):
        assert coef.loc[sym, "prime"] == pytest.approx(primes[sym], rel=0.02), sym
    for sym in ("X_u|u|", "Y_v|v|"):  # the day's own air density: 1e-4 from the truth's
        assert coef.loc[sym, "value"] == pytest.approx(truth["coefficients"][sym], rel=0.005)
    for sym in ("X_uv", "X_v|v|", "X_udot", "Y_vdot"):
        value = truth["coefficients"][sym]
        assert coef.loc[sym, "ci_low"] <= value <= coef.loc[sym, "ci_high"], sym
    # in air the added mass is below the weighing's uncertainty (0.5 g): its interval says so
    assert coef.loc["X_udot", "ci_low"] < 0 < coef.loc["X_udot", "ci_high"]


def test_air_day_outputs_name_the_medium(air_day):
    out = air_day["out"]
    summary = pd.read_excel(out / "report.xlsx", sheet_name=0, header=None)
    cells = [str(v) for v in summary.to_numpy().ravel() if isinstance(v, str)]
    assert "air" in cells and "air temperature" in cells and "air pressure" in cells
    assert not any("fresh" in c for c in cells)
    import json

    prov = json.loads((out / "provenance.json").read_text())
    water = prov["settings"]["water"]
    assert water["type"] == "air" and water["pressure_Pa"] == 101325.0
    assert water["relative_humidity_pct"] == 50.0 and "CIPM-2007" in water["properties"]
    assert prov["scaling"]["prototype_water"]["type"] == "air"
    scaling = pd.read_csv(out / "scaling.csv")
    assert (scaling["recommended"] == "drag_ittc57").all()
    # the prototype in air at 15 °C: its density and viscosity are the air's
    assert prov["scaling"]["rho_prototype"] == pytest.approx(air_density(15.0), rel=1e-9)
    assert prov["scaling"]["nu_prototype"] == pytest.approx(air_properties(15.0).nu, rel=1e-9)
    assert np.isfinite(scaling["drag_ittc57"]).all()


def test_air_day_report_text(air_day):
    """The title page and the summary say air, with its pressure and humidity, never 'fresh
    water'; the warnings carry the note of the skipped water-only checks."""
    from towtank.report import pdf

    day = air_day["day"]
    text = pdf._water_text(day.protocol.water, day.runs)
    assert text.startswith("air, ") and "101325 Pa" in text and "50 % relative humidity" in text
    assert "water" not in text
    assert pdf._medium_label(day.protocol.water) == "Air"
    assert AIR_NOTE in [str(n) for n in day.warnings]
    assert not any("displaced mass" in w and "X_udot" in w for w in map(str, day.warnings))


# ------------------------------------------------------------------ the real kite (air)
KITE = Path(__file__).resolve().parents[1] / ".." / "shared" / "real" / "tudelft_kite_lvm"


@pytest.mark.skipif(not (KITE / "normal_aoa_16_vw_20.lvm").is_file(),
                    reason="../shared/real/tudelft_kite_lvm is not present")
def test_kite_in_air_is_not_stopped_by_the_mass_check(tmp_path, capsys):
    """The TU Delft kite (6-component balance, open jet at 19.8 m/s; vw_00 its wind-off zeros):
    a 1 kg model with the kite's span as its 'diameter' is 0.0025 times the water it would
    displace, so in water the day stops (exit 2) before anything is read; in air it goes on to
    the runs (the files are read in place, never copied)."""
    (tmp_path / "sheet.csv").write_text(
        "run,file,config,angle_deg,speed_nominal,water_temp_C\n"
        "1,normal_aoa_16_vw_20.lvm,hull,16,19.8,20\n")

    def write(kind: str) -> Path:
        return syn.write_protocol(
            tmp_path / f"kite_{kind}.toml",
            campaign={"name": "TU Delft V3 kite", "run_sheet": "sheet.csv",
                      "data_dir": str(KITE.resolve()), "output_dir": f"out_{kind}"},
            water={"type": kind, "temperature_C": 20.0},
            model={"length_m": 0.4, "diameter_m": 1.3, "mass_kg": 1.0},
            channels={"drag": {"column": "Untitled"}, "lift": {"column": "Untitled 2"}},
            zeros={"file": "normal_aoa_16_vw_00.lvm"},
        )

    water = write("fresh")
    assert cli.main(["process", str(water), "--quiet", "--no-report"]) == 2
    assert "mass_kg" in capsys.readouterr().err
    air = write("air")
    assert load_protocol(air).water.is_air
    code = cli.main(["process", str(air), "--quiet", "--no-report"])
    assert code != 2 and "mass_kg" not in capsys.readouterr().err


@pytest.mark.heavy
def test_synth_air_day_processes(tmp_path):
    """``towtank synth --day air``: a day a lab can try; it processes with exit 0 (every run
    usable), the protocol in air."""
    day = tmp_path / "air"
    assert cli.main(["synth", str(day), "--day", "air", "--sheet", "csv",
                     "--format", "csv"]) == 0
    protocol = day / "protocol.toml"
    assert load_protocol(protocol).water.is_air
    assert cli.main(["process", str(protocol), "--quiet", "--no-report", "--jobs", "1"]) == 0
    runs = pd.read_csv(day / "out" / "runs.csv")
    assert runs.loc[runs["status"] == "ok", "rho"].between(1.18, 1.21).all()


def test_run_sheet_temperature_in_air(tmp_path):
    """In air a run at -10 °C is a cold wind tunnel, not an error (water would be ice); 293 °C
    is still a temperature in kelvin, rejecting that run with the slip named."""
    from towtank.ingest.runsheet import read_run_sheet

    sheet = tmp_path / "sheet.csv"
    sheet.write_text("run,file,config,angle_deg,water_temp_C\n1,a.csv,hull,0,-10\n"
                     "2,b.csv,hull,0,293.15\n")
    water = read_run_sheet(sheet, 20.0).set_index("run")["sheet_error"]
    air = read_run_sheet(sheet, 20.0, air=True).set_index("run")
    assert "water_temp_C" in water[1]
    assert air.loc[1, "sheet_error"] == "" and air.loc[1, "water_temp_C"] == -10.0
    assert "kelvin" in air.loc[2, "sheet_error"]
