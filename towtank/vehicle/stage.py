"""The vehicle stage of a protocol with a ``[vehicle]``: prediction and model in one call."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from towtank.reference import water as water_props
from towtank.vehicle import model as vmodel
from towtank.vehicle.hull import HullProfile
from towtank.vehicle.predict import FinPair, predict_coefficients


@dataclass(frozen=True)
class VehiclePrediction:
    """What ``towtank predict`` writes: the predicted table and the model."""

    profile: HullProfile
    predicted: pd.DataFrame
    masses: dict[str, Any]
    rho: float
    nu: float
    model: dict[str, Any]


def predict_vehicle(protocol: Any, measured: dict[str, float] | None = None,
                    covariance: tuple[list[str], np.ndarray] | None = None) -> VehiclePrediction:
    """Predict the coefficients of the protocol's ``[vehicle]`` and build its model.

    The water is the protocol's [water] (ITTC density and viscosity at its temperature).
    ``measured`` (SI values by symbol) and their ``covariance`` take precedence over the
    prediction in the model (sources "measured").
    """
    vehicle = protocol.vehicle
    w = protocol.water
    rho = float(water_props.density(w.temperature_C, w.type, w.salinity_g_kg))
    nu = float(water_props.kinematic_viscosity(w.temperature_C, w.type, w.salinity_g_kg))
    profile = vmodel.vehicle_profile(vehicle)
    fins = [FinPair(f.plane, f.x_m, f.span_m, f.chord_m, f.section, f.taper)
            for f in vehicle.fins]
    predicted = predict_coefficients(profile, fins, rho=rho, nu=nu, speed_m_s=vehicle.speed_m_s,
                                     x_origin_m=vehicle.origin_m)
    masses = vmodel.mass_properties(vehicle, profile, rho)
    model = vmodel.build_model(vehicle.name, rho, masses, predicted, measured, covariance)
    model["design_speed_m_s"] = float(vehicle.speed_m_s)
    model["length_m"] = float(profile.length)
    if vehicle.fin_limit_deg is not None:
        model["fin_limit_deg"] = float(vehicle.fin_limit_deg)
    return VehiclePrediction(profile, predicted, masses, rho, nu, model)
