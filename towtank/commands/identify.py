"""``towtank identify``: coefficients of a model.json from a manoeuvre record."""

from __future__ import annotations

import argparse
import sys
import tomllib
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from towtank.commands.storage import write_outputs_or_stop
from towtank.errors import ProtocolError
from towtank.report.identify_figure import save_identify_figure
from towtank.vehicle import schema
from towtank.vehicle.adequacy import failure_sentence
from towtank.vehicle.identify import Progress, identify
from towtank.vehicle.identify_log import LogError, parse_noise, read_log
from towtank.vehicle.model import kept_conversions, read_model, write_model

#: The files ``identify`` writes.
IDENTIFY_OUTPUTS = frozenset({"identified.csv", "model.json", "identify.png", "fit.csv"})


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


def noise_option(text: str) -> dict[str, float]:
    """The argparse type of identify's ``--noise``: :func:`parse_noise` with every standard
    deviation above 0; its sentence as the parser's error (usage line, exit 2)."""
    try:
        return parse_noise(text, positive=True)
    except ProtocolError as exc:
        # argparse starts the sentence with "argument --noise: "
        raise argparse.ArgumentTypeError(
            str(exc).removeprefix("--noise: ").removeprefix("--noise ")) from None


@contextmanager
def progress_bar(show: bool) -> Iterator[Progress | None]:
    """A progress bar on stderr (tqdm) that shows each stage of the identification in turn
    (:data:`towtank.vehicle.identify.Progress`); None when not ``show``."""
    if not show:
        yield None
        return
    # loaded on use: tqdm only for a progress bar on a terminal
    from tqdm import tqdm

    tqdm.monitor_interval = 0  # no monitor thread, as for process
    bars: list[Any] = []  # the bar, made at the first stage

    def progress(stage: str, done: int, total: int) -> None:
        if not bars:
            bars.append(tqdm(total=total, desc=stage, file=sys.stderr, leave=False))
        bar = bars[0]
        if bar.desc != stage or bar.total != total:
            bar.set_description_str(stage, refresh=False)
            bar.reset(total=total)  # redrawn with the new stage
        bar.update(done - bar.n)

    try:
        yield progress
    finally:
        for bar in bars:
            bar.close()


def identify_command(model_path: Path, log_path: Path, estimate: str, *, method: str = "ukf",
                     start: str = "model", out: Path | None = None,
                     protocol: Path | None = None,
                     noise: str | Mapping[str, float] | None = None, quiet: bool = False,
                     validate: Path | None = None) -> int:
    """Identify, write identified.csv, model.json, identify.png and fit.csv; print one verdict
    line per coefficient. ``noise``: the text of ``--noise`` or what :func:`noise_option` made
    of it; a progress bar on stderr when it is a terminal, unless ``quiet``; ``validate``: a
    second record the identified model is tested against.

    Returns 0, or 1 when the record does not fit the model (a test of fit.csv failed: one
    sentence on stderr naming it, every verdict ``model does not fit``)."""
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
        channels = _channels(protocol)
        log = read_log(log_path, channels)
        second = None if validate is None else read_log(validate, channels)
    except LogError as exc:
        raise ProtocolError(str(exc)) from None
    if isinstance(noise, str):
        noise = parse_noise(noise, positive=True)
    in_trim, said = trim_check(model, log)  # a warning to stderr, the in-trim sentence to stdout
    print(said, file=sys.stdout if in_trim else sys.stderr)
    try:
        with progress_bar(not quiet and sys.stderr.isatty()) as progress:
            fit = identify(model, log, symbols, method=method, start=start,
                           noise=dict(noise or {}) or None, progress=progress,
                           validate=second)
    except ValueError as exc:
        raise ProtocolError(f"{Path(log_path).name}: {exc}") from None
    # loaded on use: the results package loads the day's stages, which identify needs only here
    from towtank.results.identify import IdentifyResult
    from towtank.results.summary import from_fit

    result = from_fit(IdentifyResult, fit)
    table = result.table()
    # only what the record determined replaces the model's values: an estimate that is not
    # identifiable, or one from a record that does not fit the model, is said, not kept
    kept = np.asarray(result.identifiable(), dtype=bool) & bool(result.fits())
    idents = [s for s, k in zip(result.symbols, kept, strict=True) if k]
    left = [s for s, k in zip(result.symbols, kept, strict=True) if not k]
    updated = dict(model)
    coef = dict(model.get("coefficients") or {})
    sources = dict(model.get("sources") or {})
    for s, v, k in zip(result.symbols, result.value, kept, strict=True):
        if k:
            coef[s] = float(v)
            sources[s] = "identified"
    updated["coefficients"] = coef
    updated["sources"] = sources
    if isinstance(model.get("conversions"), dict):  # read_model checked it
        updated["conversions"] = kept_conversions(model["conversions"], idents)
    old = model.get("covariance") or {}
    old_sym = [s for s in (old.get("symbols") or []) if s not in idents]
    syms = old_sym + idents
    mat = np.zeros((len(syms), len(syms)))
    if old_sym:
        idx = [list(old["symbols"]).index(s) for s in old_sym]
        mat[:len(old_sym), :len(old_sym)] = np.asarray(old["matrix"], dtype=float)[
            np.ix_(idx, idx)]
    cov = np.array(result.covariance, dtype=float)[np.ix_(kept, kept)]
    free = ~np.isfinite(np.diag(cov))  # a direction the record does not constrain
    cov[free, :] = 0.0
    cov[:, free] = 0.0
    cov[free, free] = 1e300
    cov[~np.isfinite(cov)] = 0.0
    mat[len(old_sym):, len(old_sym):] = cov
    updated["covariance"] = {"symbols": syms, "matrix": mat.tolist()}
    notes = dict(model.get("notes") or {})
    told = [f"{', '.join(idents)} identified by {result.method} from {Path(log_path).name} "
            "(towtank identify); covariance of the identified values in 'covariance'"] \
        if idents else []
    if left:
        why = ("not identifiable from it" if result.fits()
               else "the record does not fit the model (fit.csv)")
        told.append(f"{', '.join(left)} kept at the model's values: {why}")
    notes["identified"] = "; ".join(told)
    updated["notes"] = notes

    def write(tmp: Path) -> None:
        table.to_csv(tmp / "identified.csv", index=False, float_format="%.6g")
        write_model(updated, tmp / "model.json")
        save_identify_figure(result, tmp / "identify.png", str(model.get("name", "model")))
        if result.adequacy is not None:
            result.adequacy.to_csv(tmp / "fit.csv", index=False, float_format="%.6g")

    write_outputs_or_stop(folder, IDENTIFY_OUTPUTS, write)
    for note in result.notes:
        print(f"note: {note}")
    for line in result.verdicts():
        print(line)
    for said in result.against_model(model.get("coefficients") or {}):
        print(f"warning: {said}", file=sys.stderr)
    print(f"wrote {folder / 'identified.csv'}, model.json, identify.png and fit.csv")
    misfit = failure_sentence(result.adequacy) if result.adequacy is not None else None
    if misfit:
        print(f"error: {misfit}", file=sys.stderr)
        return 1
    return 0


def trim_check(model: Mapping[str, Any], log: Any) -> tuple[bool, str]:
    """Whether the model is in trim at the record's starting speed, as ``simulate`` checks it
    (:func:`towtank.vehicle.simulate.trim_warning`), and the one sentence that says so:
    ``warning: ...`` when out of trim, else ``trim: ...``."""
    # loaded on use: simulate's module (scipy.integrate) is needed only here
    from towtank.vehicle.identify import record_speed
    from towtank.vehicle.simulate import trim_warning

    speed = record_speed(dict(model), log)
    warning = trim_warning(dict(model), speed)
    if warning:
        return False, f"warning: {warning}"
    return True, (f"trim: the model is in trim at {speed:.3g} m/s, the record's starting speed "
                  "(with zero controls its steady pitch and depth rate are within simulate's "
                  "limits).")
