"""``towtank scale``: print the model-to-prototype scaling table in the terminal."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from towtank.errors import ProtocolError


def scale_command(
    protocol_path: Path, *, speeds: list[float] | None = None, out: Path | None = None
) -> int:
    """Print scaling.csv's table for chosen prototype speeds.

    The day is reduced through the per-run cache in the output folder (``.cache``), so after a
    ``towtank process`` no run file is read again; only the fits and the scaling are redone.
    """
    import pandas as pd

    from towtank.pipeline import process_day
    from towtank.protocol import Prototype, Water, load_protocol

    protocol = load_protocol(protocol_path)
    if protocol.model is None:
        raise ProtocolError(f"{protocol.path.name}: scaling needs a [model] section.")
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
    if any(s <= 0 for s in proto.speeds_m_s):
        raise ProtocolError("prototype speeds must be positive.")
    protocol = replace(protocol, prototype=proto)
    out_dir = out if out is not None else protocol.campaign.output_dir
    day = process_day(protocol_path, protocol=protocol, cache_dir=Path(out_dir) / ".cache")
    if day.scaling is None:
        print("no scaling table: " + " ".join(day.warnings[-1:]))
        return 1
    sc = day.scaling
    table = sc.table
    show = pd.DataFrame({
        "U_p [m/s]": table["speed_prototype"],
        "Re_p": table["re_prototype"].map(lambda v: f"{v:.3g}"),
        "Fn_p": table["fn_prototype"].map(lambda v: f"{v:.3f}"),
        "U_m Froude [m/s]": table["speed_model_froude"].map(lambda v: f"{v:.3f}"),
        "U_m Reynolds [m/s]": table["speed_model_reynolds"].map(lambda v: f"{v:.3f}"),
        "R_p Froude [N]": [
            f"{v:.2f}" + ("" if ok else " *")
            for v, ok in zip(table["drag_froude"], table["froude_in_tested_range"], strict=True)
        ],
        "R_p ITTC-57 [N]": table["drag_ittc57"].map(lambda v: f"{v:.2f}"),
    })
    print(f"{protocol.name}: model L = {protocol.model.length_m:g} m, prototype "
          f"L = {proto.length_m:g} m (λ = {sc.scale:g}), {proto.water.type} water "
          f"{proto.water.temperature_C:g} °C")
    print(show.to_string(index=False))
    if not table["froude_in_tested_range"].all():
        print("* Froude-corresponding model speed outside the tested "
              f"{sc.tested_speed_range[0]:.2f}–{sc.tested_speed_range[1]:.2f} m/s: extrapolated")
    if sc.form_factor is not None:
        ff = sc.form_factor
        print(f"form factor 1 + k = {ff.one_plus_k:.3f} ± {ff.std:.3f} (n = {ff.n}, ITTC-57)")
    print(sc.statement)
    return 0
