"""The design tool's [D] Table 6 with towtank: turning four hull families of the same bulk.

The design tool turns a Myring, a DARPA SUBOFF, a DRDC and a Series 58 vehicle of 150 kg at
1.25 m/s with 10 deg of rudder on equal fins and prints the tactical diameter, advance and
transfer over the length (:data:`TABLE6`). Its fins and mass properties are not printed; this
module states towtank's (:func:`table6_vehicles`): each hull at the table's length and diameter,
neutrally buoyant at 150 kg (B = W = 150 kg x g), the centre of gravity
:data:`BG_M` below the centre of buoyancy (the origin), the same rudder and stern-plane pairs
(:data:`FIN_SPAN_M`, :data:`FIN_CHORD_M`) with their quarter chord at :data:`FIN_STATION` of
the length from the nose, and the inertia of a body of uniform density filling each hull. The
DRDC standard submarine is left out: its bow and stern equations (Mackay 2003, DRDC Atlantic
TM 2003-079) were not available to towtank (docs/method.md, "Hull families").
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from types import SimpleNamespace
from typing import Any

import pandas as pd

from towtank.ingest.vehicle_protocol import Vehicle, VehicleFin
from towtank.vehicle import hull as hull_lib
from towtank.vehicle.model import G
from towtank.vehicle.simulate import manoeuvre_metrics, simulate
from towtank.vehicle.stage import predict_vehicle

__all__ = ["TABLE6", "BG_M", "FIN_SPAN_M", "FIN_CHORD_M", "FIN_STATION", "MASS_KG",
           "SPEED_M_S", "RUDDER_DEG", "MYRING_TABLE6", "table6_vehicles", "turning_comparison",
           "with_fins"]

#: [D] Table 6: hull, diameter [m], length [m], tactical diameter, advance, transfer [L].
TABLE6 = pd.DataFrame(
    [("myring", 0.32, 2.57, 10.1, 6.2, 4.9),
     ("suboff", 0.30, 2.59, 15.8, 11.05, 7.5),
     ("drdc", 0.29, 2.56, 10.2, 6.2, 5.85),
     ("series58", 0.344, 2.41, 11.25, 6.3, 5.75)],
    columns=["hull", "diameter_m", "length_m", "tactical_diameter_L", "advance_L",
             "transfer_L"])
#: The table's inputs ([D] Table 3): weight [kg], design speed [m/s], rudder angle [deg].
MASS_KG, SPEED_M_S, RUDDER_DEG = 150.0, 1.25, 10.0
#: towtank's choices where [D] prints none: centre of gravity below the centre of buoyancy
#: [m], one fin's span and chord [m], the fins' quarter chord as a fraction of the length.
BG_M, FIN_SPAN_M, FIN_CHORD_M, FIN_STATION = 0.015, 0.14, 0.12, 0.90
#: A Myring hull of the table's 2.57 m x 0.32 m that holds 150 kg of seawater (150.2 kg):
#: nose 2 D, tail 3.5 D, n = 2, tail semi-angle 15 deg. [D] does not print its parameters.
MYRING_TABLE6 = {"a": 0.64, "b": 0.81, "c": 1.12, "n": 2.0, "theta_deg": 15.0, "d": 0.32,
                 "a_offset": 0.0, "c_offset": 0.0}


@dataclass(frozen=True)
class _Water:
    type: str = "sea"
    temperature_C: float = 15.0  # noqa: N815 (the protocol's key)
    salinity_g_kg: float = 35.0


def table6_vehicles(hulls: tuple[str, ...] = ("myring", "suboff", "series58")
                    ) -> dict[str, Vehicle]:
    """The ``[vehicle]`` of each hull of Table 6 that towtank has, as stated in the module."""
    out = {}
    for _, row in TABLE6.set_index("hull").loc[list(hulls)].iterrows():
        name = row.name
        kwargs: dict[str, Any] = {}
        if name == "myring":
            profile = hull_lib.myring_profile(**MYRING_TABLE6)
            kwargs["myring"] = dict(MYRING_TABLE6)
        elif name == "suboff":
            profile = hull_lib.suboff_profile(row["length_m"])
            kwargs["length_m"] = float(row["length_m"])
        elif name == "series58":
            s58 = {"length_m": float(row["length_m"]), "diameter_m": float(row["diameter_m"]),
                   **hull_lib.SERIES58_PARENT}
            profile = hull_lib.series58_profile(**s58)
            kwargs["series58"] = s58
        else:
            raise ValueError(f"towtank has no {name} hull (docs/method.md, \"Hull families\").")
        x_fin = profile.x_buoyancy - FIN_STATION * profile.length
        fins = tuple(VehicleFin(plane, x_fin, FIN_SPAN_M, FIN_CHORD_M)
                     for plane in ("rudder", "sternplane"))
        out[name] = Vehicle(hull=name, name=f"Table 6 {name}", mass_kg=MASS_KG,
                            buoyancy_N=MASS_KG * G, cg_m=(0.0, 0.0, BG_M), cb_m=(0.0, 0.0, 0.0),
                            speed_m_s=SPEED_M_S, fins=fins, **kwargs)
    return out


def turning_comparison(hulls: tuple[str, ...] = ("myring", "suboff", "series58"),
                       vehicles: dict[str, Vehicle] | None = None) -> pd.DataFrame:
    """Turn each hull as [D] Table 6 does and set towtank's metrics beside the table's.

    Returns one row per hull: its volume [m^3] and displaced mass in the protocol's sea water
    [kg], wetted area [m^2], towtank's tactical diameter, advance, transfer and steady turn
    radius over the length [-] (``simulate --manoeuvre turning --rudder-deg 10`` at 1.25 m/s)
    and the table's three.
    """
    vehicles = vehicles or table6_vehicles(hulls)
    table = TABLE6.set_index("hull")
    rows = []
    for name, vehicle in vehicles.items():
        result = predict_vehicle(SimpleNamespace(vehicle=vehicle, water=_Water()))
        ts = simulate(result.model, "turning", SPEED_M_S, rudder_deg=RUDDER_DEG)
        m = manoeuvre_metrics(ts).set_index("metric")["value"]
        p, length = result.profile, result.profile.length
        rows.append({
            "hull": name, "length_m": length, "diameter_m": p.max_diameter,
            "volume_m3": p.volume, "displaced_kg": p.volume * result.rho,
            "wetted_area_m2": p.wetted_area,
            "tactical_diameter_L": m["tactical_diameter_m"] / length,
            "advance_L": m["advance_m"] / length, "transfer_L": m["transfer_m"] / length,
            "steady_radius_L": m["steady_turn_radius_m"] / length,
            "table6_tactical_diameter_L": table.loc[name, "tactical_diameter_L"],
            "table6_advance_L": table.loc[name, "advance_L"],
            "table6_transfer_L": table.loc[name, "transfer_L"],
        })
    return pd.DataFrame(rows)


def with_fins(vehicle: Vehicle, span_m: float, chord_m: float) -> Vehicle:
    """The same vehicle with every fin pair of ``span_m`` x ``chord_m`` [m]."""
    return replace(vehicle, fins=tuple(replace(f, span_m=span_m, chord_m=chord_m)
                                       for f in vehicle.fins))
