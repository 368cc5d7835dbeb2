"""The protocol loader (docs/formats.md §1): the shipped example, path resolution, and every kind of
mistake a lab makes in a TOML file, each a ProtocolError of one sentence naming what is wrong."""

from __future__ import annotations

import copy
import datetime as dt
import math
import tomllib
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from towtank.commands import cli
from towtank.errors import ProtocolError
from towtank.ingest.protocol import SCHEMA, TOP_LEVEL, load_protocol

# docs/formats.md §1, verbatim
FORMATS_EXAMPLE = '''\
[campaign]
name = "SUT-2 quarter-scale hull, day 1"
run_sheet = "../sample_runs/sut2_hull/run_sheet.xlsx"   # .xlsx or .csv
data_dir = "../sample_runs/sut2_hull/data"
output_dir = "../reports/sut2_hull"       # optional; default reports/<slug of name>
reference = "remus"                       # optional: built-in set, or path to a CSV (symbol,prime)

[water]                                   # the tank
type = "fresh"                            # fresh | sea
temperature_C = 18.0                      # default for runs whose sheet gives none

[model]                                   # the captive hull; optional if the day has only fin runs
name = "SUT-2 1/4 model"
length_m = 0.353                          # overall length L (the reference length)
diameter_m = 0.050                        # frontal area A = pi D^2 / 4 unless frontal_area_m2 given
mass_kg = 0.552                           # weighed mass, everything downstream of the balance but the sting
lateral_area_m2 = 0.0152                  # optional: projected side area for transverse tows; default L*D
wetted_area_m2 = 0.0472                   # optional: for friction-line scaling
scale = 4.0                               # lambda = L_prototype / L_model

[fin]                                     # a control surface tested on its own; optional
chord_m = 0.12
span_m = 0.15
section = "NACA0015"

[prototype]                               # optional: full-size vehicle to scale to
length_m = 1.412                          # default: model length * scale
speeds_m_s = [1.0, 1.5, 2.0, 2.5]
[prototype.water]
type = "sea"
temperature_C = 15.0

[channels]                                # optional: map lab column names to canonical channels
time  = { column = "Time (s)" }
speed = { column = "Carriage speed (m/s)" }
drag  = { column = "Fx load cell (V)", gain = 20.0, offset = 0.0 }   # value = gain*(raw - offset)
lift  = { column = "Fy load cell (V)", gain = -25.0 }

[processing]                              # optional knobs, all with sensible defaults
# e.g. cutoff frequency of the zero-phase low-pass filter, zero-window length
'''  # noqa: E501


def _layout(root: Path) -> Path:
    """root/protocols/ (the protocol's folder) and root/sample_runs/sut2_hull/{sheet, data/}."""
    (root / "protocols").mkdir(parents=True, exist_ok=True)
    day = root / "sample_runs" / "sut2_hull"
    (day / "data").mkdir(parents=True, exist_ok=True)
    (day / "run_sheet.xlsx").write_bytes(b"")  # the loader only checks that it exists
    (day / "run_sheet.csv").write_text("run,file,config,angle_deg\n")
    return root / "protocols"


# ------------------------------------------------------------------------------ TOML writer
def _esc(text: str) -> str:
    out = []
    for ch in text:
        if ch == "\\":
            out.append("\\\\")
        elif ch == '"':
            out.append('\\"')
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _val(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _esc(v)
    if isinstance(v, dt.datetime | dt.date):
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(_val(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_esc(k)} = {_val(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def dump_toml(data: dict[str, Any]) -> str:
    """Any dict of TOML-able values as TOML (sub-tables as inline tables, keys quoted)."""
    lines = [f"{_esc(k)} = {_val(v)}" for k, v in data.items() if not isinstance(v, dict)]
    for k, v in data.items():
        if isinstance(v, dict):
            lines.append(f"[{_esc(k)}]")
            lines += [f"{_esc(kk)} = {_val(vv)}" for kk, vv in v.items()]
    return "\n".join(lines) + "\n"


def _base() -> dict[str, Any]:
    return tomllib.loads(FORMATS_EXAMPLE)


def _write(folder: Path, data: dict[str, Any], name: str = "p.toml") -> Path:
    path = folder / name
    path.write_text(dump_toml(data), encoding="utf-8")
    return path


def _error(folder: Path, data: dict[str, Any]) -> str:
    path = _write(folder, data)
    with pytest.raises(ProtocolError) as info:
        load_protocol(path)
    msg = str(info.value)
    assert "\n" not in msg.strip() and "Traceback" not in msg
    assert path.name in msg  # the sentence names the file
    return msg


@pytest.fixture
def folder(tmp_path) -> Path:
    return _layout(tmp_path)


# ------------------------------------------------------------------------- the FORMATS example
def test_formats_example_parses_and_resolves_paths(tmp_path, monkeypatch):
    folder = _layout(tmp_path)
    path = folder / "sut2.toml"
    path.write_text(FORMATS_EXAMPLE, encoding="utf-8")
    elsewhere = tmp_path / "cwd"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)  # paths are relative to the protocol, not to the cwd
    p = load_protocol(path)
    root = tmp_path.resolve()
    assert p.name == "SUT-2 quarter-scale hull, day 1"
    assert p.campaign.run_sheet == root / "sample_runs" / "sut2_hull" / "run_sheet.xlsx"
    assert p.campaign.data_dir == root / "sample_runs" / "sut2_hull" / "data"
    assert p.campaign.output_dir == root / "reports" / "sut2_hull"
    assert p.campaign.reference == "remus"
    assert (p.water.type, p.water.temperature_C) == ("fresh", 18.0)
    m = p.model
    assert (m.length_m, m.diameter_m, m.mass_kg, m.scale) == (0.353, 0.05, 0.552, 4.0)
    assert m.frontal_area == pytest.approx(math.pi * 0.05**2 / 4)
    assert m.lateral_area == 0.0152 and m.wetted_area_m2 == 0.0472
    assert p.fin.area == pytest.approx(0.12 * 0.15)
    assert p.prototype.length_m == 1.412
    assert p.prototype.speeds_m_s == (1.0, 1.5, 2.0, 2.5)
    assert (p.prototype.water.type, p.prototype.water.temperature_C) == ("sea", 15.0)
    assert p.channels["lift"].gain == -25.0 and p.channels["lift"].offset == 0.0
    assert p.channels["drag"].column == "Fx load cell (V)" and p.channels["drag"].gain == 20.0
    assert p.channels["time"].column == "Time (s)" and p.channels["time"].gain == 1.0
    assert p.processing.cutoff_hz > 0
    assert p.warnings == ()


def test_optional_sections_and_defaults(folder):
    data = _base()
    for section in ("fin", "prototype", "channels", "processing"):
        del data[section]
    del data["campaign"]["output_dir"]
    del data["model"]["lateral_area_m2"]
    p = load_protocol(_write(folder, data))
    assert p.fin is None and p.prototype is None and p.channels == {}
    assert p.model.lateral_area == pytest.approx(0.353 * 0.05)  # default L*D
    slug = "sut_2_quarter_scale_hull_day_1"  # documented: under the current directory
    assert p.campaign.output_dir == Path.cwd().resolve() / "reports" / slug


def test_default_prototype_length_from_scale(folder):
    data = _base()
    del data["prototype"]["length_m"]
    p = load_protocol(_write(folder, data))
    assert p.prototype.length_m == pytest.approx(0.353 * 4.0)


# ---------------------------------------------------------------------------------- mistakes
@pytest.mark.parametrize(
    "section, wrong, right",
    [
        ("model", "lenght_m", "length_m"),
        ("model", "diamter_m", "diameter_m"),
        ("water", "temperature_c", "temperature_C"),
        ("campaign", "run_shet", "run_sheet"),
        ("fin", "chord", "chord_m"),
        ("processing", "cutoff_Hz", "cutoff_hz"),
    ],
)
def test_unknown_key_names_it_and_suggests_nearest(folder, section, wrong, right):
    data = _base()
    value = data[section].pop(right, 1.0)
    data[section][wrong] = value
    msg = _error(folder, data)
    assert f"'{wrong}'" in msg
    assert f"[{section}]" in msg
    assert f"did you mean '{right}'" in msg


def test_unknown_key_in_a_channel_table(folder):
    data = _base()
    data["channels"]["lift"]["gian"] = data["channels"]["lift"].pop("gain")
    msg = _error(folder, data)
    assert "'gian'" in msg and "did you mean 'gain'" in msg and "channels.lift" in msg


def test_unknown_channel_name(folder):
    data = _base()
    data["channels"]["thrust"] = {"column": "Fz (V)"}
    msg = _error(folder, data)
    assert "'thrust'" in msg and "[channels]" in msg


@pytest.mark.parametrize("wrong, right", [("modle", "model"), ("Water", "water"),
                                          ("chanels", "channels")])
def test_unknown_section(folder, wrong, right):
    data = _base()
    data[wrong] = data.pop(right)
    if right == "water":
        data.pop("water", None)
    msg = _error(folder, data)
    assert f"unknown section [{wrong}]" in msg
    assert f"did you mean '{right}'" in msg


@pytest.mark.parametrize(
    "section, key",
    [("model", "mass_kg"), ("model", "length_m"), ("campaign", "run_sheet"),
     ("campaign", "name"), ("water", "temperature_C"), ("fin", "span_m")],
)
def test_missing_required_key(folder, section, key):
    data = _base()
    del data[section][key]
    msg = _error(folder, data)
    assert f"'{key}'" in msg and f"[{section}]" in msg and "missing" in msg


@pytest.mark.parametrize("section", ["campaign", "water"])
def test_missing_required_section(folder, section):
    data = _base()
    del data[section]
    msg = _error(folder, data)
    assert f"[{section}]" in msg and "missing" in msg


def test_model_or_fin_needed(folder):
    data = _base()
    del data["model"], data["fin"], data["prototype"]
    msg = _error(folder, data)
    assert "[model]" in msg and "[fin]" in msg


@pytest.mark.parametrize(
    "section, key, value, words",
    [
        ("model", "length_m", "0.353", "a number"),
        ("model", "mass_kg", True, "a number"),
        ("water", "temperature_C", False, "a number"),
        ("fin", "chord_m", [0.12], "a number"),
        ("model", "diameter_m", math.nan, "a number"),
        ("model", "length_m", math.inf, "a number"),
        ("prototype", "speeds_m_s", "1.0, 1.5", "a list of numbers"),
        ("prototype", "speeds_m_s", [1.0, True], "a list of numbers"),
        ("processing", "filter_order", 4.5, "a whole number"),
        ("processing", "despike", 1, "true or false"),
        ("campaign", "name", 42, "a text string"),
        ("campaign", "run_sheet", "", "a path"),
        ("water", "type", 1, "a text string"),
    ],
)
def test_wrong_type(folder, section, key, value, words):
    data = _base()
    data[section][key] = value
    msg = _error(folder, data)
    assert f"'{key}' in [{section}]" in msg
    assert f"must be {words}" in msg


def test_string_for_a_number_quotes_the_value(folder):
    data = _base()
    data["model"]["length_m"] = "0.353 m"
    msg = _error(folder, data)
    assert "'0.353 m'" in msg and "must be a number" in msg


@pytest.mark.parametrize(
    "section, key, value",
    [("model", "length_m", -0.353), ("model", "mass_kg", 0.0), ("fin", "span_m", -1.0),
     ("prototype", "speeds_m_s", [1.0, -2.0]), ("processing", "cutoff_hz", 0.0)],
)
def test_non_positive_values(folder, section, key, value):
    data = _base()
    data[section][key] = value
    msg = _error(folder, data)
    assert key in msg and "positive" in msg


def test_zero_gain_rejected(folder):
    data = _base()
    data["channels"]["drag"]["gain"] = 0.0
    msg = _error(folder, data)
    assert "gain" in msg and "channels.drag" in msg


@pytest.mark.parametrize("value, suggestion", [("Fresh water", "fresh"), ("see", "sea")])
def test_water_type_must_be_known(folder, value, suggestion):
    data = _base()
    data["water"]["type"] = value
    msg = _error(folder, data)
    assert "fresh" in msg and "sea" in msg


def test_nonexistent_run_sheet(folder):
    data = _base()
    data["campaign"]["run_sheet"] = "../sample_runs/sut2_hull/run_sheet_day2.xlsx"
    msg = _error(folder, data)
    assert "run sheet" in msg and "run_sheet_day2.xlsx" in msg and "does not exist" in msg


def test_run_sheet_of_another_kind(folder):
    (folder / "sheet.txt").write_text("run,file\n")
    data = _base()
    data["campaign"]["run_sheet"] = "sheet.txt"
    msg = _error(folder, data)
    assert ".csv" in msg and ".xlsx" in msg


def test_nonexistent_data_dir(folder):
    data = _base()
    data["campaign"]["data_dir"] = "../sample_runs/sut2_hull/dta"
    msg = _error(folder, data)
    assert "data folder" in msg and "dta" in msg and "does not exist" in msg


def test_nonexistent_reference_csv(folder):
    data = _base()
    data["campaign"]["reference"] = "remus.csv"
    msg = _error(folder, data)
    assert "remus.csv" in msg and "reference" in msg


def test_protocol_file_missing_or_not_toml(folder):
    with pytest.raises(ProtocolError, match="does not exist"):
        load_protocol(folder / "nope.toml")
    bad = folder / "bad.toml"
    bad.write_text("[campaign\nname = 'x'\n")
    with pytest.raises(ProtocolError, match="not valid TOML"):
        load_protocol(bad)


# ---------------------------------------------------------------------- unit plausibility
def test_length_in_millimetres_warns(folder):
    data = _base()
    data["model"]["length_m"] = 353.0
    data["prototype"]["length_m"] = 1412.0
    p = load_protocol(_write(folder, data))
    assert p.model.length_m == 353.0
    text = " ".join(p.warnings)
    assert "length_m = 353" in text and "mm" in text
    assert "length/diameter" in text  # L/D = 7060 is not a hull either


@pytest.mark.parametrize(
    "section, key, value, hint",
    [("model", "diameter_m", 50.0, "mm"),
     ("water", "temperature_C", 45.0, "K or °F"), ("fin", "chord_m", 120.0, "mm")],
)
def test_other_unit_warnings(folder, section, key, value, hint):
    data = _base()
    data[section][key] = value
    p = load_protocol(_write(folder, data))
    assert any(key in w and hint in w for w in p.warnings), p.warnings


@pytest.mark.parametrize("key, value, ratio", [
    ("wetted_area_m2", 472.0, 8512.0),  # the FORMATS example's 0.0472 m² typed in cm²
    ("frontal_area_m2", 19.6, 9982.0),
    ("lateral_area_m2", 152.0, 8612.0),
    ("wetted_area_m2", 0.00472, 0.0851),  # a slip the other way
])
def test_areas_in_other_units_warn(folder, key, value, ratio):
    """An area that no hull of the model's length and diameter (0.353 m, 0.05 m) has: one
    sentence naming the key, its ratio to π·D·L, π·D²/4 or L·D and the likely unit; the
    FORMATS example's own values (0.85, 1.0, 0.86 times) give none. (A volume in other units
    stops the protocol through the mass check.)"""
    data = _base()
    assert not any(k in w for w in load_protocol(_write(folder, data)).warnings
                   for k in ("_area_m2",))
    data["model"][key] = value
    p = load_protocol(_write(folder, data))
    said = [w for w in p.warnings if f"[model] {key} = {value:g}" in w]
    assert len(said) == 1, p.warnings
    assert f"is {ratio:.3g} times" in said[0] and "was it given in" in said[0]


@pytest.mark.parametrize("value, hint", [(291.15, "kelvin (18.0 °C)"), (100.0, "°F (37.8 °C)"),
                                         (180.0, "a typo for 18"), (-273.16, ""),
                                         (1e300, "not a water temperature")])
def test_water_that_is_not_liquid_stops_the_day(folder, value, hint):
    """A protocol temperature at which there is no liquid water (a kelvin or °F value, a lost
    decimal point, absolute zero) is exit 2 with the likely slip, not an IAPWS error (exit 3)."""
    data = _base()
    data["water"]["temperature_C"] = value
    with pytest.raises(ProtocolError, match=r"'temperature_C' in \[water\]") as err:
        load_protocol(_write(folder, data))
    assert hint in str(err.value)


@pytest.mark.parametrize("mass, unit", [(552.0, "grams"), (0.000552, "tonnes")])
def test_mass_in_other_units_stops_the_day(folder, mass, unit):
    """mass_kg = 552 for a 0.353 m × 50 mm hull (it displaces about 0.55 kg of water): the
    mass was typed in grams; it would make X_udot = +551 kg. Exit 2, naming the unit."""
    data = _base()
    data["model"]["mass_kg"] = mass
    with pytest.raises(ProtocolError, match=f"mass_kg = {mass:g} is .* was it given in {unit}"):
        load_protocol(_write(folder, data))
    data["model"]["mass_kg"] = 0.552 * 7.8  # a solid steel body of that size is fine
    load_protocol(_write(folder, data))


def test_cli_exit_2_and_nothing_written_for_an_unusable_protocol(folder, capsys):
    data = _base()
    data["model"]["lenght_m"] = data["model"].pop("length_m")
    path = _write(folder, data)
    out = folder / "out"
    assert cli.main(["process", str(path), "--no-report", "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert "did you mean 'length_m'" in err and "Traceback" not in err


# ------------------------------------------------------------------------ [prototype] checks
def test_prototype_length_must_match_model_length_times_scale(folder):
    data = _base()
    data["prototype"]["length_m"] = 2.0  # L_m x scale = 0.353 x 4 = 1.412 m
    msg = _error(folder, data)
    assert "length_m = 2 m" in msg and "1.412" in msg and "0.353" in msg and "scale" in msg
    data["prototype"]["length_m"] = 1.412 * 1.009  # within 1 %: accepted
    assert load_protocol(_write(folder, data)).prototype.length_m == pytest.approx(1.4247, 1e-4)


@pytest.mark.parametrize("delta_cf", [0.0021, -0.0021, 0.4, -5.0])
def test_absurd_roughness_allowance_is_refused(folder, delta_cf):
    data = _base()
    data["prototype"]["delta_cf"] = delta_cf
    msg = _error(folder, data)
    assert "delta_cf" in msg and "[prototype]" in msg and "0.002" in msg


@pytest.mark.parametrize("delta_cf", [0.0004, -0.0002, 0.002])
def test_plausible_roughness_allowance_is_kept(folder, delta_cf):
    data = _base()
    data["prototype"]["delta_cf"] = delta_cf
    assert load_protocol(_write(folder, data)).prototype.delta_cf == delta_cf


@pytest.mark.parametrize(
    "key, value, words",
    [("temperature_C", 45.0, "temperature_C = 45"), ("temperature_C", -1.5, "temperature_C = -1.5"),
     ("salinity_g_kg", 350.0, "salinity_g_kg = 350")],
)
def test_prototype_water_outside_the_ittc_range_warns(folder, key, value, words):
    data = _base()
    data["prototype"]["water"][key] = value
    p = load_protocol(_write(folder, data))
    hits = [w for w in p.warnings if "[prototype.water]" in w]
    assert len(hits) == 1 and words in hits[0] and "extrapolated" in hits[0], p.warnings
    data["prototype"]["water"][key] = 15.0 if key == "temperature_C" else 35.0
    assert load_protocol(_write(folder, data)).warnings == ()


def test_salinity_given_for_fresh_water_is_refused(folder):
    data = _base()
    data["prototype"]["water"] = {"type": "fresh", "temperature_C": 15.0, "salinity_g_kg": 35.0}
    msg = _error(folder, data)
    assert "[prototype.water]" in msg and "salinity_g_kg" in msg and "sea" in msg


def test_model_geometry_lists_each_quantity_with_its_source(folder):
    from towtank.ingest.protocol import model_geometry

    data = _base()
    del data["model"]["lateral_area_m2"]
    p = load_protocol(_write(folder, data))
    rows = {g["symbol"]: g for g in model_geometry(p.model, 4.0)}
    assert rows["A"]["value"] == pytest.approx(math.pi * 0.05**2 / 4)
    assert "π D²/4" in rows["A"]["source"]
    assert rows["A_lat"]["value"] == pytest.approx(0.353 * 0.05)
    assert "L·D" in rows["A_lat"]["source"]
    assert rows["S_m"]["value"] == 0.0472 and "wetted_area_m2" in rows["S_m"]["source"]
    assert rows["V"]["value"] is None and "not known" in rows["V"]["source"]
    assert rows["S_p"]["value"] == pytest.approx(0.0472 * 16) and "λ²" in rows["S_p"]["source"]
    assert "S_p" not in {g["symbol"] for g in model_geometry(p.model)}


# ------------------------------------------------------------------------------- fuzzing
KNOWN_PATHS: list[tuple[str, ...]] = [(s,) for s in TOP_LEVEL]
for _name, _keys in SCHEMA.items():
    _prefix = tuple(_name.split("."))
    if _prefix[0] == "channel":
        for _ch in SCHEMA["channels"]:
            KNOWN_PATHS += [("channels", _ch, k) for k in _keys]
        continue
    KNOWN_PATHS += [(*_prefix, k) for k in _keys]

_text = st.text(max_size=12)
_scalars = st.one_of(
    st.booleans(),
    st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -1.0, 1e-9, 0.353, 1e300, 4.0]),
    _text,
    st.sampled_from(["", "..", "/", ".", "run_sheet.csv", "remus", "fresh", "sea",
                     "NACA0015", "wall", "a" * 300, "data/../data"]),
    st.dates(),
)
_values = st.recursive(
    _scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.dictionaries(st.one_of(_text, st.sampled_from(["column", "gain", "offset",
                                                           "type", "temperature_C"])),
                        inner, max_size=4),
    ),
    max_leaves=8,
)
_paths = st.one_of(
    st.sampled_from(KNOWN_PATHS),
    st.tuples(st.sampled_from(list(TOP_LEVEL) + ["bogus"]), _text),
    st.tuples(_text),
)
DELETE = object()
_mutations = st.lists(st.tuples(_paths, st.one_of(_values, st.just(DELETE))), max_size=6)


def _apply(data: dict[str, Any], mutations) -> dict[str, Any]:
    data = copy.deepcopy(data)
    for path, value in mutations:
        node = data
        for key in path[:-1]:
            if not isinstance(node.get(key), dict):
                node[key] = {}
            node = node[key]
        if value is DELETE:
            node.pop(path[-1], None)
        else:
            node[path[-1]] = value
    return data


@pytest.fixture(scope="session")
def fuzz_folder(tmp_path_factory) -> Path:
    return _layout(tmp_path_factory.mktemp("fuzz"))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations=_mutations)
@example(mutations=[])
# a NUL character (TOML "\u0000") in a path: the loader must say so, not crash
@example(mutations=[(("campaign", "output_dir"), "out\x00put")])
@example(mutations=[(("campaign", "run_sheet"), "sheet\x00.csv")])
# a path component longer than the file system allows (ENAMETOOLONG)
@pytest.mark.heavy
@example(mutations=[(("campaign", "run_sheet"), "a" * 300 + ".csv")])
@example(mutations=[(("campaign", "data_dir"), "d" * 300)])
def test_fuzz_protocol_loads_or_raises_protocol_error(fuzz_folder, mutations):
    """Random keys and values in random sections: the loader either returns a Protocol or
    raises ProtocolError -- never any other exception (which would reach the user as a
    traceback or as exit status 3 instead of 2)."""
    data = _apply(_base(), mutations)
    path = fuzz_folder / "fuzz.toml"
    path.write_text(dump_toml(data), encoding="utf-8")
    assert tomllib.loads(path.read_text(encoding="utf-8")) is not None  # valid TOML written
    try:
        p = load_protocol(path)
    except ProtocolError as exc:
        assert str(exc).strip()
    else:
        assert p.model is not None or p.fin is not None
        if p.model is not None:
            assert p.model.length_m > 0 and p.model.mass_kg > 0 and p.model.frontal_area > 0
