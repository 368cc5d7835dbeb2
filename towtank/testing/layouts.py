"""Run files written as other labs' software writes them (the generator's file layouts).

Each layout takes the file frame of :func:`towtank.testing.instruments.to_file_frame` (the
columns as the lab names them, rounded as recorded) and writes it the way a real acquisition
or processing program does, so that towtank's readers are tested on the files labs keep:

================  ===========  ===================================================================
layout            extension    as written by
================  ===========  ===================================================================
tdms-waveform     .tdms        LabVIEW's default: waveform channels, NO time channel; the timing
                               in ``wf_start_offset``, ``wf_increment``, ``wf_samples``
lvm               .lvm         LabVIEW Measurement text: file header, two segments each with its
                               header (``Delta_X``, ``Y_Unit_Label``), ``X_Value`` times
txt-eu            .txt         a European Excel export: three preamble lines, ``;`` separators,
                               decimal commas, a units row; the speed in mm/s
mat               .mat         MATLAB v5: a struct ``run`` with one field per channel
mat73             .mat         MATLAB v7.3 (HDF5 with MATLAB's 512-byte header): vectors at the
                               top level, no time vector, a scalar ``fs`` [Hz]
hdf5              .h5          HDF5: group ``data``, one dataset per channel with a ``unit``
                               attribute, ``sample_rate`` on the group
hdf5-rate-name    .h5m         HDF5 as a MARIN basin export writes it: the sample rate only in
                               the group's name (``/200.00 Hz``), one dataset per channel, no
                               time dataset, no attributes (the units in the channels' names)
two-cell          .csv         the drag from two load cells (``DragL``, ``DragR``) to be summed
matrix            .csv         a two-component dynamometer: bridges ``Fx``, ``Fy`` with cross-talk
speed-log         .csv         no speed column; the carriage speed in ``run_NNN_carriage.csv`` at
                               100 Hz on a clock 0.35 s behind the balance's
position-log      .csv         as speed-log, but the log holds the encoder's position ``x (mm)``
zero-file         .csv         the plain run file, and the balance at rest before the run in
                               ``run_NNN_zero.csv`` (the lab's zeros file, 1.5 s)
no-speed          .csv         no speed channel at all (a speed log not kept): the run sheet
                               gives the set speed and each run's steady window
                               (``window_start_s``, ``window_end_s``)
lvm-appended      .lvm         two acquisitions appended under one LVM header, as TU Delft's
                               load balance wrote them: first the balance at rest
                               (:data:`APPENDED_FIRST_S`), then, the time jumping by
                               :data:`APPENDED_GAP_S`, the run; the run sheet's ``segment`` is 2
================  ===========  ===================================================================

Names that are not MATLAB identifiers (``Time (s)``) are written as identifiers (``Time_s``)
in the MATLAB layouts; :func:`variable_name` gives the name a protocol then maps.
"""

from __future__ import annotations

import datetime as _dt
import io
import re
from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import scipy.io
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from towtank.testing.labchannels import LabChannels
from towtank.testing.numbertext import column_texts, csv_text, rows_text

#: Layout -> file extension.
LAYOUTS = {
    "tdms-waveform": "tdms",
    "lvm": "lvm",
    "txt-eu": "txt",
    "mat": "mat",
    "mat73": "mat",
    "hdf5": "h5",
    "hdf5-rate-name": "h5m",
    "two-cell": "csv",
    "matrix": "csv",
    "speed-log": "csv",
    "position-log": "csv",
    "zero-file": "csv",
    "no-speed": "csv",
    "lvm-appended": "lvm",
}

#: The "lvm-appended" layout: length of the first acquisition (the balance at rest, the run's
#: own first seconds) [s], and the time from its last row to the run's first [s].
APPENDED_FIRST_S = 2.0
APPENDED_GAP_S = 77.0

#: The steady window the "no-speed" layout's run sheet gives: the generated plateau, this far
#: in from each of its ends [s].
NO_SPEED_WINDOW_MARGIN_S = 0.6

#: The carriage logs of the "speed-log" and "position-log" layouts: their rate [Hz], the
#: motion controller's clock (log time + offset = run-file time) [s], and the encoder's
#: resolution [m].
CARRIAGE_LOG_HZ = 100.0
CARRIAGE_OFFSET_S = 0.35
ENCODER_STEP_M = 1e-5

#: The [balance] matrix of the "matrix" layout: outputs (drag, lift) [N] per input [V], with
#: cross-talk (the example of docs/formats.md).
BALANCE_MATRIX = ((20.0, 0.3), (-0.2, -25.0))

_FIXED = _dt.datetime(2024, 5, 21, 9, 0, 0)

#: Layouts without a time column (the time comes from the file's timing).
NO_TIME_COLUMN = ("tdms-waveform", "lvm", "mat73", "lvm-appended", "hdf5-rate-name")


def protocol_channels(layout: str, section: dict[str, dict]) -> dict[str, dict]:
    """A ``[channels]`` table for a layout: the time left unmapped where the file has no time
    column (LabVIEW waveform timing, LVM's X_Value, a MATLAB ``fs``)."""
    if layout in NO_TIME_COLUMN:
        return {k: v for k, v in section.items() if k != "time"}
    return section


def variable_name(column: str) -> str:
    """A column name as a MATLAB identifier: other characters to '_', a letter first."""
    name = re.sub(r"\W+", "_", column).strip("_") or "x"
    return name if name[0].isalpha() else f"x_{name}"


def layout_channels(layout: str, channels: LabChannels) -> LabChannels:
    """The lab's channel names as a layout stores them (MATLAB identifiers in .mat files, no
    '/' in HDF5 names), for the protocol's ``[channels]``."""
    if layout not in ("mat", "mat73", "hdf5", "hdf5-rate-name"):
        return channels
    fix = variable_name if layout.startswith("mat") else (lambda c: c.replace("/", "_per_"))
    return replace(channels, time=fix(channels.time), speed=fix(channels.speed),
                   accel=fix(channels.accel), drag=fix(channels.drag), lift=fix(channels.lift))


def _time_column(frame: pd.DataFrame, time_col: str) -> np.ndarray:
    return frame[time_col].to_numpy(dtype=np.float64)


def write_layout(
    layout: str, frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]
) -> Path:
    """Write ``frame`` (columns as the lab names them; ``time_col`` the time [s]) to ``path``.

    ``units`` gives each column's unit (SI, or V for load cells).
    """
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {', '.join(LAYOUTS)}, not {layout!r}.")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writer = {
        "tdms-waveform": _tdms_waveform, "lvm": _lvm, "txt-eu": _txt_eu, "mat": _mat_v5,
        "mat73": _mat_v73, "hdf5": _hdf5, "hdf5-rate-name": _hdf5_rate_name, "two-cell": _csv,
        "matrix": _csv,
        "speed-log": _csv, "position-log": _csv, "zero-file": _csv, "no-speed": _csv,
        "lvm-appended": _lvm_appended,
    }[layout]
    writer(frame, path, time_col, units)
    return path


def _csv(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    path.write_bytes(csv_text(frame).encode())


def carriage_log_name(run_file: str | Path) -> str:
    """The carriage log beside a run file: ``run_021.csv`` -> ``run_021_carriage.csv``."""
    return f"{Path(run_file).name.split('.', 1)[0]}_carriage.csv"


def write_carriage_log(layout: str, frame: pd.DataFrame, run_path: Path, time_col: str,
                       speed_col: str) -> Path:
    """The motion controller's log of a run: its speed ("speed-log", ``v (m/s)``) or its
    position ("position-log", ``x (mm)`` to the encoder's step) at :data:`CARRIAGE_LOG_HZ` on
    its own clock, which runs :data:`CARRIAGE_OFFSET_S` behind the balance's."""
    t = _time_column(frame, time_col)
    u = frame[speed_col].to_numpy(np.float64)
    t_log = np.arange(t[0] - CARRIAGE_OFFSET_S + 0.004, t[-1] - CARRIAGE_OFFSET_S + 0.2,
                      1.0 / CARRIAGE_LOG_HZ)
    if layout == "speed-log":
        speed = np.interp(t_log + CARRIAGE_OFFSET_S, t, u)
        log = pd.DataFrame({"t (s)": np.round(t_log, 4), "v (m/s)": np.round(speed, 5)})
    else:  # the encoder counts the carriage's travel
        x = np.concatenate(([0.0], np.cumsum(0.5 * (u[1:] + u[:-1]) * np.diff(t))))
        pos = np.round(np.interp(t_log + CARRIAGE_OFFSET_S, t, x) / ENCODER_STEP_M) * \
            ENCODER_STEP_M
        log = pd.DataFrame({"t (s)": np.round(t_log, 4), "x (mm)": np.round(pos * 1e3, 3)})
    path = Path(run_path).with_name(carriage_log_name(run_path))
    path.write_bytes(csv_text(log).encode())
    return path


#: Length of the zeros file of the "zero-file" layout [s].
ZERO_FILE_S = 1.5


#: The first part of a run file taken as the carriage at rest by :func:`motion_start` [s].
STILL_REFERENCE_S = 1.0


def motion_start(t: np.ndarray, u: np.ndarray) -> float:
    """When the carriage starts to move [s]: the first time the speed [m/s], averaged over
    0.1 s (5 or 6 mains periods, so that hum is not taken for motion), leaves its level over
    the file's first :data:`STILL_REFERENCE_S` by more than six times its scatter there or
    0.3 % of the top speed. A jerk-limited start (speed ∝ t²) crosses that within about 0.2 s,
    where a fraction of the top speed (3 %: half a second) would come late, and a zeros file
    ending before it would hold the model's first inertial force."""
    k = max(1, int(round(0.1 / float(np.median(np.diff(t))))))
    smooth = np.convolve(u, np.ones(k) / k, mode="valid")
    ts = t[k // 2: k // 2 + smooth.size]
    ref = smooth[ts < t[0] + STILL_REFERENCE_S]
    level = float(np.mean(ref))
    threshold = max(6.0 * float(np.std(ref)), 0.003 * float(np.max(np.abs(u))))
    return float(ts[int(np.argmax(np.abs(smooth - level) > threshold))])


def write_zero_file(frame: pd.DataFrame, run_path: Path, time_col: str,
                    speed_col: str) -> Path:
    """The lab's zeros file of a run: the balance at rest just before the carriage moves
    (here :data:`ZERO_FILE_S` of the run's own still start, ending 0.5 s before the motion),
    with the run file's columns."""
    t = _time_column(frame, time_col)
    start = motion_start(t, frame[speed_col].to_numpy(np.float64)) - 0.5
    zero = frame[(t >= start - ZERO_FILE_S) & (t < start)]
    path = Path(run_path).with_name(f"{Path(run_path).name.split('.', 1)[0]}_zero.csv")
    path.write_bytes(csv_text(zero).encode())
    return path


def balance_frame(layout: str, frame: pd.DataFrame, lab: LabChannels) -> pd.DataFrame:
    """The lab-style file frame as a balance with two load cells per force ("two-cell": DragL
    + DragR, the sum is the drag bridge's voltage, split unevenly as a moment would) or as a
    two-component dynamometer whose bridges see both forces ("matrix": inputs = M⁻¹·forces
    with :data:`BALANCE_MATRIX`)."""
    out = frame.copy()
    v_drag = frame[lab.drag].to_numpy(np.float64)
    v_lift = frame[lab.lift].to_numpy(np.float64)
    if layout == "two-cell":
        # the left cell carries 60 % ± 10 % (the lift's moment loads one cell more)
        swing = v_lift - np.median(v_lift)
        share = 0.6 + 0.1 * np.tanh(swing / (np.std(swing) or 1.0))
        left = np.round(v_drag * share, 8)
        out = out.drop(columns=[lab.drag])
        out.insert(1 + list(frame.columns).index(lab.drag) - 1, "DragL (V)", left)
        out.insert(list(out.columns).index("DragL (V)") + 1, "DragR (V)",
                   np.round(v_drag - left, 8))
    elif layout == "matrix":
        forces = np.vstack([lab.drag_gain * (v_drag - lab.drag_offset),
                            lab.lift_gain * (v_lift - lab.lift_offset)])
        inputs = np.linalg.solve(np.array(BALANCE_MATRIX), forces)
        out = out.drop(columns=[lab.drag, lab.lift])
        out["Fx (V)"] = np.round(inputs[0], 9)
        out["Fy (V)"] = np.round(inputs[1], 9)
    return out


def protocol_sections(layout: str, sections: dict[str, dict]) -> dict[str, dict]:
    """The protocol sections for a layout: [channels] as the layout names them (no time for
    files without a time column, summed cells, none for the balance's forces) and
    [balance]."""
    sections = dict(sections)
    if "channels" not in sections:
        return sections
    ch = protocol_channels(layout, sections["channels"])
    if layout == "two-cell":
        drag = dict(ch["drag"])
        drag.pop("column")
        ch = {**ch, "drag": {"columns": ["DragL (V)", "DragR (V)"], **drag}}
    elif layout == "matrix":
        ch = {k: v for k, v in ch.items() if k not in ("drag", "lift")}
        sections["balance"] = {"inputs": ["Fx (V)", "Fy (V)"], "outputs": ["drag", "lift"],
                               "matrix": [list(r) for r in BALANCE_MATRIX]}
    elif layout == "zero-file":
        sections["zeros"] = {"file": "{stem}_zero.csv"}
    elif layout == "no-speed":
        ch = {k: v for k, v in ch.items() if k != "speed"}
        sections["processing"] = {**sections.get("processing", {}), "speed_source": "nominal"}
    elif layout in ("speed-log", "position-log"):
        ch = {k: v for k, v in ch.items() if k != "speed"}
        how = ({"speed": {"column": "v (m/s)"}} if layout == "speed-log"
               else {"position": {"column": "x (mm)"}})
        sections["speed_log"] = {"file": "{stem}_carriage.csv", "time": {"column": "t (s)"},
                                 **how, "offset_s": CARRIAGE_OFFSET_S}
    sections["channels"] = ch
    return sections


def _tdms_waveform(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    t = _time_column(frame, time_col)
    dt = float(np.median(np.diff(t)))
    objects = [RootObject(properties={"name": path.stem}), GroupObject("Untitled")]
    for col in frame.columns:
        if col == time_col:
            continue
        props = {
            "wf_start_time": np.datetime64(_FIXED),
            "wf_start_offset": float(t[0]),
            "wf_increment": dt,
            "wf_samples": int(t.size),
            "unit_string": units.get(col, ""),
        }
        objects.append(ChannelObject("Untitled", col, frame[col].to_numpy(np.float64), props))
    with TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)


def appended_frame(frame: pd.DataFrame, time_col: str) -> pd.DataFrame:
    """Two acquisitions one after another ("lvm-appended"): the run's first
    :data:`APPENDED_FIRST_S` (the balance at rest), then the whole run, its times moved on so
    that they jump by :data:`APPENDED_GAP_S` from the first acquisition's last row."""
    t = _time_column(frame, time_col)
    dt = float(np.median(np.diff(t)))
    n1 = max(2, int(round(APPENDED_FIRST_S / dt)))
    first = frame.iloc[:n1]
    second = frame.copy()
    second[time_col] = np.round(t - t[0] + t[n1 - 1] + APPENDED_GAP_S, 9)
    return pd.concat([first, second], ignore_index=True)


def _lvm_appended(frame: pd.DataFrame, path: Path, time_col: str,
                  units: dict[str, str]) -> None:
    _lvm(appended_frame(frame, time_col), path, time_col, units, segments=1)


def _lvm(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str],
         segments: int = 2) -> None:
    """LabVIEW Measurement text: the file header, then the rows in ``segments`` blocks, each
    under its own segment header."""
    t = _time_column(frame, time_col)
    cols = [c for c in frame.columns if c != time_col]
    dt = float(np.median(np.diff(t)))
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
            "Decimal_Separator\t.", "Multi_Headings\tNo", "X_Columns\tOne",
            "Time_Pref\tRelative", "Operator\ttowtank synth", "Date\t2024/05/21",
            "Time\t09:00:00", "***End_of_Header***", ""]
    values = [t] + [frame[c].to_numpy(np.float64) for c in cols]
    half = t.size // 2
    out = io.StringIO()
    out.write("\n".join(head) + "\n")
    for lo, hi in ((0, half), (half, t.size)) if segments == 2 else ((0, t.size),):
        n = len(cols)
        out.write("\n".join([
            f"Channels\t{n}\t",
            "Samples\t" + "\t".join([str(hi - lo)] * n),
            "Date\t" + "\t".join(["2024/05/21"] * n),
            "Time\t" + "\t".join(["09:00:00"] * n),
            "Y_Unit_Label\t" + "\t".join(units.get(c, "") for c in cols),
            "X_Dimension\t" + "\t".join(["Time"] * n),
            "X0\t" + "\t".join([repr(float(t[lo]))] * n),
            "Delta_X\t" + "\t".join([repr(dt)] * n),
            "***End_of_Header***\t",
            "X_Value\t" + "\t".join(cols) + "\tComment",
        ]) + "\n")
        out.write(_lvm_rows([v[lo:hi] for v in values]))
        out.write("\n")
    path.write_text(out.getvalue(), encoding="utf-8")


def _lvm_rows(columns: list[np.ndarray]) -> str:
    """LVM data rows: the columns' ``repr`` (non-finite blank), tab-separated, each row ended
    by a tab."""
    return rows_text([column_texts(v, blank_infinite=True) for v in columns], "\t", row_end="\t")


def _eu_rows(columns: list[np.ndarray]) -> str:
    """European data rows: ``%.9g`` with decimal commas (non-finite blank), ``;``-separated;
    a lone line end for no rows."""
    text = rows_text([column_texts(v, "%.9g", blank_infinite=True) for v in columns], ";")
    return text.replace(".", ",") or "\n"


def _txt_eu(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    """A European export: a preamble, ';' separators, decimal commas, a units row; the speed
    column (whose unit is m/s) is written in mm/s to exercise the unit conversion."""
    out = {}
    unit_row = []
    for col in frame.columns:
        values = frame[col].to_numpy(np.float64)
        unit = units.get(col, "")
        if unit == "m/s" and "(" not in col:
            values, unit = values * 1000.0, "mm/s"
        out[col] = values
        unit_row.append(unit)
    lines = ["Lab B towing tank;;;", "Datum: 21.05.2024;Operator: synth;;",
             "Messung exportiert aus DAQ;;;", ";".join(frame.columns), ";".join(unit_row)]
    path.write_text("\n".join(lines) + "\n" + _eu_rows(list(out.values())), encoding="latin-1")


def _mat_v5(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    run = {variable_name(c): frame[c].to_numpy(np.float64) for c in frame.columns}
    scipy.io.savemat(str(path), {"run": run, "description": "towtank synth"}, format="5",
                     oned_as="column")


def _mat_v73(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    t = _time_column(frame, time_col)
    fs = 1.0 / float(np.median(np.diff(t)))
    with h5py.File(str(path), "w", userblock_size=512) as fh:
        for col in frame.columns:
            if col == time_col:
                continue
            ds = fh.create_dataset(variable_name(col),
                                   data=frame[col].to_numpy(np.float64)[None, :])
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        ds = fh.create_dataset("fs", data=np.array([[fs]]))
        ds.attrs["MATLAB_class"] = np.bytes_("double")
    header = (b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Tue May 21 09:00:00 2024 "
              b"HDF5 schema 1.00 .").ljust(116, b" ")
    with open(path, "r+b") as fh:
        fh.write(header + b"\x00" * 8 + b"\x00\x02" + b"IM")


def _hdf5(frame: pd.DataFrame, path: Path, time_col: str, units: dict[str, str]) -> None:
    t = _time_column(frame, time_col)
    with h5py.File(str(path), "w") as fh:
        grp = fh.create_group("data")
        grp.attrs["sample_rate"] = 1.0 / float(np.median(np.diff(t)))
        fh.attrs["description"] = "towtank synth"
        for col in frame.columns:
            ds = grp.create_dataset(col.replace("/", "_per_"),
                                    data=frame[col].to_numpy(np.float64))
            ds.attrs["unit"] = units.get(col, "")


def _hdf5_rate_name(frame: pd.DataFrame, path: Path, time_col: str,
                    units: dict[str, str]) -> None:
    """A MARIN-style export: the rate written only in the group's name (``/200.00 Hz``), a
    dataset per channel, no time dataset and no attributes."""
    t = _time_column(frame, time_col)
    fs = 1.0 / float(np.median(np.diff(t)))
    with h5py.File(str(path), "w") as fh:
        grp = fh.create_group(f"{fs:.2f} Hz")
        for col in frame.columns:
            if col != time_col:
                grp.create_dataset(col.replace("/", "_per_"),
                                   data=frame[col].to_numpy(np.float64))
