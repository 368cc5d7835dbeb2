"""``[vehicle.propeller]`` and ``[vehicle.pressure_hull]``: the design sections of predict.

Each is optional; parsed and checked here (one sentence naming the key, a
:class:`~towtank.errors.ProtocolError`, exit 2) and turned into powering.csv
(:mod:`towtank.vehicle.powering`) and pressure_hull.csv (:mod:`towtank.vehicle.pressure_hull`)
by ``towtank predict`` (docs/formats.md §6).
"""

from __future__ import annotations

from typing import Any

from towtank.errors import ProtocolError
from towtank.ingest.values import finite_number, shown

__all__ = ["PROPELLER_KEYS", "PRESSURE_HULL_KEYS", "parse_propeller", "parse_pressure_hull"]

#: key -> (required, default, low, high, what); the range is inclusive.
PROPELLER_KEYS: dict[str, tuple[bool, Any, float, float, str]] = {
    "diameter_m": (True, None, 1e-3, 100.0, "propeller diameter D [m]"),
    "pitch_ratio": (True, None, 0.5, 1.4, "pitch ratio P/D of the B-series"),
    "blade_area_ratio": (True, None, 0.30, 1.05, "expanded area ratio A_E/A_0 of the B-series"),
    "blades": (False, 3, 2, 7, "number of blades of the B-series"),
    "thrust_deduction": (False, 0.0, 0.0, 0.9, "thrust deduction t"),
    "wake_fraction": (False, 0.0, 0.0, 0.9, "wake fraction w"),
    "speeds_m_s": (False, None, 1e-3, 100.0, "speeds of powering.csv [m/s]"),
}
PRESSURE_HULL_KEYS: dict[str, tuple[bool, Any, float, float, str]] = {
    "depth_m": (True, None, 0.1, 11000.0, "design depth [m]"),
    "yield_MPa": (True, None, 1.0, 5000.0, "yield stress of the material [MPa]"),
    "E_GPa": (True, None, 0.1, 1000.0, "Young's modulus [GPa]"),
    "poisson": (False, 0.3, 0.0, 0.5, "Poisson's ratio"),
    "safety_factor": (False, 1.5, 1.0, 10.0, "safety factor on the pressure"),
    "radius_m": (False, None, 1e-3, 100.0, "hull radius R [m] (default the hull's largest)"),
    "frame_spacing_m": (False, None, 1e-3, 1000.0,
                        "unsupported length l [m] (default the hull's length)"),
}


def _parse(raw: Any, keys: dict, label: str, src: str) -> dict[str, Any]:
    if not isinstance(raw, dict):
        raise ProtocolError(f"{src}: [{label}] must be a table of keys, but it is {raw!r}.")
    out: dict[str, Any] = {}
    for key in raw:
        if key not in keys:
            raise ProtocolError(f"{src}: unknown key '{key}' in [{label}] (known: "
                                f"{', '.join(keys)}).")
    for key, (required, default, low, high, what) in keys.items():
        if key not in raw:
            if required:
                raise ProtocolError(f"{src}: [{label}] is missing the required key '{key}' "
                                    f"({what}).")
            out[key] = default
            continue
        value = raw[key]
        values = value if isinstance(value, list) else [value]
        if key != "speeds_m_s" and isinstance(value, list):
            values = [None]
        if key == "speeds_m_s" and (not isinstance(value, list) or not value):
            values = [None]
        nums = []
        for v in values:
            number = finite_number(v)
            if number is None or not (low <= number <= high):
                raise ProtocolError(f"{src}: '{key}' in [{label}] must be "
                                    f"{'a list of numbers' if key == 'speeds_m_s' else 'a number'}"
                                    f" from {low:g} to {high:g} ({what}), but it is "
                                    f"{shown(value)}.")
            nums.append(number)
        out[key] = nums if key == "speeds_m_s" else nums[0]
    return out


def parse_propeller(raw: Any, src: str, label: str = "vehicle.propeller") -> dict[str, Any]:
    """The checked ``[vehicle.propeller]`` (keys :data:`PROPELLER_KEYS`); ``label`` names the
    section in the sentences (model.json's block: ``propeller``)."""
    out = _parse(raw, PROPELLER_KEYS, label, src)
    if out["blades"] != int(out["blades"]):
        raise ProtocolError(f"{src}: 'blades' in [{label}] must be a whole number, "
                            f"but it is {out['blades']}.")
    out["blades"] = int(out["blades"])
    return out


def parse_pressure_hull(raw: Any, src: str) -> dict[str, Any]:
    """The checked ``[vehicle.pressure_hull]`` (keys :data:`PRESSURE_HULL_KEYS`)."""
    return _parse(raw, PRESSURE_HULL_KEYS, "vehicle.pressure_hull", src)
