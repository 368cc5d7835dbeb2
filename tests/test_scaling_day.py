"""Issue 5 on the sample hull day: prototype coefficients and the scaling table.

The SUT-2 prototype (L = 1.412 m, λ = 4) in sea water at 15 °C: every coefficient carries
prime × ½ρ_p·L_p^k, scaling.csv follows Froude and Reynolds similarity and the ITTC-57 line,
and ``towtank scale`` prints the same numbers from the cached reduction.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.analysis import similarity
from towtank.analysis.scaling import form_factor_warnings
from towtank.commands.cli import main
from towtank.errors import ProtocolError
from towtank.ingest.protocol import load_protocol
from towtank.pipeline import process_day
from towtank.reference import geometry
from towtank.reference.water import water_properties

ROOT = Path(__file__).resolve().parents[1]
PROTOCOL = ROOT / "protocols" / "sut2_hull.toml"
SCALING_COLUMNS = ["speed_prototype", "re_prototype", "fn_prototype", "speed_model_froude",
                   "speed_model_reynolds", "drag_froude", "drag_ittc57"]


@pytest.fixture(scope="session")
def outputs(sample_outputs):
    """The sample day's output folder (shared: read only)."""
    done = sample_outputs("sut2_hull")
    assert done.code == 0
    return done.out


@pytest.fixture(scope="session")
def cache(outputs, tmp_path_factory):
    """A copy of the sample day's run cache: the variants below reduce nothing again."""
    folder = tmp_path_factory.mktemp("cache") / ".cache"
    shutil.copytree(outputs / ".cache", folder)
    return folder


def _variant(folder: Path, *, drop: tuple[str, ...] = (), myring: bool = True,
             prototype: dict[str, str] | None = None) -> Path:
    """protocols/sut2_hull.toml with keys dropped, [model.myring] removed or [prototype]
    values changed (``key: TOML value``), written to ``folder``."""
    text = PROTOCOL.read_text(encoding="utf-8").replace('"../', f'"{ROOT}/')
    text = re.sub(r"(?m)^output_dir = .*\n", "", text)
    for key in drop:
        text, n = re.subn(rf"(?m)^{key} = .*\n", "", text)
        assert n == 1, key
    if not myring:
        text, n = re.subn(r"(?ms)^\[model\.myring\]\n.*?(?=^\[)", "", text)
        assert n == 1
        text = re.sub(r"(?ms)^\[vehicle\]\n.*?(?=^\[|\Z)", "", text)  # its hull is the Myring
    for key, value in (prototype or {}).items():
        text, n = re.subn(r"(?m)^(\[prototype\]\n)", rf"\g<1>{key} = {value}\n", text)
        assert n == 1
        text = re.sub(rf"(?m)^({key} = .*\n)((?:.*\n)*?){key} = .*\n", r"\1\2", text)
    path = folder / "variant.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _process_cached(path: Path, out: Path, cache: Path, *args: str) -> int:
    """``towtank process`` on a variant, with the sample day's reductions in its cache."""
    shutil.copytree(cache, out / ".cache")
    return main(["process", str(path), "--no-report", "--out", str(out), *args])


def _zero_runs(runs: pd.DataFrame) -> pd.DataFrame:
    return runs[(runs.config == "hull") & (runs.status == "ok") & (runs.angle_deg == 0)]


def test_prototype_values_are_prime_times_prototype_scale(outputs):
    coef = pd.read_csv(outputs / "coefficients.csv")
    sea = water_properties(15.0, "sea")
    for row in coef.itertuples():
        k = 3 if row.symbol.endswith("dot") else 2
        expected = row.prime * 0.5 * sea.rho * 1.412**k
        assert row.prototype_value == pytest.approx(expected, rel=1e-12), row.symbol
    # prime values carry over unchanged: prototype/model ratio = (ρ_p/ρ_m)·λ^k
    x = coef.set_index("symbol")
    ratio = x.loc["X_udot", "prototype_value"] / x.loc["X_udot", "value"]
    fresh = water_properties(18.0, "fresh")
    assert ratio == pytest.approx(sea.rho / fresh.rho * 4.0**3, rel=2e-3)


def test_scaling_table_laws(outputs):
    sc = pd.read_csv(outputs / "scaling.csv")
    assert list(sc.columns[: len(SCALING_COLUMNS)]) == SCALING_COLUMNS
    assert sc["speed_prototype"].tolist() == [1.0, 1.5, 2.0, 2.5]
    sea = water_properties(15.0, "sea")
    fresh = water_properties(18.0, "fresh")
    up = sc["speed_prototype"].to_numpy()
    np.testing.assert_allclose(sc["speed_model_froude"], up / 2.0, rtol=1e-12)
    np.testing.assert_allclose(sc["speed_model_reynolds"], up * 4.0 * fresh.nu / sea.nu,
                               rtol=1e-9)
    np.testing.assert_allclose(sc["re_prototype"], up * 1.412 / sea.nu, rtol=1e-9)
    np.testing.assert_allclose(sc["fn_prototype"], up / np.sqrt(9.80665 * 1.412), rtol=1e-12)
    # Froude drag: the model's zero-angle resistance at U_p/2, times λ³ ρ_p/ρ_m
    runs = pd.read_csv(outputs / "runs.csv")
    zero = runs[(runs.config == "hull") & (runs.status == "ok") & (runs.angle_deg == 0)]
    k2 = np.linalg.lstsq(np.column_stack([zero.speed_mean**2, zero.speed_mean]),
                         zero.drag_mean, rcond=None)[0]
    um = sc["speed_model_froude"].to_numpy()
    r_m = k2[0] * um**2 + k2[1] * um
    np.testing.assert_allclose(sc["drag_froude"], r_m * 64 * sea.rho / fresh.rho, rtol=1e-3)
    # flagged where the Froude model speed was not tested (0.5 and 0.75 m/s < 0.8 m/s)
    assert sc["froude_in_tested_range"].tolist() == [False, False, True, True]


def test_ittc57_drag_follows_form_factor(outputs):
    sc = pd.read_csv(outputs / "scaling.csv")
    runs = pd.read_csv(outputs / "runs.csv")
    zero = runs[(runs.config == "hull") & (runs.status == "ok") & (runs.angle_deg == 0)]
    ff = similarity.form_factor(zero.drag_mean.to_numpy(), zero.speed_mean.to_numpy(), 0.0472,
                                zero.rho.to_numpy(), zero.nu.to_numpy(), 0.353)
    sea = water_properties(15.0, "sea")
    up = sc["speed_prototype"].to_numpy()
    cf = 0.075 / (np.log10(up * 1.412 / sea.nu) - 2) ** 2
    expected = 0.5 * sea.rho * 0.0472 * 16 * up**2 * ff.one_plus_k * cf
    np.testing.assert_allclose(sc["drag_ittc57"], expected, rtol=1e-9)
    # a deeply submerged hull scaled by Reynolds drags less than Froude-scaled, at every speed
    assert np.all(sc["drag_ittc57"] < sc["drag_froude"])


def test_ittc57_line_value():
    assert similarity.ittc57_cf(1e6) == pytest.approx(0.0046875, rel=1e-12)


def _spy_on_reductions(monkeypatch) -> list[int]:
    """Record every run handed to the reduction stage, wherever it would then run.

    The runs are reduced in worker processes, where a patch of ``load_run`` in this process
    sees nothing; :func:`towtank.runtime.parallel.map_runs` is the one door every reduction passes
    through, in this process, so the spy sits there.
    """
    import towtank.runtime.parallel as parallel

    reduced: list[int] = []
    real = parallel.map_runs

    def spy(func, protocol, records, **kwargs):
        records = list(records)
        reduced.extend(int(r["run"]) for r in records)
        return real(func, protocol, records, **kwargs)

    monkeypatch.setattr(parallel, "map_runs", spy)
    return reduced


def _packs(cache_dir: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted((cache_dir / "runs").iterdir())}


def test_scale_command_prints_table_from_cache(outputs, capsys, monkeypatch):
    import towtank.reduce.run as reduce_stage

    def no_read(*args, **kwargs):
        raise AssertionError("the scale command re-read a run file despite the cache")

    reduced = _spy_on_reductions(monkeypatch)
    monkeypatch.setattr(reduce_stage, "load_run", no_read)
    packs = _packs(outputs / ".cache")
    assert packs
    code = main(["scale", str(PROTOCOL), "--speeds", "2", "3", "--out", str(outputs)])
    text = capsys.readouterr().out
    assert code == 0
    assert reduced == []  # every run came from the cache: none was handed to a worker
    assert _packs(outputs / ".cache") == packs  # and the cache was not rewritten
    assert "U_m Froude" in text and "ITTC-57" in text
    assert "1.000" in text and "1.500" in text  # Froude model speeds of 2 and 3 m/s
    assert "depth" in text.lower() or "froude similarity" in text.lower()
    assert "4 tested speeds, 9 runs" in text


def test_reduction_spy_sees_a_cache_miss(tmp_path, capsys, monkeypatch):
    """The spy of the test above is not blind: with no cache, scale reduces every run."""
    reduced = _spy_on_reductions(monkeypatch)
    code = main(["scale", str(PROTOCOL), "--speeds", "2", "--out", str(tmp_path / "empty")])
    assert code == 0 and "U_m Froude" in capsys.readouterr().out
    assert len(reduced) == 41  # the sheet's 42 runs but the void one


@pytest.mark.parametrize("speed", ["nan", "inf", "-1", "0", "1e-9"])
def test_scale_command_refuses_unusable_speeds(outputs, capsys, speed):
    code = main(["scale", str(PROTOCOL), "--speeds", "2", speed, "--out", str(outputs)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.count("\n") == 0 and "--speeds" in err and "internal error" not in err
    assert "prototype speed" in err


def test_scale_speeds_are_checked_as_the_protocols_speeds_m_s(outputs, tmp_path, capsys):
    """--speeds 2500 (mm/s for m/s) printed R_p = 5,033,207 N at Fn = 672 with exit 0, where
    [prototype] speeds_m_s = [2500.0] stops: both go through one check, in one sentence."""
    code = main(["scale", str(PROTOCOL), "--speeds", "2", "2500", "--out", str(outputs)])
    err = capsys.readouterr().err.strip()
    assert code == 2
    said = ("must all be positive prototype speeds up to 100 m/s, but they are 2, 2500; was it "
            "given in mm/s for m/s?")
    assert err == f"towtank: --speeds {said}"
    path = _variant(tmp_path, prototype={"speeds_m_s": "[2.0, 2500.0]"})
    with pytest.raises(ProtocolError) as exc:
        load_protocol(path)
    assert str(exc.value) == f"{path.name}: 'speeds_m_s' in [prototype] {said}"


def test_prototype_speeds_below_the_turbulent_range_are_warned(outputs, capsys):
    code = main(["scale", str(PROTOCOL), "--speeds", "0.05", "2", "--out", str(outputs)])
    out = capsys.readouterr().out
    assert code == 0
    assert "warning: prototype speeds 0.05 m/s give Re below 200000" in out
    assert "ITTC-57 drag there is indicative only" in out
    code = main(["scale", str(PROTOCOL), "--speeds", "2", "--out", str(outputs)])
    assert code == 0 and "indicative only" not in capsys.readouterr().out


def test_protocol_speed_below_minimum_reynolds_exits_2(tmp_path, cache, capsys):
    path = _variant(tmp_path, prototype={"speeds_m_s": "[0.00005, 1.0]"})
    out = tmp_path / "out"
    assert _process_cached(path, out, cache, "-q") == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "internal error" not in err
    assert "'speeds_m_s' in [prototype]" in err and "5e-05 m/s" in err and "Re = 59" in err
    assert not (out / "scaling.csv").exists()  # nothing written


def test_missing_wetted_area_leaves_only_ittc57_empty(outputs, tmp_path, cache, capsys):
    """No wetted_area_m2 and no Myring description (valid per FORMATS): the day completes,
    drag_ittc57 is empty with a warning and every other column of scaling.csv is as before."""
    path = _variant(tmp_path, drop=("wetted_area_m2",), myring=False)
    out = tmp_path / "out"
    assert _process_cached(path, out, cache) == 0
    text = capsys.readouterr().out
    assert "drag_ittc57 needs the model's wetted area" in text
    sc = pd.read_csv(out / "scaling.csv")
    assert sc["drag_ittc57"].isna().all()
    ref = pd.read_csv(outputs / "scaling.csv")
    rest = [c for c in ref.columns
            if c not in ("drag_ittc57", "drag_recommended", "recommended")]
    pd.testing.assert_frame_equal(sc[rest], ref[rest])
    # no ITTC-57 estimate: none is recommended (Froude scaling is not one for this hull)
    assert (sc["recommended"] == "none").all() and sc["drag_recommended"].isna().all()
    prov = json.loads((out / "provenance.json").read_text(encoding="utf-8"))
    assert prov["scaling"]["form_factor"] is None
    assert prov["scaling"]["wetted_area_prototype_m2"] is None
    wetted = next(g for g in prov["geometry"]["quantities"] if g["symbol"] == "S_m")
    assert wetted["value"] is None and "not known" in wetted["source"]


def test_myring_geometry_is_used_and_documented(tmp_path, cache):
    """wetted_area_m2 and lateral_area_m2 left out, a Myring description given: its areas are
    used (the wetted area in 1 + k and, through the ΔC_F term, in drag_ittc57) and the
    workbook, the PDF text and provenance.json say where each came from."""
    import openpyxl

    from towtank.report.pdf import geometry_text
    from towtank.report.provenance import provenance
    from towtank.report.workbook import write_workbook

    path = _variant(tmp_path, drop=("wetted_area_m2", "lateral_area_m2"),
                    prototype={"delta_cf": "0.0004"})
    day = process_day(path, cache_dir=cache)
    my = tomllib.loads(PROTOCOL.read_text(encoding="utf-8"))["model"]["myring"]
    g = geometry.myring_geometry(my["a"], my["b"], my["c"], my["n"], my["theta_deg"], my["d"])
    model = day.protocol.model
    assert model.wetted_area_m2 == g.wetted_area and model.lateral_area == g.lateral_area
    assert g.wetted_area == pytest.approx(0.0483, abs=5e-5)  # not the 0.0472 of the protocol

    zero = _zero_runs(day.runs)
    rho_m, nu_m = zero.rho.to_numpy(), zero.nu.to_numpy()  # each run's water
    ff = similarity.form_factor(zero.drag_mean, zero.speed_mean, g.wetted_area, rho_m, nu_m,
                                0.353)
    assert day.scaling.form_factor.one_plus_k == pytest.approx(ff.one_plus_k, rel=1e-12)
    given = similarity.form_factor(zero.drag_mean, zero.speed_mean, 0.0472, rho_m, nu_m, 0.353)
    assert abs(ff.one_plus_k - given.one_plus_k) > 0.02  # the area matters to 1 + k
    sea = water_properties(15.0, "sea")
    up = day.scaling.table["speed_prototype"].to_numpy()
    cf = 0.075 / (np.log10(up * 1.412 / sea.nu) - 2) ** 2
    s_p = 16 * g.wetted_area
    expected = 0.5 * sea.rho * s_p * up**2 * (ff.one_plus_k * cf + 0.0004)
    np.testing.assert_allclose(day.scaling.table["drag_ittc57"], expected, rtol=1e-9)
    assert day.scaling.wetted_area_prototype == pytest.approx(s_p, rel=1e-12)
    assert "Re = 2e+05" in day.scaling.statement  # the form factor's laminar threshold

    write_workbook(day, tmp_path)
    rows = [r[:5] for r in openpyxl.load_workbook(tmp_path / "report.xlsx")["Summary"]
            .iter_rows(values_only=True)]
    head = rows.index(("quantity", "symbol", "value", "unit", "source"))
    table = {r[1]: r for r in rows[head + 1:head + 6]}
    assert table["S_m"][2] == g.wetted_area and "Myring" in table["S_m"][4]
    assert table["A_lat"][2] == g.lateral_area and "Myring" in table["A_lat"][4]
    assert table["S_p"][2] == pytest.approx(s_p, rel=1e-12)
    assert any("Myring" in str(r[0]) for r in rows if r and r[0])  # the geometry_source note

    prov = json.loads(json.dumps(provenance(day), default=str))
    geo = {q["symbol"]: q for q in prov["geometry"]["quantities"]}
    assert geo["S_m"]["value"] == g.wetted_area and "Myring" in geo["S_m"]["source"]
    assert "wetted area" in prov["geometry"]["geometry_source"]
    assert "Myring" in prov["geometry"]["geometry_source"]
    assert prov["scaling"]["delta_cf"] == 0.0004
    assert "S_m = 0.04831 m² (Myring description)" in geometry_text(day)


def test_roughness_allowance_adds_its_term_exactly(tmp_path, cache):
    """[prototype] delta_cf through the whole day: drag_ittc57 rises by ½ρ_p U² S_p ΔC_F."""
    base = process_day(PROTOCOL, cache_dir=cache)
    rough = process_day(_variant(tmp_path, prototype={"delta_cf": "0.0004"}), cache_dir=cache)
    assert rough.protocol.prototype.delta_cf == 0.0004
    sea = water_properties(15.0, "sea")
    up = base.scaling.table["speed_prototype"].to_numpy()
    rise = 0.5 * sea.rho * up**2 * (16 * 0.0472) * 0.0004
    np.testing.assert_allclose(
        rough.scaling.table["drag_ittc57"] - base.scaling.table["drag_ittc57"], rise, rtol=1e-9
    )
    assert rough.scaling.form_factor.one_plus_k == base.scaling.form_factor.one_plus_k
    pd.testing.assert_series_equal(rough.scaling.table["drag_froude"],
                                   base.scaling.table["drag_froude"])


def test_a_wetted_area_in_cm2_is_named_twice_and_1_plus_k_below_1_is_warned(tmp_path, cache):
    """wetted_area_m2 = 472 (the sample hull's 0.0472 m² typed in cm²): the protocol warns
    of the unit, and the day's form factor, 1 + k = 0.000155 (the drag is 6500 times less than
    the friction of 472 m²), is named as no hull's, with drag_ittc57 not to be trusted."""
    text = _variant(tmp_path).read_text(encoding="utf-8")
    text, n = re.subn(r"(?m)^wetted_area_m2 = 0\.0472", "wetted_area_m2 = 472.0", text)
    assert n == 1
    (tmp_path / "cm2.toml").write_text(text, encoding="utf-8")
    day = process_day(tmp_path / "cm2.toml", cache_dir=cache)
    said = [str(w) for w in day.warnings]
    assert any("[model] wetted_area_m2 = 472 m² is 8.51e+03 times π·D·L" in w for w in said)
    one_plus_k = day.scaling.form_factor.one_plus_k
    assert one_plus_k == pytest.approx(1.548e-4, rel=0.01)
    hits = [w for w in said if w.startswith("form factor 1 + k = 0.000155 is far below 1")]
    assert len(hits) == 1 and "wetted_area_m2 in other units" in hits[0], said


def test_form_factor_takes_each_run_at_its_own_water():
    """Two runs at 0.8 m/s in water at 10 °C and 26 °C, two at 2 m/s at 26 °C (the sample
    hull's speeds and drags): 1 + k by hand, each run's C_T with its ρ and C_F at its
    Re = U L/ν, equals form_factor's with the runs' waters. The mean water (what the day
    used) moved this programme's 1 + k by 0.5 %, its speeds' 1 + k by up to 3 %."""
    u = np.array([0.8, 0.8, 2.0, 2.0])
    r = np.array([0.1392, 0.1376, 0.8264, 0.8251])
    w = [water_properties(t, "fresh") for t in (10.0, 26.0, 26.0, 26.0)]
    rho, nu = np.array([x.rho for x in w]), np.array([x.nu for x in w])
    ff = similarity.form_factor(r, u, 0.0472, rho, nu, 0.353, re_min=1e5)
    re = u * 0.353 / nu
    k = r / (0.5 * rho * 0.0472 * u**2) / (0.075 / (np.log10(re) - 2.0) ** 2)
    assert ff.one_plus_k == pytest.approx(np.mean([k[:2].mean(), k[2:].mean()]), rel=1e-12)
    np.testing.assert_allclose(ff.reynolds, re, rtol=1e-12)
    mean = similarity.form_factor(r, u, 0.0472, rho.mean(), nu.mean(), 0.353, re_min=1e5)
    assert abs(mean.one_plus_k / ff.one_plus_k - 1.0) > 0.004  # 0.50 %
    with pytest.raises(ValueError, match="one per point"):
        similarity.form_factor(r, u, 0.0472, rho[:3], nu, 0.353)


def test_form_factor_warnings_by_range():
    """None at 1 and above; laminar flow named between 0.5 and 1; units below 0.5."""
    assert form_factor_warnings(1.0, 0.05) == [] and form_factor_warnings(1.3, 0.05) == []
    assert form_factor_warnings(math.nan, 0.05) == []
    assert "laminar" in form_factor_warnings(0.8, 0.05)[0]
    assert "other units" in form_factor_warnings(0.4, 0.05)[0]


def test_hot_prototype_water_is_a_day_warning(tmp_path, cache):
    text = _variant(tmp_path).read_text(encoding="utf-8")
    text, n = re.subn(r"(\[prototype\.water\]\ntype = \"sea\"\ntemperature_C = )15\.0",
                      r"\g<1>45.0", text)
    assert n == 1
    (tmp_path / "hot.toml").write_text(text, encoding="utf-8")
    day = process_day(tmp_path / "hot.toml", cache_dir=cache)
    hits = [w for w in map(str, day.warnings) if "[prototype.water]" in w]
    assert len(hits) == 1 and "temperature_C = 45" in hits[0]


def test_sample_day_form_factor_is_the_mean_over_tested_speeds(outputs):
    """Nine zero-angle runs at four speeds (five at 2 m/s): 1 + k weighs each speed once."""
    runs = pd.read_csv(outputs / "runs.csv")
    zero = _zero_runs(runs)
    u = zero.speed_mean.to_numpy()
    # each run at its own water (runs.csv rho, nu), as docs/method.md says of every run
    ct = zero.drag_mean.to_numpy() / (0.5 * zero.rho.to_numpy() * 0.0472 * u**2)
    k = ct / similarity.ittc57_cf(u * 0.353 / zero.nu.to_numpy())
    per_speed = pd.Series(k).groupby(np.round(u, 1)).mean()
    assert list(per_speed.index) == [0.8, 1.2, 1.6, 2.0]
    prov = json.loads((outputs / "provenance.json").read_text(encoding="utf-8"))
    ff = prov["scaling"]["form_factor"]
    assert (ff["n_speeds"], ff["n_runs"]) == (4, 9)
    assert ff["one_plus_k"] == pytest.approx(per_speed.mean(), rel=1e-6)
    assert ff["std"] == pytest.approx(per_speed.std(ddof=1), rel=1e-6)
    assert abs(ff["one_plus_k"] - k.mean()) > 0.05  # the run-weighted mean is another number


def test_myring_geometry_feeds_the_model():
    from towtank.ingest.protocol import load_protocol

    p = load_protocol(PROTOCOL)
    assert p.model.myring is not None
    assert p.model.volume_m3 == pytest.approx(math.pi * 0.05**2 / 4 * 0.353, rel=0.5)
    assert "Myring" in p.model.geometry_source
    assert p.model.frontal_area == pytest.approx(math.pi * 0.05**2 / 4, rel=1e-12)


def test_scaling_csv_names_the_recommended_prototype_resistance(outputs):
    """Issue 22: the deeply submerged sample hull (5 D) makes no waves, so the recommended
    prototype resistance is the ITTC-57 one, in its own column; Froude scaling is comparison."""
    sc = pd.read_csv(outputs / "scaling.csv")
    assert (sc["recommended"] == "drag_ittc57").all()
    np.testing.assert_array_equal(sc["drag_recommended"], sc["drag_ittc57"])
    assert not np.allclose(sc["drag_recommended"], sc["drag_froude"])
    prov = json.loads((outputs / "provenance.json").read_text(encoding="utf-8"))["scaling"]
    assert prov["recommended"]["column"] == "drag_ittc57"
    assert prov["form_factor"]["trend"]["significant"] is True


def test_form_factor_trend_of_the_sample_day_is_named(outputs):
    """The sample day's 1 + k rises from 1.37 at 0.8 m/s to 1.70 at 2 m/s: a significant trend
    with Re, which the scaling result states with what was used."""
    day = process_day(PROTOCOL, jobs=1, cache_dir=outputs / ".cache")
    sr = day.scaling
    trend = sr.form_factor_trend
    assert trend.significant and trend.slope > 0
    assert trend.first[1] == pytest.approx(1.364, abs=0.005)
    assert trend.last[1] == pytest.approx(1.701, abs=0.005)
    assert sr.form_factor_trend_text.startswith("1 + k rises with Re from 1.364")
    assert f"the mean {sr.form_factor.one_plus_k:.3f}" in sr.form_factor_trend_text


def _straight_runs(speeds: list[float], k2: float = 12.0, k1: float = 0.8) -> pd.DataFrame:
    """Steady straight hull runs whose drag is R = k2·U|U| + k1·U plus a ripple [N] that no
    two-term curve follows, in fresh water at 18 °C."""
    u = np.asarray(speeds, dtype=float)
    rho, nu = 998.6, 1.054e-6
    return pd.DataFrame({
        "run": np.arange(1, len(u) + 1), "config": "hull", "status": "ok", "angle_deg": 0.0,
        "speed_mean": u, "drag_mean": k2 * u * np.abs(u) + k1 * u + 0.01 * np.cos(7.0 * u),
        "rho": rho, "nu": nu, "re": u * 0.35 / nu,
    })


@pytest.mark.parametrize("speeds", [[0.6, 1.2], [0.6, 0.9, 1.2, 1.5]])
def test_the_resistance_curves_errors_are_nan_only_when_two_runs_fix_it(speeds):
    """k2 and k1 from exactly two straight runs leave no residual freedom: their standard errors
    are NaN with 0 degrees of freedom (not statsmodels' ∞ with a divide-by-zero warning that a
    notebook user would see), and their intervals NaN, never (−∞, ∞) or a point; from four runs
    they are finite, with 2 degrees of freedom, and hold the curve's k2 and k1."""
    import warnings

    from towtank.analysis.scaling import scale_to_prototype
    from towtank.ingest.protocol import load_protocol
    from towtank.results import ScalingResult
    from towtank.results.summary import from_fit

    protocol = load_protocol(PROTOCOL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit, _ = scale_to_prototype(
            _straight_runs(speeds), protocol.model, protocol.prototype, scale=4.0,
            rho_m=998.6, nu_m=1.054e-6, rho_p=1025.9, nu_p=1.19e-6, laminar_re=5e5,
            damping_alpha_max_deg=10.0)
    assert fit is not None
    result = from_fit(ScalingResult, fit)
    ci = result.conf_int()
    if len(speeds) == 2:
        assert fit.resistance_dof == 0.0
        assert all(math.isnan(s) for s in fit.resistance_se)
        assert ci.loc[["k2", "k1"]].isna().all().all()
    else:
        assert fit.resistance_dof == 2.0
        assert all(0 < s < 1 for s in fit.resistance_se)
        assert ci.loc["k2", "lower"] < 12.0 < ci.loc["k2", "upper"]
        assert ci.loc["k1", "lower"] < 0.8 < ci.loc["k1", "upper"]
