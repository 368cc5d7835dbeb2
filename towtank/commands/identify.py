"""``towtank identify``: coefficients of a model.json from a manoeuvre record (issue #25)."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from towtank.commands.storage import write_outputs_or_stop
from towtank.errors import ProtocolError
from towtank.report.identify_figure import save_identify_figure
from towtank.vehicle import schema
from towtank.vehicle.identify import identify
from towtank.vehicle.identify_log import STATE_COLUMNS, LogError, read_log
from towtank.vehicle.model import read_model, write_model

#: The files ``identify`` writes.
IDENTIFY_OUTPUTS = frozenset({"identified.csv", "model.json", "identify.png"})


def _channels(protocol: Path | None) -> dict[str, Any] | None:
    """The ``[channels]`` table of an optional protocol (TOML)."""
    if protocol is None:
        return None
    name = Path(protocol).name
    try:
        with open(protocol, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise ProtocolError(f"{name}: no such file.") from None
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"{name}: cannot be read as TOML ({exc}).") from None
    table = data.get("channels", {})
    if not isinstance(table, dict):
        raise ProtocolError(f"{name}: [channels] must be a table.")
    return table


def parse_noise(text: str | None) -> dict[str, float]:
    """``--noise u=0.01,r=0.2,psi=0.5``: standard deviation per state, in the state's column
    unit (m, deg, m/s, deg/s); short names (``u``, ``psi``) or the columns (``u_m_s``)."""
    out: dict[str, float] = {}
    if not text:
        return out
    short = {c.split("_", 1)[0]: c for c in STATE_COLUMNS}
    for part in text.split(","):
        if not part.strip():
            continue
        key, sep, val = part.partition("=")
        key = key.strip()
        col = short.get(key, key)
        if not sep or col not in STATE_COLUMNS:
            raise ProtocolError(f"--noise: {part.strip()!r} is not state=sd (states: "
                                f"{', '.join(short)}).")
        try:
            sd = float(val)
        except ValueError:
            sd = float("nan")
        if not (math.isfinite(sd) and sd >= 0):
            raise ProtocolError(f"--noise: the standard deviation of {key} must be a number "
                                f">= 0, not {val.strip()!r}.")
        out[col] = sd
    return out


def identify_command(model_path: Path, log_path: Path, estimate: str, *, method: str = "ukf",
                     start: str = "model", out: Path | None = None,
                     protocol: Path | None = None, noise: str | None = None) -> int:
    """Identify, write identified.csv, model.json and identify.png; print one verdict line per
    coefficient."""
    name = Path(model_path).name
    try:
        model = read_model(model_path)
    except schema.ModelError as exc:
        raise ProtocolError(schema.joined(exc.problems)) from None
    symbols = [s.strip() for s in (estimate or "").split(",") if s.strip()]
    folder = Path(out) if out is not None else Path.cwd() / "identify"
    if (folder / "model.json").resolve() == Path(model_path).resolve():
        raise ProtocolError(f"--out {folder} holds the input {name}; identify never writes over "
                            "its input, give another folder.")
    try:
        log = read_log(log_path, _channels(protocol))
    except LogError as exc:
        raise ProtocolError(str(exc)) from None
    try:
        result = identify(model, log, symbols, method=method, start=start,
                          noise=parse_noise(noise) or None)
    except ValueError as exc:
        raise ProtocolError(f"{Path(log_path).name}: {exc}") from None
    table = result.table()
    updated = dict(model)
    coef = dict(model.get("coefficients") or {})
    sources = dict(model.get("sources") or {})
    for s, v in zip(result.symbols, result.value, strict=True):
        coef[s] = float(v)
        sources[s] = "identified"
    updated["coefficients"] = coef
    updated["sources"] = sources
    old = model.get("covariance") or {}
    old_sym = [s for s in (old.get("symbols") or []) if s not in result.symbols]
    syms = old_sym + list(result.symbols)
    mat = np.zeros((len(syms), len(syms)))
    if old_sym:
        idx = [list(old["symbols"]).index(s) for s in old_sym]
        mat[:len(old_sym), :len(old_sym)] = np.asarray(old["matrix"], dtype=float)[
            np.ix_(idx, idx)]
    cov = np.array(result.covariance, dtype=float)
    free = ~np.isfinite(np.diag(cov))  # a direction the record does not constrain
    cov[free, :] = 0.0
    cov[:, free] = 0.0
    cov[free, free] = 1e300
    cov[~np.isfinite(cov)] = 0.0
    mat[len(old_sym):, len(old_sym):] = cov
    updated["covariance"] = {"symbols": syms, "matrix": mat.tolist()}
    notes = dict(model.get("notes") or {})
    notes["identified"] = (f"{', '.join(result.symbols)} identified by {result.method} from "
                           f"{Path(log_path).name} (towtank identify); covariance of the "
                           "identified values in 'covariance'")
    updated["notes"] = notes

    def write(tmp: Path) -> None:
        table.to_csv(tmp / "identified.csv", index=False, float_format="%.6g")
        write_model(updated, tmp / "model.json")
        save_identify_figure(result, tmp / "identify.png", str(model.get("name", "model")))

    write_outputs_or_stop(folder, IDENTIFY_OUTPUTS, write)
    for note in result.notes:
        print(f"note: {note}")
    for line in result.verdicts():
        print(line)
    print(f"wrote {folder / 'identified.csv'}, model.json and identify.png")
    return 0
