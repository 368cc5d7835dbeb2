"""``towtank scale``: print the model-to-prototype scaling table in the terminal."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pandas as pd

from towtank.analysis import similarity
from towtank.errors import ProtocolError
from towtank.ingest.protocol import (
    Prototype,
    Water,
    check_prototype_speed_range,
    load_protocol,
)
from towtank.runner import Options, Plan, reduce_day
from towtank.runtime.manifest import output_lock


def scale_command(
    protocol_path: Path, *, speeds: list[float] | None = None, out: Path | None = None
) -> int:
    """Print scaling.csv's table for chosen prototype speeds.

    The day is reduced through the per-run cache in the output folder (``.cache``), so after a
    ``towtank process`` no run file is read again; only the fits and the scaling are redone.
    Speeds that are not > 0 and at most 100 m/s, as in ``[prototype] speeds_m_s``
    (:func:`towtank.ingest.protocol.check_prototype_speed_range`), or give a prototype Re below
    1e3 (:func:`towtank.analysis.similarity.check_prototype_speeds`) are refused with a
    ProtocolError (exit status 2).
    """
    protocol = load_protocol(protocol_path)
    if speeds:  # as [prototype] speeds_m_s: > 0 and at most MAX_PROTOTYPE_SPEED
        check_prototype_speed_range(speeds, "--speeds")
    if protocol.model is None:
        raise ProtocolError(f"{protocol.path.name}: scaling needs a [model] section.")
    model = protocol.model
    proto = protocol.prototype
    if proto is None:
        if protocol.model.scale is None or not speeds:
            raise ProtocolError(
                f"{protocol.path.name}: scaling needs a [prototype] section, or [model] scale "
                "and --speeds."
            )
        proto = Prototype(
            length_m=protocol.model.length_m * protocol.model.scale,
            speeds_m_s=tuple(speeds),
            water=Water(type="sea", temperature_C=15.0),
        )
    elif speeds:
        proto = replace(proto, speeds_m_s=tuple(float(s) for s in speeds))
    _, nu_p = similarity.medium_at(proto.water)
    try:
        similarity.check_prototype_speeds(proto.speeds_m_s, proto.length_m, nu_p)
    except ValueError as exc:
        where = "--speeds" if speeds else f"{protocol.path.name}: 'speeds_m_s' in [prototype]"
        raise ProtocolError(f"{where} cannot be scaled: {exc}") from None
    protocol = replace(protocol, prototype=proto)
    out_dir = out if out is not None else protocol.campaign.output_dir
    # the cache of an earlier `process` into that folder is used (and added to); a folder
    # that does not exist is not created (scale prints, it writes no output)
    cache = Path(out_dir) / ".cache"
    plan = Plan(path=Path(protocol_path), protocol=protocol, out=None,
                options=Options(replay=False, record=False), jobs=protocol.processing.jobs,
                cache_dir=cache if cache.is_dir() else None)
    if plan.cache_dir is not None:
        # the reduction may add to the folder's cache: one writer at a time
        with output_lock(out_dir):
            day = reduce_day(plan).day
    else:
        day = reduce_day(plan).day
    if day.scaling is None:
        said = [str(n) for n in day.warnings if n.stage == "scaling"]
        print("no scaling table: " + " ".join(said[-1:]))
        return 1
    sc = day.scaling
    table = sc.table
    rec = sc.recommendation.column if sc.recommendation is not None else "none"
    ittc = "R_p ITTC-57 [N]" + (", recommended" if rec == "drag_ittc57" else "")
    froude = "R_p Froude [N]" + (", comparison" if rec == "drag_ittc57" else "")
    show = pd.DataFrame({
        "U_p [m/s]": table["speed_prototype"],
        "Re_p": table["re_prototype"].map(lambda v: f"{v:.3g}"),
        "Fn_p": table["fn_prototype"].map(lambda v: f"{v:.3f}"),
        "U_m Froude [m/s]": table["speed_model_froude"].map(lambda v: f"{v:.3f}"),
        "U_m Reynolds [m/s]": table["speed_model_reynolds"].map(lambda v: f"{v:.3f}"),
        ittc: table["drag_ittc57"].map(lambda v: f"{v:.2f}" if math.isfinite(v) else "–"),
        froude: [
            f"{v:.2f}" + ("" if ok else " *")
            for v, ok in zip(table["drag_froude"], table["froude_in_tested_range"], strict=True)
        ],
    })
    print(f"{protocol.name}: model L = {model.length_m:g} m, prototype "
          f"L = {proto.length_m:g} m (λ = {sc.scale:g}), {proto.water.medium} "
          f"{proto.water.temperature_C:g} °C")
    print(show.to_string(index=False))
    if not table["froude_in_tested_range"].all():
        print("* Froude-corresponding model speed outside the tested "
              f"{sc.tested_speed_range[0]:.2f}–{sc.tested_speed_range[1]:.2f} m/s: extrapolated")
    if sc.form_factor is not None:
        ff = sc.form_factor
        print(f"form factor 1 + k = {ff.one_plus_k:.3f} ± {ff.std:.3f} (s.d. over {ff.n} "
              f"tested speeds, {ff.n_runs} runs; ITTC-57)")
        if sc.form_factor_trend_text:
            print(sc.form_factor_trend_text)
    else:
        print("no form factor: R_p ITTC-57 needs the model's wetted area and runs above "
              "the laminar range")
    if sc.laminar_note:
        print(f"warning: {sc.laminar_note}")
    if sc.recommendation is not None:
        print(sc.recommendation.rule)
    print(sc.statement)
    return 0
