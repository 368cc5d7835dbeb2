"""A synthetic hull day in air: the SUT-2 hull on a wind tunnel's track or whirling arm.

The hull day of :mod:`towtank.testing.days` at twenty times its speeds, with forces, truth and
sting tare at the air's density (CIPM-2007, towtank.reference.air) and ``[water] type = "air"``
in its protocol; used by ``towtank synth --day air`` and the tests of the air medium.
"""

from __future__ import annotations

import datetime as _dt
from dataclasses import replace
from pathlib import Path
from typing import Any

from towtank.testing.days import (
    DayTruth,
    RunSpec,
    hull_day_plan,
    hull_protocol_sections,
    make_hull_day,
)
from towtank.testing.instruments import LabChannels, Noise, medium_properties
from towtank.testing.truth import (
    HULL_SAMPLE_SEED,
    ChannelStyle,
    FileFormat,
    SheetFormat,
    TareTruth,
    sut2_hull_truth,
)

__all__ = ["AIR_SPEED_FACTOR", "AIR_MODEL_MASS_KG", "air_hull_day_plan", "make_air_hull_day",
           "air_protocol_sections"]

#: Speed factor of the air day: the hull plan's speeds and accelerations times this (16-40 m/s,
#: wind-tunnel speeds at which the forces in air are about half those of the hull day in water).
AIR_SPEED_FACTOR = 20.0

#: Weighed mass of the air day's model [kg] (the SUT-2 hull's 0.552 kg in water): in air a
#: model is not ballasted, so the mass is the structure's.
AIR_MODEL_MASS_KG = 1.0


def air_hull_day_plan() -> list[RunSpec]:
    """The hull day's plan (:func:`hull_day_plan`) at :data:`AIR_SPEED_FACTOR` times its speeds
    and accelerations: the same 42 runs, at 2-40 m/s, the same phase durations."""
    k = AIR_SPEED_FACTOR
    return [replace(spec, speed=spec.speed * k, accel=spec.accel * k)
            for spec in hull_day_plan()]


def make_air_hull_day(
    out_dir: str | Path,
    *,
    seed: int = HULL_SAMPLE_SEED,
    fs: float = 200.0,
    file_format: FileFormat = "csv.gz",
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    channels: LabChannels | None = None,
    noise: Noise | None = None,
    temperature_C: float = 20.0,
    temperature_spread_C: tuple[float, float] | None = (-0.2, 0.3),
    date: str | _dt.date | None = None,
) -> DayTruth:
    """Write a synthetic hull day in air (a wind tunnel's track or whirling arm).

    The SUT-2 hull (:func:`sut2_hull_truth` at the air's density, weighed mass
    :data:`AIR_MODEL_MASS_KG`) on :func:`air_hull_day_plan`; the air at ``temperature_C``,
    101325 Pa and 50 % relative humidity (CIPM-2007 density, Sutherland viscosity), each run at
    its own temperature. The sting's drag terms are the hull day's scaled to air
    (``t2·ρ_air/ρ_water``, ``t1·ρ_air/ρ_water·k``); its inertia is unchanged. The truth's
    ``water`` is ``{"type": "air", ...}``.

    Parameters are those of :func:`make_hull_day` (``temperature_C`` the air temperature
    [degC]).

    Returns
    -------
    DayTruth
    """
    rho = float(medium_properties(temperature_C, "air").rho)
    ratio = rho / float(medium_properties(temperature_C, "fresh").rho)
    k = AIR_SPEED_FACTOR
    base = TareTruth()
    tare = TareTruth(t2=base.t2 * ratio, t1=base.t1 * ratio * k, m_t=base.m_t,
                     lift_t2=base.lift_t2 * ratio, lift_t1=base.lift_t1 * ratio * k,
                     lift_m_t=base.lift_m_t)
    return make_hull_day(
        out_dir, seed=seed, fs=fs, file_format=file_format, sheet_format=sheet_format,
        channel_style=channel_style, channels=channels, noise=noise,
        temperature_C=temperature_C, runs=air_hull_day_plan(),
        hull=sut2_hull_truth(rho, mass=AIR_MODEL_MASS_KG),
        tares={"A": tare}, temperature_spread_C=temperature_spread_C, water_type="air",
        tank_length_m=1000.0, date=date,
    )


def air_protocol_sections(
    day_dir: str = ".",
    output_dir: str = "out",
    *,
    sheet_format: SheetFormat = "xlsx",
    channel_style: ChannelStyle = "lab",
    channels: LabChannels | None = None,
    temperature_C: float = 20.0,
) -> dict[str, dict[str, Any]]:
    """The protocol of :func:`make_air_hull_day`: ``[water] type = "air"`` (101325 Pa and 50 %
    relative humidity, the defaults), the 1 kg model without a depth, a prototype in air at
    15 °C at 10-30 m/s.

    Parameters as :func:`hull_protocol_sections` (``temperature_C`` the air's [degC]).
    """
    sections = hull_protocol_sections(day_dir, output_dir, sheet_format=sheet_format,
                                      channel_style=channel_style, channels=channels,
                                      temperature_C=temperature_C, water_type="air")
    sections["campaign"]["name"] = "SUT-2 quarter-scale hull in air, synthetic day"
    sections["model"]["mass_kg"] = AIR_MODEL_MASS_KG
    del sections["model"]["depth_m"]  # no free surface
    sections["prototype"] = {"length_m": 1.412, "speeds_m_s": [10.0, 20.0, 30.0],
                             "water": {"type": "air", "temperature_C": 15.0}}
    return sections
