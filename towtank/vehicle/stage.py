"""The vehicle stage of a protocol with a ``[vehicle]``: prediction and model in one call."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from towtank.ingest.glider_inputs import HullBounds, glider_problems
from towtank.reference import water as water_props
from towtank.vehicle import model as vmodel
from towtank.vehicle.assumptions import neutral_warning, vehicle_assumptions
from towtank.vehicle.hull import HullProfile
from towtank.vehicle.powering import PROPELLER_FIELDS, powering_table, propeller_from
from towtank.vehicle.predict import FinPair, axial_drag, predict_coefficients
from towtank.vehicle.pressure_hull import pressure_hull_table
from towtank.vehicle.schema import (
    stability_warning,
    vehicle_geometry_problems,
    vehicle_mass_problems,
)


@dataclass(frozen=True)
class VehiclePrediction:
    """What ``towtank predict`` writes: the predicted table and the model."""

    profile: HullProfile
    predicted: pd.DataFrame
    masses: dict[str, Any]
    rho: float
    nu: float
    model: dict[str, Any]
    powering: pd.DataFrame | None = None  # powering.csv, with [vehicle.propeller]
    pressure_hull: pd.DataFrame | None = None  # pressure_hull.csv, with [vehicle.pressure_hull]
    warnings: tuple[str, ...] = ()  # e.g. a neutral vehicle whose hull displaces far more


def predict_vehicle(protocol: Any, measured: dict[str, float] | None = None,
                    covariance: tuple[list[str], np.ndarray] | None = None,
                    forms: dict[str, str] | None = None) -> VehiclePrediction:
    """Predict the coefficients of the protocol's ``[vehicle]`` and build its model.

    The water is the protocol's [water] (ITTC density and viscosity at its temperature).
    ``measured`` (SI values by symbol) and their ``covariance`` take precedence over the
    prediction in the model (sources "measured"); ``forms`` says which of them are totals
    (captive tests) to convert to the Fossen form
    (:func:`towtank.vehicle.model.build_model`).
    """
    vehicle = protocol.vehicle
    w = protocol.water
    rho = float(water_props.density(w.temperature_C, w.type, w.salinity_g_kg))
    nu = float(water_props.kinematic_viscosity(w.temperature_C, w.type, w.salinity_g_kg))
    profile = vmodel.vehicle_profile(vehicle)
    _check_geometry(vehicle, profile)
    fins = [FinPair(f.plane, f.x_m, f.span_m, f.chord_m, f.section, f.taper,
                    getattr(f, "x_drag_m", None)) for f in vehicle.fins]
    predicted = predict_coefficients(profile, fins, rho=rho, nu=nu, speed_m_s=vehicle.speed_m_s,
                                     x_origin_m=vehicle.origin_m,
                                     added_mass=getattr(vehicle, "added_mass", "towtank"),
                                     damping=getattr(vehicle, "damping", "towtank"),
                                     fin_lift=getattr(vehicle, "fin_lift", "towtank"))
    masses = vmodel.mass_properties(vehicle, profile, rho)
    model = vmodel.build_model(vehicle.name, rho, masses, predicted, measured, covariance,
                               forms=forms)
    model["design_speed_m_s"] = float(vehicle.speed_m_s)
    model["length_m"] = float(profile.length)
    model["sources"]["hull"] = profile.source
    model["hull"] = {"name": profile.name, "length_m": float(profile.length),
                     "diameter_m": float(profile.max_diameter),
                     "volume_m3": float(profile.volume),
                     "wetted_area_m2": float(profile.wetted_area),
                     "x_buoyancy_m": float(profile.x_buoyancy)}
    if vehicle.fin_limit_deg is not None:
        model["fin_limit_deg"] = float(vehicle.fin_limit_deg)
    if getattr(vehicle, "glider", None) is not None:  # [vehicle.glider] (#26)
        _check_glider(vehicle, profile, float(model["mass_kg"]))
        model["glider"] = dict(vehicle.glider)
    if getattr(vehicle, "propeller", None) is not None:  # simulate --propeller rps
        model["propeller"] = {k: vehicle.propeller[k] for k in PROPELLER_FIELDS}
    model["assumptions"] = vehicle_assumptions(vehicle, masses, getattr(vehicle, "assumed", None))
    warning = neutral_warning(str(vehicle.name), masses, float(profile.volume), rho)
    upright = stability_warning(model.get("cg_m"), model.get("cb_m"), "[vehicle]")
    return VehiclePrediction(profile, predicted, masses, rho, nu, model,
                             _powering(vehicle, profile, fins, rho, nu),
                             _pressure_hull(vehicle, profile, rho),
                             tuple(w for w in (warning, upright) if w))


def geometry_problem(vehicle: Any) -> str | None:
    """The first problem of ``[vehicle]``'s reference point, fins and centres against the
    hull it describes (:func:`towtank.vehicle.schema.vehicle_geometry_problems`), for a day
    to stop on before anything is read or written; None when there is none, or when the hull
    itself cannot be built (the vehicle stage says why in its warning)."""
    try:
        profile = vmodel.vehicle_profile(vehicle)
    except ValueError:
        return None
    problems = _problems(vehicle, profile)
    return problems[0] if problems else None


def _problems(vehicle: Any, profile: HullProfile) -> list[str]:
    """What [vehicle] gives that its hull cannot have: positions and sizes
    (:func:`towtank.vehicle.schema.vehicle_geometry_problems`), then mass, volume and
    inertia (:func:`towtank.vehicle.schema.vehicle_mass_problems`)."""
    length = float(profile.length)
    return (vehicle_geometry_problems(vehicle, length, _reference_x(vehicle, profile))
            + vehicle_mass_problems(vehicle, float(profile.volume), length))


def _reference_x(vehicle: Any, profile: HullProfile) -> float:
    """x [m] aft of the nose tip of the vehicle's reference point: ``origin_m``, else the
    hull's centre of buoyancy."""
    return profile.x_buoyancy if vehicle.origin_m is None else float(vehicle.origin_m)


def _check_geometry(vehicle: Any, profile: HullProfile) -> None:
    """``[vehicle]``'s reference point, fins and centres against the hull it describes, before
    anything is computed from them.

    Raises
    ------
    ValueError
        Its first problem (:func:`towtank.vehicle.schema.vehicle_geometry_problems`): e.g. a fin
        typed in millimetres, whose span would be longer than the hull.
    """
    problems = _problems(vehicle, profile)
    if problems:
        raise ValueError(problems[0])


def _check_glider(vehicle: Any, profile: HullProfile, mass_kg: float) -> None:
    """``[vehicle.glider]`` against the hull that holds it and the vehicle's mass [kg].

    Raises
    ------
    ValueError
        Its first problem (:func:`towtank.ingest.glider_inputs.glider_problems`).
    """
    nose = profile.x_buoyancy if vehicle.origin_m is None else float(vehicle.origin_m)
    hull = HullBounds(float(profile.length), 0.5 * float(profile.max_diameter),
                      float(profile.volume), (nose - float(profile.length), nose))
    problems = glider_problems(vehicle.glider, "[vehicle.glider]", mass_kg, hull)
    if problems:
        raise ValueError(problems[0])


#: Speeds of powering.csv without ``speeds_m_s``: these fractions of the design speed.
POWERING_SPEED_FRACTIONS = (0.5, 0.75, 1.0, 1.25, 1.5)


def _powering(vehicle: Any, profile: HullProfile, fins: list[FinPair], rho: float,
              nu: float) -> pd.DataFrame | None:
    """powering.csv of ``[vehicle.propeller]``: R = -X_u|u| U^2 at each speed's Re."""
    raw = getattr(vehicle, "propeller", None)
    if raw is None:
        return None
    speeds = raw["speeds_m_s"] or [f * vehicle.speed_m_s for f in POWERING_SPEED_FRACTIONS]
    resistance = [-axial_drag(profile, fins, rho, nu, u) * u * u for u in speeds]
    return powering_table(speeds, resistance, propeller_from(raw), rho)


def _pressure_hull(vehicle: Any, profile: HullProfile, rho: float) -> pd.DataFrame | None:
    """pressure_hull.csv of ``[vehicle.pressure_hull]`` (design tool eqs. 5-7)."""
    raw = getattr(vehicle, "pressure_hull", None)
    if raw is None:
        return None
    radius = raw["radius_m"] or 0.5 * profile.max_diameter
    spacing = raw["frame_spacing_m"] or profile.length
    return pressure_hull_table(raw["depth_m"], radius, spacing, raw["yield_MPa"] * 1e6,
                               raw["E_GPa"] * 1e9, raw["poisson"], raw["safety_factor"], rho)
