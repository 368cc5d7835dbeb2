"""One results vocabulary in one package (issue #34, item 4).

Every result class lives in ``towtank.results``; the ones with estimates give ``params``,
``bse``, ``conf_int(alpha)`` (columns ``lower``, ``upper``), ``summary(alpha)`` (a
``Summary``) and ``to_frame()`` from their own numbers; DayResult's stage results are
``hull``, ``fins``, ``scaling``, ``vehicle``. The check across the real results (sample days,
an identification) is in tests/test_api.py; here each result is built from small numbers whose
intervals are known.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import subprocess
import sys
import typing
import warnings
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from towtank.analysis.hull import Estimate
from towtank.analysis.scaling import ScalingFit
from towtank.ingest.protocol import Fin
from towtank.pipeline import fin_stage
from towtank.results import (
    DayResult,
    Estimates,
    FinResult,
    HullResult,
    IdentifyResult,
    ScalingResult,
    Summary,
    TareResult,
    VehicleResult,
    from_fit,
)
from towtank.results.stages import FromPrediction
from towtank.vehicle.identify import IdentifyFit


def _identify_fit(sd: tuple[float, ...] = (0.1, 0.02)) -> IdentifyFit:
    k = len(sd)
    symbols = ["N_ur", "N_uudr", "M_uq"][:k]
    return IdentifyFit(symbols=symbols, start=np.zeros(k), value=np.array([-8.0, -13.0, 2.0][:k]),
                       sd=np.array(sd), prior_sd=np.full(k, 10.0), method="ukf",
                       covariance=np.diag(np.square(sd)),
                       check={"value": np.array([-8.05, -13.0, 2.0][:k]),
                              "sd": np.array([0.2, 0.03, 1.0][:k])})


def _day(**fields: object) -> DayResult:
    """A DayResult without runs: its stage results as given."""
    base = DayResult(protocol=SimpleNamespace(name="t"), sheet=pd.DataFrame(),  # type: ignore[arg-type]
                     reductions={}, rejected={}, tares={}, runs=pd.DataFrame())
    return dataclasses.replace(base, **fields)


# --------------------------------------------------------------------------------- one package
def test_every_result_class_lives_in_the_results_package():
    for cls in (DayResult, HullResult, FinResult, ScalingResult, TareResult, VehicleResult,
                IdentifyResult, Summary):
        assert cls.__module__.split(".")[:2] == ["towtank", "results"], cls
    for cls in (HullResult, FinResult, ScalingResult, TareResult, IdentifyResult):
        assert issubclass(cls, Estimates)
    import towtank

    assert towtank.FinResult is FinResult and towtank.ScalingResult is ScalingResult
    assert towtank.IdentifyResult is IdentifyResult


@pytest.mark.heavy
def test_the_results_of_a_day_and_simulate_load_no_identification():
    """IdentifyResult comes with the package's names, but the identification's filter loads
    only when it is asked for (a fresh interpreter: what an import loads is the point); nor
    does ``towtank simulate`` load it (its ``--noise`` is read by the manoeuvre record's
    module: the identification's imports were a third of simulate's 3.4 s)."""
    code = ("import sys, towtank.results, towtank.pipeline, towtank.commands.simulate\n"
            "assert 'filterpy' not in sys.modules, 'filterpy'\n"
            "assert 'towtank.vehicle.identify' not in sys.modules\n"
            "assert 'towtank.report.identify_figure' not in sys.modules\n"
            "from towtank.results import IdentifyResult\n"
            "assert 'filterpy' in sys.modules\n")
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120)


# -------------------------------------------------------------------------------- the estimate
def test_an_estimate_at_a_computed_five_percent_gives_its_stored_interval():
    """0.15 − 0.1 is 0.05 to within rounding, not exactly: still coefficients.csv's interval."""
    e = Estimate("X_udot", 1.0, 0.1, 0.7, 1.3, "m", 5, dof=5.0)
    assert 0.15 - 0.1 != 0.05
    assert e.conf_int(0.15 - 0.1) == (0.7, 1.3)
    assert e.conf_int(0.05) == (0.7, 1.3)
    lo, hi = e.conf_int(0.10)
    assert hi - lo == pytest.approx(2 * stats.t.ppf(0.95, 5.0) * 0.1, rel=1e-12)


# ---------------------------------------------------------------------------- identification
def test_an_identification_speaks_the_vocabulary_and_keeps_identified_csv():
    fit = _identify_fit()
    res = from_fit(IdentifyResult, fit)
    assert isinstance(res, IdentifyFit) and res.symbols == fit.symbols
    z = stats.norm.ppf(0.975)
    ci = res.conf_int()
    assert list(ci.columns) == ["lower", "upper"] and ci.index.name == "symbol"
    np.testing.assert_allclose(ci["lower"], fit.value - z * fit.sd, rtol=1e-15)
    pd.testing.assert_series_equal(res.params, pd.Series(
        fit.value, index=pd.Index(fit.symbols, name="symbol"), name="params"))
    assert list(res.bse) == list(fit.sd)
    ls = res.conf_int(0.10, "ls")
    np.testing.assert_allclose(ls["upper"], fit.check["value"] + stats.norm.ppf(0.95)
                               * fit.check["sd"], rtol=1e-15)
    table = res.table()  # identified.csv: its columns and numbers as before
    assert list(table.columns) == ["symbol", "start", "value", "ci_low", "ci_high", "method",
                                   "unit", "verdict", "agree"]
    first = table[table["method"] == "ukf"].set_index("symbol")
    np.testing.assert_array_equal(first["ci_low"], ci["lower"])
    np.testing.assert_array_equal(first["ci_high"], ci["upper"])
    pd.testing.assert_frame_equal(res.to_frame(), table)
    summary = res.summary(0.10)
    assert isinstance(summary, Summary)
    assert summary.notes == tuple(res.verdicts(0.10))
    assert "N_ur: identifiable" in str(summary)
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.notes = ("changed",)  # type: ignore[misc]


def test_an_unconstrained_coefficient_keeps_an_open_interval():
    res = from_fit(IdentifyResult, _identify_fit((0.1, math.inf)))
    ci = res.conf_int()
    assert math.isinf(ci.loc["N_uudr", "upper"]) and not res.identifiable()[1]


# ----------------------------------------------------------------------------------------- fins
def test_the_fin_lift_slopes_are_the_estimates_of_the_fin_result():
    """The lift slope of each speed group: the OLS fit of fin_curves.csv, with its standard
    error and residual degrees of freedom; conf_int(0.05) is fin_curves.csv's interval."""
    rng = np.random.default_rng(4)
    angles = np.repeat([-5.0, -2.5, 0.0, 2.5, 5.0, 7.5], 2)
    speed = np.repeat([0.8, 1.2], len(angles))
    alpha = np.tile(angles, 2)
    runs = pd.DataFrame({
        "run": range(1, len(alpha) + 1), "config": "fin", "status": "ok", "angle_deg": alpha,
        "speed_mean": speed, "re": speed * 1.2e5, "cl": 4.5 * np.deg2rad(alpha)
        + rng.normal(0, 0.01, len(alpha)), "cd": 0.02, "drag_mean": 0.01, "lift_mean": 0.01,
        "rho": 998.6})
    fins, _ = fin_stage(SimpleNamespace(fin=Fin(0.12, 0.15)), runs)  # type: ignore[arg-type]
    assert isinstance(fins, FinResult)
    assert list(fins.params.index) == ["lift_slope@0.80 m/s", "lift_slope@1.20 m/s"]
    curves = fins.curves
    np.testing.assert_allclose(fins.params, curves["lift_slope"], rtol=1e-12)
    ci = fins.conf_int()
    np.testing.assert_allclose(ci["lower"], curves["lift_slope_ci_low"], rtol=1e-9)
    np.testing.assert_allclose(ci["upper"], curves["lift_slope_ci_high"], rtol=1e-9)
    # 12 runs per group, a line with an intercept: 10 residual degrees of freedom
    assert list(fins.slopes["dof"]) == [10.0, 10.0]
    half = (curves["lift_slope_ci_high"] - curves["lift_slope_ci_low"]) / 2
    np.testing.assert_allclose(fins.bse, half / stats.t.ppf(0.975, 10), rtol=1e-9)
    assert fins.summary().table["unit"].tolist() == ["1/rad", "1/rad"]


# -------------------------------------------------------------------------------------- scaling
def test_the_resistance_curve_and_form_factor_are_the_estimates_of_the_scaling():
    fit = ScalingFit(table=pd.DataFrame({"speed_prototype": [1.0]}), resistance=(20.0, 1.5),
                     tested_speed_range=(0.5, 2.0), form_factor=None, statement="",
                     rho_p=1025.0, nu_p=1.19e-6, rho_m=998.0, nu_m=1.0e-6, scale=5.0,
                     resistance_se=(0.4, 0.2), resistance_dof=6.0)
    res = from_fit(ScalingResult, fit)
    assert list(res.params.index) == ["k2", "k1"] and list(res.params) == [20.0, 1.5]
    t = stats.t.ppf(0.95, 6.0)
    ci = res.conf_int(0.10)
    assert ci.loc["k2"].tolist() == pytest.approx([20.0 - t * 0.4, 20.0 + t * 0.4], rel=1e-12)
    pd.testing.assert_frame_equal(res.to_frame(), fit.table)


# -------------------------------------------------------------------------------------- vehicle
def test_the_vehicle_result_gives_the_prediction_by_typed_properties_only():
    prediction = SimpleNamespace(predicted=pd.DataFrame({"symbol": ["X_udot"]}), model={"a": 1},
                                 profile="hull", masses={}, rho=1025.0, nu=1.2e-6,
                                 powering=None, pressure_hull=None, something_else=1)
    vr = VehicleResult(prediction=prediction)  # type: ignore[arg-type]
    assert vr.model == {"a": 1} and vr.rho == 1025.0 and vr.predicted is prediction.predicted
    with pytest.raises(AttributeError):
        vr.something_else  # noqa: B018  (nothing is forwarded that is not declared)
    assert "__getattr__" not in vars(VehicleResult)
    for name in ("predicted", "model", "profile", "masses", "rho", "nu", "powering",
                 "pressure_hull"):
        field = inspect.getattr_static(VehicleResult, name)
        assert isinstance(field, FromPrediction), name
        assert typing.get_args(field.__orig_class__)[0] is not typing.Any, name
        assert getattr(vr, name) is getattr(prediction, name)
    with pytest.raises(dataclasses.FrozenInstanceError):
        vr.rho = 1.0  # type: ignore[misc]


# ------------------------------------------------------------------------------ the day's names
def test_the_day_names_its_stage_results_evenly():
    names = [f.name for f in dataclasses.fields(DayResult)]
    assert {"hull", "fins", "scaling", "vehicle"} <= set(names)
    assert not {"fin_result", "scaling_result"} & set(names)
    fit = ScalingFit(table=pd.DataFrame({"speed_prototype": [1.0, 2.0]}), resistance=(2.0, 1.0),
                     tested_speed_range=(0.5, 2.0), form_factor=None, statement="",
                     rho_p=1025.0, nu_p=1.19e-6, rho_m=998.0, nu_m=1.0e-6, scale=5.0)
    day = _day(scaling=from_fit(ScalingResult, fit))
    assert day.fins is None and isinstance(day.scaling, ScalingResult)
    pd.testing.assert_frame_equal(day.table("scaling"), day.scaling.table)
    assert day.table("scaling") is not day.scaling.table  # a copy to edit
    empty = day.table("fins")  # fins.csv with its header on a day without fins
    assert empty.empty and list(empty.columns)[:2] == ["run", "angle_deg"]
    with pytest.raises(ValueError, match="'fins' or 'scaling'"):
        day.table("coefficients")  # type: ignore[arg-type]
    assert "stages: scaling" in repr(day)


def test_the_former_names_of_the_stage_results_still_work_and_warn():
    day = _day()
    with pytest.warns(DeprecationWarning, match="DayResult.fins"):
        assert day.fin_result is None
    with pytest.warns(DeprecationWarning, match="DayResult.scaling"):
        assert day.scaling_result is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert day.fins is None and day.scaling is None  # the new names say nothing


# ----------------------------------------------------------------------------------------- tare
def test_the_tare_coefficients_are_the_estimates_of_the_tare_and_give_tare_csv():
    from towtank.reduce.tare import TareFit, TareModel

    drag = TareFit(coef=np.array([0.5, 0.1, 0.2]), cov=np.diag([1e-4, 4e-4, 9e-4]),
                   residual_std=0.01, n_samples=400, dof=4.0)
    lift = TareFit(coef=np.array([0.05, 0.0, 0.0]), cov=np.diag([1e-6, 0.0, 1e-6]),
                   residual_std=0.01, n_samples=400)
    tare = TareResult({"A": TareModel("A", (1, 2), drag, lift, (0.5, 2.0), (0.0, 0.3))})
    assert list(tare.params.index) == ["A.drag.t2", "A.drag.t1", "A.drag.m_t", "A.lift.t2",
                                       "A.lift.t1", "A.lift.m_t"]
    assert tare.bse["A.drag.t1"] == pytest.approx(0.02)
    ci, csv = tare.conf_int(), tare.to_frame().set_index("channel")
    for channel in ("drag", "lift"):
        for term in ("t2", "t1", "m_t"):
            assert ci.loc[f"A.{channel}.{term}"].tolist() == pytest.approx(
                [csv.loc[channel, f"{term}_ci_low"], csv.loc[channel, f"{term}_ci_high"]],
                rel=1e-12), (channel, term)
    assert tare.summary().table["unit"].tolist()[:3] == ["N s²/m²", "N s/m", "kg"]
