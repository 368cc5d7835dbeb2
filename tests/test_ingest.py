"""Ingest checks, one by one, on bytes and arrays: each damage is found, said in one sentence
that names the file, what is wrong and where (rows as a text editor counts them, header = row
1; times in s), and repaired where that is safe; good realistic data pass untouched."""

from __future__ import annotations

import gzip
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from towtank.errors import RunError
from towtank.ingest.protocol import ChannelMap
from towtank.ingest.runfile import (
    check_clipping,
    despike,
    file_bytes,
    load_run,
    read_csv_columns,
    time_base,
)
from towtank.testing import damage, synthetic

LAB = synthetic.LabChannels()
LAB_MAP = {k: ChannelMap(**v) for k, v in LAB.protocol_section().items()}
NAME = "run_007.csv"


def frame_of(
    *,
    fs: float = 200.0,
    style: str = "canonical",
    seed: int = 1,
    noise: synthetic.Noise | None = None,
    config: str = "hull",
    angle: float = 0.0,
    speed: float = 1.2,
    accel: float = 0.5,
    **kw,
) -> pd.DataFrame:
    frame, _ = synthetic.simulate_run(
        config, angle, speed, accel, fs=fs, rng=seed, noise=noise, tare=synthetic.TareTruth(),
        **kw,
    )
    return synthetic.to_file_frame(frame, style)


def csv_of(frame: pd.DataFrame) -> bytes:
    return frame.to_csv(index=False, lineterminator="\n").encode()


GOOD_FRAME = frame_of()
GOOD = csv_of(GOOD_FRAME)


def load(data: bytes, name: str = NAME, mapping=None, **kw):
    return load_run(Path(name), {} if mapping is None else mapping, data=data, **kw)


def reason(data: bytes, name: str = NAME, mapping=None, **kw) -> str:
    with pytest.raises(RunError) as err:
        load(data, name, mapping, **kw)
    text = str(err.value)
    assert "\n" not in text and "Traceback" not in text
    return text


def text_rows(data: bytes) -> list[int]:
    """File rows (header = 1) of the data lines holding a field that is not a number."""

    def numeric(field: bytes) -> bool:
        try:
            float(field)
        except ValueError:
            return False
        return True

    lines = data.split(b"\n")
    return [
        i + 1
        for i, ln in enumerate(lines)
        if i > 0 and ln and not all(numeric(f) for f in ln.split(b","))
    ]


# ------------------------------------------------------------------------------ good input
def test_good_file_loads_without_notes():
    raw = load(GOOD)
    assert raw.notes == []
    assert raw.fs == pytest.approx(200.0)
    np.testing.assert_array_equal(raw.drag, GOOD_FRAME["drag"].to_numpy())
    assert raw.lift is not None and raw.accel is None


@pytest.mark.parametrize(
    "variant",
    ["crlf", "trailing_blank", "bom", "bom_crlf", "no_final_newline", "semicolon", "tab",
     "spaced_header", "blank_lines_at_end_crlf", "latin1_header"],
)
def test_csv_dialects_read_the_same(variant):
    data = GOOD
    mapping = None
    if variant == "crlf":
        data = data.replace(b"\n", b"\r\n")
    elif variant == "trailing_blank":
        data = data + b"\n"
    elif variant == "bom":
        data = b"\xef\xbb\xbf" + data
    elif variant == "bom_crlf":
        data = b"\xef\xbb\xbf" + data.replace(b"\n", b"\r\n")
    elif variant == "no_final_newline":
        data = data.rstrip(b"\n")
    elif variant == "semicolon":
        data = data.replace(b",", b";")
    elif variant == "tab":
        data = data.replace(b",", b"\t")
    elif variant == "spaced_header":
        head, rest = data.split(b"\n", 1)
        data = head.replace(b",", b", ") + b"\n" + rest
    elif variant == "blank_lines_at_end_crlf":
        data = data.replace(b"\n", b"\r\n") + b"\r\n\r\n"
    elif variant == "latin1_header":
        head, rest = data.split(b"\n", 1)
        data = head.replace(b"drag", b"drag \xb0") + b"\n" + rest
        mapping = {"drag": ChannelMap(column="drag °")}
    raw = load(data, mapping=mapping)
    base = load(GOOD)
    assert raw.notes == []
    for ch in ("time", "speed", "drag", "lift"):
        np.testing.assert_array_equal(getattr(raw, ch), getattr(base, ch))


def test_gzip_and_lab_channels_are_calibrated():
    lab = csv_of(frame_of(style="lab"))
    raw = load_run(Path("run_007.csv.gz"), LAB_MAP, data=gzip.compress(lab, mtime=0))
    base = load(GOOD)
    np.testing.assert_allclose(raw.drag, base.drag, atol=1e-6)
    np.testing.assert_allclose(raw.lift, base.lift, atol=1e-6)
    assert raw.notes == []


def test_rows_are_counted_like_a_text_editor():
    cols, _ = read_csv_columns(GOOD, NAME)
    np.testing.assert_array_equal(cols["__rows__"][:3], [2, 3, 4])
    lines = GOOD.split(b"\n")
    with_blanks = b"\n".join(lines[:10] + [b"", b"\r"] + lines[10:])
    cols, _ = read_csv_columns(with_blanks, NAME)
    assert cols["__rows__"][8] == 10 and cols["__rows__"][9] == 13


# ---------------------------------------------------------------------------- empty files
@pytest.mark.parametrize("data", [b"", b"\n\n", b"\xef\xbb\xbf", b"  \r\n \r\n"])
def test_empty_file(data):
    assert reason(data) == f"{NAME} is empty (0 data rows)"


def test_header_only_and_empty_gzip():
    assert "has a header but no data rows" in reason(GOOD.split(b"\n")[0] + b"\n")
    assert "empty" in reason(b"", name="run_007.csv.gz")
    assert "empty" in reason(gzip.compress(b"", mtime=0), name="run_007.csv.gz")
    assert "empty" in reason(b"", name="run_007.tdms")


# ---------------------------------------------------------------------- truncated last line
@pytest.mark.parametrize("seed", range(6))
def test_truncated_mid_line(seed):
    cut = damage.truncate(GOOD, seed)
    assert not cut.endswith(b"\n")
    row = cut.count(b"\n") + 1
    assert reason(cut).startswith(f"{NAME} ends in the middle of a line (row {row} has ")
    assert reason(cut).endswith("; a truncated file): was it copied before the recording "
                                "finished?")


@pytest.mark.parametrize("tail", [b",", b",-", b",0.1e", b",1.5e-"])
def test_truncated_inside_the_last_value(tail):
    lines = GOOD.split(b"\n")
    cut = b"\n".join(lines[:1000]) + b"\n" + lines[1000][: lines[1000].rfind(b",")] + tail
    assert reason(cut).startswith(f"{NAME} ends in the middle of a line (row 1001 ")
    assert "a truncated file" in reason(cut)


def test_complete_last_line_without_line_break_is_kept():
    lines = GOOD.split(b"\n")
    data = b"\n".join(lines[:1500])
    raw = load(data)
    assert raw.n == 1499 and raw.notes == []
    short = lines[1499][: lines[1499].rfind(b",")] + b",0.27"  # a round last value
    assert load(b"\n".join(lines[:1499] + [short])).n == 1499


def test_truncated_gzip():
    packed = gzip.compress(GOOD, mtime=0)
    text = reason(packed[: len(packed) // 2], name="run_007.csv.gz")
    assert text.startswith("run_007.csv.gz") and "truncated" in text


# ------------------------------------------------------------------------ non-numeric rows
def test_few_text_rows_are_dropped_with_a_note():
    data = damage.insert_text_rows(GOOD, 3, seed=4)
    raw = load(data)
    bad = text_rows(data)
    assert len(bad) == 3
    assert raw.notes == [
        f"3 non-numeric row(s) dropped (rows {', '.join(map(str, bad))})"
    ]
    np.testing.assert_array_equal(raw.drag, load(GOOD).drag)


def test_text_replacing_a_data_row_is_dropped_and_the_sample_put_back():
    lines = GOOD.split(b"\n")
    lines[800] = b"ERROR,ERROR,ERROR,ERROR"
    raw = load(b"\n".join(lines))
    base = load(GOOD)
    assert raw.notes[0] == "1 non-numeric row(s) dropped (row 801)"
    assert "1 lost sample(s) put back by interpolation" in raw.notes
    assert raw.n == base.n
    np.testing.assert_allclose(raw.time, base.time, atol=1e-9)
    assert abs(raw.drag[798] - base.drag[798]) < 0.02


def test_many_text_rows_reject_the_run_and_say_how_many():
    data = damage.insert_text_rows(GOOD, 200, seed=2)
    first = text_rows(data)[0]
    total = data.count(b"\n") - 1
    assert reason(data) == (
        f"{NAME}: 200 of {total} rows are not numeric or malformed (first at row {first}; "
        f"{100 * 200 / total:.1f} %, more than the 1 % that may be dropped)"
    )


def test_rows_with_the_wrong_number_of_fields():
    lines = GOOD.split(b"\n")
    lines[500] = lines[500] + b",0.1"
    lines[900] = lines[900].rsplit(b",", 1)[0]
    data = b"\n".join(lines)
    cols, notes = read_csv_columns(data, NAME)
    assert notes == ["2 row(s) with the wrong number of fields skipped (rows 501, 901)"]
    raw = load(data)
    assert "2 lost sample(s) put back by interpolation" in raw.notes
    for i in range(400, 450):
        lines[i] = lines[i] + b",x,y"
    assert "not numeric or malformed (first at row 401;" in reason(b"\n".join(lines))


# --------------------------------------------------------------------- missing channel
def test_missing_channel_names_the_columns_and_the_mapping():
    text = reason(damage.drop_channel(GOOD, "drag"))
    assert text == (
        f"{NAME}: the drag channel is missing (expected as the column 'drag' (no [channels] "
        "mapping)); columns found: 'time', 'speed', 'lift'"
    )
    lab = damage.drop_channel(csv_of(frame_of(style="lab")), "drag")
    text = reason(lab, mapping=LAB_MAP)
    assert text == (
        f"{NAME}: the drag channel is missing (mapped from the column 'Fx load cell (V)' in "
        "[channels]); columns found: 'Time (s)', 'Carriage speed (m/s)', 'Fy load cell (V)'"
    )


def test_an_explicitly_mapped_optional_channel_must_be_there():
    mapping = {"accel": ChannelMap(column="a (m/s2)")}
    assert "the accel channel is missing (mapped from the column 'a (m/s2)'" in reason(
        GOOD, mapping=mapping
    )


def test_a_duplicated_column_is_ambiguous():
    head, rest = GOOD.split(b"\n", 1)
    data = head + b",drag\n" + b"\n".join(ln + b",0.5" for ln in rest.split(b"\n") if ln)
    assert "the column 'drag' for the drag channel appears more than once" in reason(data)


# ------------------------------------------------------------------------------ NaN gaps
def test_short_gap_is_interpolated():
    data = damage.nan_gap(GOOD, 0.02, "drag", start=8.0)
    raw = load(data)
    assert raw.notes == ["4 missing drag value(s) interpolated"]
    base = load(GOOD)
    i = np.flatnonzero(np.abs(base.time - 8.0) < 1e-9)[0]
    assert np.max(np.abs(raw.drag[i : i + 4] - base.drag[i : i + 4])) < 0.02


def test_long_gap_rejects_the_run_with_where():
    data = damage.nan_gap(GOOD, 0.5, "speed", start=8.0)
    assert reason(data) == (
        f"{NAME}: the speed channel has a gap of 100 missing values (0.50 s) from t = 8.00 s, "
        "rows 1602–1701, longer than the 0.05 s that may be interpolated"
    )


def test_infinite_values_are_missing_values():
    frame = GOOD_FRAME.copy()
    frame.loc[1000:1002, "drag"] = np.inf
    frame.loc[2000, "speed"] = -np.inf
    raw = load(csv_of(frame))
    assert "3 infinite drag value(s) treated as missing" in raw.notes
    assert "3 missing drag value(s) interpolated" in raw.notes
    assert np.isfinite(raw.drag).all() and np.isfinite(raw.speed).all()


def test_an_empty_optional_channel_is_ignored_an_empty_required_one_rejected():
    frame = GOOD_FRAME.copy()
    frame["lift"] = np.nan
    raw = load(csv_of(frame))
    assert raw.lift is None
    assert raw.notes == ["the lift column holds no numbers; the channel is ignored"]
    frame["drag"] = np.nan
    assert reason(csv_of(frame)) == f"{NAME}: the drag channel holds no numbers"


def test_missing_times_are_interpolated_or_rejected():
    frame = GOOD_FRAME.copy()
    frame.loc[300:302, "time"] = np.nan
    raw = load(csv_of(frame))
    assert raw.notes == ["3 missing time value(s) interpolated"]
    np.testing.assert_allclose(raw.time, GOOD_FRAME["time"].to_numpy(), atol=1e-9)
    np.testing.assert_array_equal(raw.drag, GOOD_FRAME["drag"].to_numpy())
    frame.loc[300:400, "time"] = np.nan
    assert reason(csv_of(frame)) == (
        f"{NAME}: the time channel is empty for 101 rows (rows 302–402), longer than the "
        "0.05 s that may be interpolated"
    )


# ------------------------------------------------------------------------------- time
def test_duplicated_block():
    data = damage.duplicate_block(GOOD, seed=3, length=40)
    frame = damage.read_frame(data)
    t = frame["time"].to_numpy()
    i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1  # first repeated sample
    r = i + 2
    assert reason(data) == (
        f"{NAME}: time repeats itself from row {r}: rows {r}–{r + 39} duplicate rows "
        f"{r - 40}–{r - 1} (t = {t[i]:.4f}–{t[i + 39]:.4f} s), a duplicated block of 40 rows"
    )


def test_duplicated_row():
    lines = GOOD.split(b"\n")
    data = b"\n".join(lines[:700] + [lines[699]] + lines[700:])
    assert reason(data) == (
        f"{NAME}: time repeats at row 701 (t = {GOOD_FRAME['time'][698]:.4f} s twice): a "
        "duplicated row"
    )


def test_clock_reset():
    data = damage.time_reset(GOOD, seed=5)
    t = damage.read_frame(data)["time"].to_numpy()
    i = int(np.flatnonzero(np.diff(t) <= 0)[0])
    from towtank.ingest.segments import human_duration

    n = t.size
    dt = float(np.median(np.diff(t)[np.diff(t) > 0]))  # the duration: samples × the step
    assert reason(data) == (
        f"{NAME} holds 2 segments (the time restarts at row {i + 3}, t = 0.0000 s after "
        f"{t[i]:.4f} s: a clock reset, or acquisitions appended to one file): segment 1: rows "
        f"2–{i + 2}, {i + 1} samples, {human_duration((i + 1) * dt)} (t = 0.0000–{t[i]:.4f} "
        f"s); segment 2: rows {i + 3}–{n + 1}, {n - i - 1} samples, "
        f"{human_duration((n - i - 1) * dt)} (t = 0.0000–{t[-1]:.4f} s); say which one is the "
        "run in the run sheet's 'segment' column (1 = the first) or with [read] segment = N"
    )
    # the second acquisition chosen: read from its first row, time from 0
    raw = load(data, segment=2)
    assert raw.n == n - i - 1 and raw.time[0] == 0.0
    assert raw.notes == [f"segment 2 of 2 read (rows {i + 3}–{n + 1}, t = 0.0000–"
                         f"{t[-1]:.4f} s; the file holds 2 acquisitions)"]


def test_time_going_backwards():
    frame = GOOD_FRAME.copy()
    frame.loc[1200, "time"] = frame.loc[1190, "time"]
    assert reason(csv_of(frame)).startswith(
        f"{NAME}: time goes backwards at row 1202 (t = 5.9500 s after"
    )


def test_time_in_milliseconds_is_an_implausible_rate():
    frame = GOOD_FRAME.copy()
    frame["time"] = frame["time"] * 1000.0
    assert reason(csv_of(frame)) == (
        f"{NAME}: the time channel steps by 5 per sample, a sample rate of 0.2 Hz: is time "
        "recorded in ms or as sample numbers rather than in s?"
    )


def test_irregular_sample_rate():
    text = reason(damage.irregular_rate(GOOD, seed=2))
    assert text.startswith(f"{NAME}: the sample rate is irregular: a step of ")
    assert "steps off by more than 20 %" in text


def test_time_written_with_a_coarse_resolution_is_not_irregular():
    frame = frame_of(fs=300.0)
    frame["time"] = np.round(frame["time"], 3)  # ms resolution at 300 Hz: steps of 3 and 4 ms
    raw = load(csv_of(frame))
    assert raw.fs == pytest.approx(300.0, rel=1e-3)
    assert raw.notes == []


def test_a_few_lost_samples_are_put_back_many_reject():
    lines = GOOD.split(b"\n")
    data = b"\n".join(lines[:500] + lines[502:])  # two samples lost in one place
    raw = load(data)
    assert raw.notes == ["2 lost sample(s) put back by interpolation"]
    np.testing.assert_allclose(raw.time, GOOD_FRAME["time"].to_numpy(), atol=1e-9)
    data = b"\n".join(lines[:500] + lines[540:])  # 0.2 s lost
    assert reason(data) == (
        f"{NAME}: 40 samples are missing after row 500 (t = 2.490–2.695 s, a step of 205 ms "
        "where the rate is 200.0 Hz; 40 lost in 1 place(s), more than can be interpolated)"
    )


def test_time_base_directly():
    t = np.arange(1000) / 500.0
    assert time_base(t, "x.csv").fs == pytest.approx(500.0)
    with pytest.raises(RunError, match="only 5 samples"):
        time_base(t[:5], "x.csv")


# ---------------------------------------------------------------------------- clipping
def test_clipped_channel_is_rejected():
    text = reason(damage.clip(GOOD, "drag"))
    assert re.fullmatch(
        rf"{NAME}: the drag channel is clipped flat at [-0-9.e]+ N \(upper rail\) for \d+ "
        r"samples \([0-9.]+ s\) between t = [0-9.]+ s and [0-9.]+ s, rows \d+–\d+: the sensor "
        r"or its amplifier saturated",
        text,
    )
    text = reason(damage.clip(GOOD, "speed", level=1.0))
    assert "the speed channel is clipped flat at 1 m/s (upper rail)" in text
    level = float(np.percentile(GOOD_FRAME["lift"], 10))
    text = reason(damage.clip(GOOD, "lift", rail="lower"))
    assert f"the lift channel is clipped flat at {level:.6g} N (lower rail)" in text


def test_clipped_lab_channel_names_the_value_in_the_file():
    lab = csv_of(frame_of(style="lab"))
    level = float(np.percentile(damage.read_frame(lab)[LAB.drag], 85))
    text = reason(damage.clip(lab, "drag", level), mapping=LAB_MAP)
    assert f"(upper rail, {level:.6g} in the file)" in text


@pytest.mark.parametrize(
    "noise",
    [
        synthetic.Noise(),  # speed quantised to 0.1 mm/s with noise
        synthetic.Noise(speed_quantum=1e-3),  # coarser than its noise
        synthetic.Noise(speed_sigma=0.0),  # quantised, noise-free speed
        synthetic.Noise.quiet(),  # no noise at all
    ],
)
@pytest.mark.parametrize("plateau_s", [0.6, 8.0])
def test_no_clipping_on_healthy_flat_or_quantised_channels(noise, plateau_s):
    raw = load(csv_of(frame_of(noise=noise, plateau_s=plateau_s, seed=11)))
    assert not any("clipped" in n for n in raw.notes)


def test_a_speed_encoder_reading_exactly_zero_at_rest_is_not_clipped():
    frame = GOOD_FRAME.copy()
    frame.loc[frame["speed"] < 0.005, "speed"] = 0.0
    frame.loc[frame["speed"] < 0.0, "speed"] = 0.0
    raw = load(csv_of(frame))
    assert raw.notes == []


def test_check_clipping_on_arrays():
    rng = np.random.default_rng(0)
    t = np.arange(4000) / 200.0
    x = np.sin(t) + 0.01 * rng.standard_normal(t.size)
    check_clipping(x, t, 200.0, "drag")
    with pytest.raises(RunError, match="clipped flat at 0.9 N"):
        check_clipping(np.minimum(x, 0.9), t, 200.0, "drag")
    check_clipping(np.round(x, 2), t, 200.0, "drag")  # quantised, healthy


# ----------------------------------------------------------------------------- spikes
@pytest.fixture(scope="session")
def clean_days(tmp_path_factory):
    """Good hull days at three sample rates (every run of the plan). TDMS float64 files: the
    generator rounds each channel before writing, so they hold exactly the numbers the CSV
    files' reader returns (despike sees the same arrays), without formatting and parsing the
    text of 42 runs at 1000 Hz."""
    out = {}
    for fs in (100.0, 200.0, 1000.0):
        root = tmp_path_factory.mktemp(f"day{int(fs)}")
        synthetic.make_hull_day(root, seed=int(fs), fs=fs, file_format="tdms",
                                sheet_format="csv")
        out[fs] = sorted((root / "data").glob("*.tdms"))
    return out


@pytest.mark.parametrize("fs", [100.0, 200.0, 1000.0])
def test_despike_removes_nothing_from_clean_runs(clean_days, fs):
    for path in clean_days[fs]:
        data = path.read_bytes()
        on = load_run(path, LAB_MAP, data=data)
        off = load_run(path, LAB_MAP, data=data, do_despike=False)
        assert on.notes == [], (path.name, on.notes)
        for ch in ("speed", "drag", "lift"):
            np.testing.assert_array_equal(getattr(on, ch), getattr(off, ch))
        assert np.mean(on.drag) == np.mean(off.drag)


def test_despike_keeps_sharp_real_signal():
    # a transverse accelerated tow at 50 Hz: the inertia force kinks within a few samples
    frame = frame_of(fs=50.0, angle=90.0, speed=0.3, accel=0.2, seed=3)
    for ch in ("speed", "drag", "lift"):
        x = frame[ch].to_numpy()
        assert despike(x)[1] == 0
    t = np.arange(2000) / 100.0
    kinks = np.interp(t, [0, 5, 5.05, 10, 10.02, 20], [0, 0, 3, 3, -1, -1])
    assert despike(kinks)[1] == 0


@pytest.mark.parametrize("seed", range(4))
def test_spikes_are_counted_and_removed(seed):
    data = damage.spikes(GOOD, 7, "drag", seed=seed)
    raw = load(data)
    assert raw.notes == ["7 spike(s) removed from drag"]
    base = load(GOOD)
    assert np.max(np.abs(raw.drag - base.drag)) < 0.02
    assert abs(np.mean(raw.drag) - np.mean(base.drag)) < 1e-4


def test_despike_on_arrays():
    rng = np.random.default_rng(1)
    x = np.round(0.5 + 0.0005 * rng.standard_normal(5000), 4)  # quantised to 0.1 mm/s
    assert despike(x)[1] == 0
    y = x.copy()
    y[[100, 2000, 2001, 4000]] += [0.05, -0.08, -0.08, 0.1]
    out, n = despike(y)
    assert n == 4
    np.testing.assert_allclose(out[[100, 2000, 2001, 4000]], 0.5, atol=0.003)


# -------------------------------------------------------------------------- plausibility
def test_speed_in_the_wrong_unit():
    frame = GOOD_FRAME.copy()
    frame["speed"] = frame["speed"] * 1000.0
    assert re.fullmatch(
        rf"{NAME}: the speed channel reaches 12\d\d m/s at row \d+ \(t = [0-9.]+ s; \d+ "
        r"value\(s\) beyond ±50\): a wrong unit or gain in \[channels\]\?",
        reason(csv_of(frame)),
    )


# ---------------------------------------------------------------------------------- TDMS
def _tdms(tmp_path: Path, channels: dict[str, np.ndarray]) -> bytes:
    from nptdms import ChannelObject, TdmsWriter

    path = tmp_path / "x.tdms"
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([ChannelObject("data", k, v) for k, v in channels.items()])
    return path.read_bytes()


def test_tdms_good_damaged_and_ragged(tmp_path):
    cols = {c: GOOD_FRAME[c].to_numpy() for c in GOOD_FRAME.columns}
    data = _tdms(tmp_path, cols)
    raw = load_run(Path("run_007.tdms"), {}, data=data)
    np.testing.assert_array_equal(raw.drag, load(GOOD).drag)
    text = reason(data[: len(data) // 3], name="run_007.tdms")
    assert text.startswith("run_007.tdms")
    cols["drag"] = cols["drag"][:-100]
    text = reason(_tdms(tmp_path, cols), name="run_007.tdms")
    assert "the channels have different lengths" in text and "the file is incomplete" in text
    cols["drag"] = cols["drag"].copy()


# ----------------------------------------------------------------------------- the file
def test_missing_unreadable_and_unknown_files(tmp_path):
    with pytest.raises(RunError, match=r"the data file run_404.csv is not found in "):
        file_bytes(tmp_path / "run_404.csv")
    (tmp_path / "run_dir.csv").mkdir()
    with pytest.raises(RunError, match="is a folder, not a data file"):
        file_bytes(tmp_path / "run_dir.csv")
    with pytest.raises(RunError, match=r"run_1.xlsx: towtank does not know the format of a "
                                       r"'\.xlsx' file \(it reads .*\.csv.*\.tdms"):
        load_run(tmp_path / "run_1.xlsx", {}, data=b"x")


def test_loading_never_touches_the_file(tmp_path):
    path = tmp_path / NAME
    path.write_bytes(damage.insert_text_rows(GOOD, 2, seed=1))
    before = (path.read_bytes(), path.stat().st_mtime_ns)
    load_run(path, {})
    assert (path.read_bytes(), path.stat().st_mtime_ns) == before
