"""Property tests: random damage to a good run file never crashes ingest or reduction.

Whatever is done to the bytes of a good CSV (bytes inserted, removed or flipped, the file cut
anywhere, NaN, infinities or text put into cells, the header renamed), reading, loading and
reducing it either gives a result or a :class:`~towtank.errors.RunError` with a sentence;
never any other exception (which the pipeline would report as an internal error).
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from towtank.errors import RunError
from towtank.ingest.protocol import ChannelMap, Processing
from towtank.ingest.runfile import RawRun, load_run, read_columns, read_csv_columns
from towtank.reduce.run import reduce_run
from towtank.testing import synthetic

SETTINGS = settings(
    max_examples=int(__import__("os").environ.get("FUZZ_N", 60)),
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
PROCESSING = Processing()
LAB = synthetic.LabChannels()
LAB_MAP = {k: ChannelMap(**v) for k, v in LAB.protocol_section().items()}


def _good_frame(style: str = "canonical"):
    frame, _ = synthetic.simulate_run(
        "hull", 0.0, 1.0, 0.5, fs=100.0, rng=7, plateau_s=3.0, pre_still_s=2.0,
        post_still_s=2.0, tare=synthetic.TareTruth(),
    )
    return synthetic.to_file_frame(frame, style)


GOOD = _good_frame().to_csv(index=False, lineterminator="\n").encode()
GOOD_LAB = _good_frame("lab").to_csv(index=False, lineterminator="\n").encode()
LINES = GOOD.split(b"\n")[:-1]
N_FIELDS = LINES[0].count(b",") + 1


def _never_crashes(data: bytes, name: str = "run_001.csv", mapping=None) -> RawRun | None:
    """Read, load and reduce; only a RunError may stop it. Returns the loaded run, if any."""
    mapping = {} if mapping is None else mapping
    if name.endswith(".csv"):
        try:
            read_csv_columns(data, name)
        except RunError as exc:
            assert str(exc).strip()
    else:
        try:
            read_columns(Path(name), data)
        except RunError as exc:
            assert str(exc).strip()
    try:
        raw = load_run(Path(name), mapping, data=data)
    except RunError as exc:
        assert str(exc).strip()
        return None
    assert raw.time.size == raw.speed.size == raw.drag.size
    for arr in (raw.time, raw.speed, raw.drag):
        assert np.isfinite(arr).all()
    assert np.all(np.diff(raw.time) > 0)
    assert math.isfinite(raw.fs) and raw.fs > 0
    try:
        red = reduce_run(raw, PROCESSING, run=1, file=name)
    except RunError as exc:
        assert str(exc).strip()
    else:
        assert red.n_samples == raw.n
    return raw


def test_the_good_file_loads_and_reduces():
    raw = _never_crashes(GOOD)
    assert raw is not None and raw.notes == []
    assert _never_crashes(GOOD_LAB, mapping=LAB_MAP) is not None


# ------------------------------------------------------------------------ byte-level damage
_op = st.tuples(
    st.sampled_from(["insert", "delete", "flip", "cut"]),
    st.floats(0.0, 1.0),
    st.binary(min_size=1, max_size=40),
)


def _apply(data: bytes, ops) -> bytes:
    for kind, where, payload in ops:
        if not data:
            break
        i = min(int(where * len(data)), len(data) - 1)
        if kind == "insert":
            data = data[:i] + payload + data[i:]
        elif kind == "delete":
            data = data[:i] + data[i + len(payload) * 50 :]
        elif kind == "flip":
            data = data[:i] + payload[:1] + data[i + 1 :]
        else:
            data = data[:i]
    return data


@SETTINGS
@given(ops=st.lists(_op, min_size=1, max_size=6))
def test_random_byte_damage(ops):
    _never_crashes(_apply(GOOD, ops))


@SETTINGS
@given(ops=st.lists(_op, min_size=1, max_size=4), tail=st.binary(max_size=200))
def test_random_bytes_appended_to_a_lab_file(ops, tail):
    _never_crashes(_apply(GOOD_LAB, ops) + tail, mapping=LAB_MAP)


@SETTINGS
@given(cut=st.integers(0, len(GOOD)))
def test_random_truncation(cut):
    _never_crashes(GOOD[:cut])


@SETTINGS
@given(ops=st.lists(_op, min_size=0, max_size=3), cut=st.floats(0.0, 1.0))
def test_random_damage_to_a_gzip_file(ops, cut):
    packed = gzip.compress(GOOD, mtime=0)
    damaged = _apply(packed, ops)
    damaged = damaged[: max(1, int(cut * len(damaged)))] if cut < 0.98 else damaged
    _never_crashes(damaged, name="run_001.csv.gz")


@SETTINGS
@given(data=st.binary(max_size=600))
def test_random_bytes_as_a_file(data):
    _never_crashes(data)
    _never_crashes(data, name="run_001.tdms")


# ------------------------------------------------------------------------ cell-level damage
_TOKENS = st.one_of(
    st.sampled_from(
        ["nan", "NaN", "inf", "-inf", "Infinity", "", " ", "abc", "1e999", "-1e999", "1e-400",
         "--", "1,5", '"x"', "0x10", "#N/A", "null", "١٢", "1e308", "-1e308", "0", "1e15",
         "-0.0", "NULL", "TRUE"]
    ),
    st.text(max_size=8),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
)


@pytest.mark.heavy
@SETTINGS
@given(
    cells=st.lists(
        st.tuples(st.integers(1, len(LINES) - 1), st.integers(0, N_FIELDS - 1), _TOKENS),
        min_size=1,
        max_size=40,
    )
)
def test_random_values_injected(cells):
    lines = [ln.split(b",") for ln in LINES]
    for row, col, token in cells:
        lines[row][col] = token.encode("utf-8", "replace")
    data = b"\n".join(b",".join(f) for f in lines) + b"\n"
    _never_crashes(data)


@SETTINGS
@given(
    start=st.integers(1, len(LINES) - 2),
    length=st.integers(1, 400),
    col=st.integers(0, N_FIELDS - 1),
    token=_TOKENS,
)
def test_random_block_of_values_replaced(start, length, col, token):
    lines = [ln.split(b",") for ln in LINES]
    for row in range(start, min(start + length, len(lines))):
        lines[row][col] = token.encode("utf-8", "replace")
    _never_crashes(b"\n".join(b",".join(f) for f in lines) + b"\n")


@pytest.mark.heavy
@SETTINGS
@given(
    names=st.lists(
        st.one_of(
            st.sampled_from(["time", "speed", "drag", "lift", "accel", " drag", "Time", ""]),
            st.text(max_size=12),
        ),
        min_size=1,
        max_size=7,
    )
)
def test_random_column_names(names):
    header = ",".join(n.replace(",", ";").replace("\n", " ").replace("\r", " ") for n in names)
    data = header.encode("utf-8") + b"\n" + b"\n".join(LINES[1:]) + b"\n"
    _never_crashes(data)


@SETTINGS
@given(
    rows=st.lists(st.integers(1, len(LINES) - 1), min_size=1, max_size=30),
    seed=st.integers(0, 2**16),
)
def test_random_rows_repeated_or_removed(rows, seed):
    rng = np.random.default_rng(seed)
    lines = list(LINES)
    for row in sorted(set(rows), reverse=True):
        if rng.random() < 0.5:
            del lines[row]
        else:
            lines.insert(row, lines[row])
    _never_crashes(b"\n".join(lines) + b"\n")


@SETTINGS
@given(
    scale=st.sampled_from([1e-300, 1e-9, 1e-3, 1.0, 1e3, 1e9, 1e300, -1.0]),
    shift=st.sampled_from([0.0, 1e9, -1e9, 1e300]),
    which=st.sampled_from(["time", "speed", "drag"]),
)
def test_extreme_scales(scale, shift, which):
    frame = _good_frame()
    with np.errstate(all="ignore"):
        frame[which] = frame[which] * scale + shift
    _never_crashes(frame.to_csv(index=False, lineterminator="\n").encode())


@pytest.mark.parametrize("gain", [1e-12, -1.0, 1e12])
def test_extreme_gains(gain):
    mapping = dict(LAB_MAP)
    mapping["drag"] = ChannelMap(column=LAB.drag, gain=gain)
    _never_crashes(GOOD_LAB, mapping=mapping)


# ------------------------------------------------------------------------ TDMS damage
def _good_tdms() -> bytes:
    import tempfile

    frame, _ = synthetic.simulate_run(
        "hull", 0.0, 1.0, 0.5, fs=100.0, rng=8, plateau_s=3.0, pre_still_s=2.0,
        post_still_s=2.0,
    )
    with tempfile.TemporaryDirectory() as tmp:
        path = synthetic.write_run_file(frame, Path(tmp) / "run.tdms", tdms_dtype="float32")
        return path.read_bytes()


GOOD_TDMS = _good_tdms()


def test_the_good_tdms_file_loads():
    raw = _never_crashes(GOOD_TDMS, name="run_001.tdms")
    assert raw is not None and raw.notes == []


@SETTINGS
@given(ops=st.lists(_op, min_size=1, max_size=4))
def test_random_damage_to_a_tdms_file(ops):
    _never_crashes(_apply(GOOD_TDMS, ops), name="run_001.tdms")


# ------------------------------------------------------- the damage kinds, at random seeds
@SETTINGS
@given(
    kind=st.sampled_from(
        ["truncate", "duplicate_block", "time_reset", "irregular_rate", "drop_channel", "empty"]
    ),
    seed=st.integers(0, 2**32 - 1),
)
def test_fatal_damage_is_always_rejected(kind, seed):
    from towtank.testing import damage

    fn = getattr(damage, kind)
    data = fn(GOOD) if kind == "empty" else fn(GOOD, "drag") if kind == "drop_channel" else fn(
        GOOD, seed
    )
    with pytest.raises(RunError):
        load_run(Path("run_001.csv"), {}, data=data)


@pytest.mark.heavy
@SETTINGS
@given(
    kind=st.sampled_from(["spikes", "nan_gap", "text_rows"]),
    n=st.integers(1, 5),
    seed=st.integers(0, 2**32 - 1),
)
def test_repairable_damage_is_always_repaired(kind, n, seed):
    from towtank.testing import damage

    if kind == "spikes":
        data = damage.spikes(GOOD, n, "drag", seed)
    elif kind == "nan_gap":
        data = damage.nan_gap(GOOD, n * 0.01, "speed", seed)
    else:
        data = damage.insert_text_rows(GOOD, n, seed)
    raw = _never_crashes(data)
    assert raw is not None
    good = load_run(Path("run_001.csv"), {}, data=GOOD)
    assert raw.n == good.n
    np.testing.assert_allclose(raw.drag, good.drag, atol=0.05)
    np.testing.assert_allclose(raw.speed, good.speed, atol=0.05)
    assert len(raw.notes) == 1
