"""`towtank identify` tells a record its model did not make (#36): the innovations' whiteness,
the normalised innovation squared and the held-out (or --validate) re-simulation, fit.csv,
the verdict `model does not fit` and exit 1; identify's trim sentence.

The mismatched records of the issue: a sine-rudder record made by REMUS predicted with
``added_mass = damping = fin_lift = "prestero"`` identified with the default prediction (old
code: N_ur of the wrong sign, every verdict `identifiable`, exit 0), and a record made neutral
(``net_buoyancy_n = 0``) identified with the 7 N buoyant model (old code: N_rdot 65 % off,
`identifiable`, exit 0).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.commands.cli import main
from towtank.vehicle.adequacy import adequacy_table, failure_sentence
from towtank.vehicle.identify import identify
from towtank.vehicle.identify_log import log_from_frame
from towtank.vehicle.simulate import simulate

REPO = Path(__file__).resolve().parents[1]
PAPER = ["N_ur", "N_rdot", "N_uudr"]
NOISE = {"u_m_s": 0.01, "v_m_s": 0.01, "r_deg_s": 0.2, "psi_deg": 0.5, "x_m": 0.05, "y_m": 0.05}
KEEP = ["t_s", "x_m", "y_m", "psi_deg", "u_m_s", "v_m_s", "r_deg_s", "rudder_deg",
        "sternplane_deg"]


def _predict(tmp: Path, extra: str = "") -> dict:
    text = (REPO / "protocols" / "remus_vehicle.toml").read_text()
    text = text.replace('fin_limit_deg = 20.0', 'fin_limit_deg = 20.0\n' + extra)
    (tmp / "p.toml").write_text(text)
    assert main(["predict", str(tmp / "p.toml"), "--out", str(tmp / "p")]) == 0
    return json.loads((tmp / "p" / "model.json").read_text())


@pytest.fixture(scope="module")
def models(tmp_path_factory) -> dict[str, dict]:
    """REMUS as shipped (7 N buoyant), the same neutral, and Prestero's reading neutral."""
    buoyant = _predict(tmp_path_factory.mktemp("remus"))
    prestero = _predict(tmp_path_factory.mktemp("prestero"), 'added_mass = "prestero"\n'
                        'damping = "prestero"\nfin_lift = "prestero"\n')
    neutral = dict(buoyant, buoyancy_N=buoyant["weight_N"])
    prestero["buoyancy_N"] = prestero["weight_N"]
    return {"buoyant": buoyant, "neutral": neutral, "prestero": prestero}


def _record(model: dict, seed: int, duration_s: float = 30.0, **kw) -> pd.DataFrame:
    """A sine-rudder record (10 deg, 10 s, 1.5 m/s, 10 Hz), white noise on the paper's
    measured states, only those columns kept."""
    clean = simulate(model, "sine", 1.5, rudder_deg=10.0, period_s=10.0,
                     duration_s=duration_s, sample_hz=10.0, **kw)
    rng = np.random.default_rng(seed)
    df = clean[KEEP].copy()
    for col, sd in NOISE.items():
        df[col] = df[col] + rng.normal(0.0, sd, len(df))
    return df


def _run(tmp: Path, model: dict, record: pd.DataFrame, *more: str) -> int:
    (tmp / "m").mkdir(exist_ok=True)
    (tmp / "m" / "model.json").write_text(json.dumps(model))
    record.to_csv(tmp / "log.csv", index=False)
    return main(["identify", str(tmp / "m" / "model.json"), str(tmp / "log.csv"), "--estimate",
                 ",".join(PAPER), "--out", str(tmp / "id"), "--quiet", *more])


def test_a_record_of_another_prediction_does_not_fit(models, tmp_path, capsys):
    """The Prestero-reading record identified with the default model: exit 1, every verdict
    `model does not fit` (old code: `identifiable`, N_ur of the wrong sign, exit 0), one
    sentence naming the worst test and by how much, fit.csv beside the other outputs."""
    assert _run(tmp_path, models["neutral"], _record(models["prestero"], 7)) == 1
    out, err = capsys.readouterr()
    tab = pd.read_csv(tmp_path / "id" / "identified.csv")
    assert (tab["verdict"] == "model does not fit").all()
    assert "identifiable" not in out
    said = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(said) == 1 and "does not fit the record" in said[0] and "times its threshold" \
        in said[0]
    fit = pd.read_csv(tmp_path / "id" / "fit.csv")
    assert list(fit.columns) == ["test", "state", "statistic", "threshold", "passed"]
    assert set(fit["test"]) == {"whiteness", "nis", "holdout"}
    assert set(fit["state"]) == set(NOISE)
    assert not fit["passed"].all()
    worst = fit.loc[(fit["statistic"] / fit["threshold"]).idxmax()]
    assert str(worst["state"]) in said[0]
    assert (tmp_path / "id" / "model.json").exists()


def test_a_neutral_record_does_not_fit_the_buoyant_model(models):
    """A record made neutral, identified with the 7 N buoyant model (old code: N_rdot 65 %
    off, `identifiable`): the record does not fit."""
    log = log_from_frame(_record(models["buoyant"], 8, net_buoyancy_n=0.0), "neutral")
    res = identify(models["buoyant"], log, PAPER)
    assert not res.fits()
    assert not res.adequacy["passed"].all()


def test_a_record_the_model_made_fits_and_exits_0(models, tmp_path, capsys):
    assert _run(tmp_path, models["neutral"], _record(models["neutral"], 9)) == 0
    out, err = capsys.readouterr()
    fit = pd.read_csv(tmp_path / "id" / "fit.csv")
    assert fit["passed"].all() and len(fit) == 18
    tab = pd.read_csv(tmp_path / "id" / "identified.csv")
    assert (tab["verdict"] == "identifiable").all()
    assert "error:" not in err
    assert "trim: the model is in trim at 1." in err


def test_validate_tests_against_a_second_record(models, tmp_path, capsys):
    """--validate LOG2: the model is simulated along the second record; one of another model
    fails `validation`."""
    models_path = tmp_path / "other.csv"
    _record(models["prestero"], 3, duration_s=20.0).to_csv(models_path, index=False)
    code = _run(tmp_path, models["neutral"], _record(models["neutral"], 10), "--method", "ls",
                "--validate", str(models_path))
    fit = pd.read_csv(tmp_path / "id" / "fit.csv")
    assert code == 1
    rows = fit[fit["test"] == "validation"]
    assert len(rows) == 6 and not rows["passed"].any()
    assert fit[fit["test"] != "validation"]["passed"].all()  # the record itself fits
    capsys.readouterr()


def test_identify_says_the_buoyant_model_is_out_of_trim(models, tmp_path, capsys):
    """identify checks trim as simulate does (the 7 N buoyant REMUS rises with zero
    controls): one warning sentence, the same as simulate's."""
    from towtank.commands.identify import trim_sentence
    from towtank.vehicle.identify import record_speed
    from towtank.vehicle.simulate import trim_warning

    log = log_from_frame(_record(models["neutral"], 1, duration_s=5.0), "short")
    said = trim_sentence(models["buoyant"], log)
    warning = trim_warning(models["buoyant"], record_speed(models["buoyant"], log))
    assert warning is not None and said == f"warning: {warning}"
    assert said.startswith("warning: the model is out of trim") and "\n" not in said
    assert trim_sentence(models["neutral"], log).startswith("trim: the model is in trim")


def test_the_tests_on_white_and_coloured_innovations():
    """White unit innovations pass; a slow correlated error fails the whiteness test; twice
    the noise fails the normalised innovation squared; the sentence names the worst."""
    rng = np.random.default_rng(0)
    n = 1000
    e = np.full((n, 12), np.nan)
    e[:, [0, 1, 5]] = rng.normal(size=(n, 3))
    table = adequacy_table(e, e[-200:])
    assert table["passed"].all() and len(table) == 9
    assert failure_sentence(table) is None
    bad = e.copy()
    bad[:, 5] += 0.8 * np.sin(np.arange(n) / 30.0)
    bad[:, 1] *= 2.0
    table = adequacy_table(bad, None).set_index(["test", "state"])
    assert not table.loc[("whiteness", "psi_deg"), "passed"]
    assert not table.loc[("nis", "y_m"), "passed"]
    assert table.loc[("nis", "x_m"), "passed"]
    said = failure_sentence(table.reset_index())
    assert said is not None and "\n" not in said and said.endswith(".")
