"""Each run's non-dimensional numbers: C_D, C_L, Re and Fn of runs.csv (docs/formats.md §5).

C = F / (½ρ·A·U²) on the reference area of the run's configuration (the hull's frontal area,
its lateral area for a transverse tow, the fin's planform area), Re = U·L/ν and
Fn = U/√(g·L) on its reference length (the hull's length, the fin's chord).
"""

from __future__ import annotations

from typing import Any

from towtank.analysis.similarity import froude_number, reynolds_number
from towtank.ingest.protocol import Fin, Model
from towtank.reduce.run import force_coefficient

#: A hull run within this of α = 90° is a transverse tow [deg] (the hull fit's angle tolerance):
#: its drag coefficient is on the lateral area, as C_D,90 of Y_v|v|.
TRANSVERSE_TOL_DEG = 0.5


def run_coefficients(config: str, angle_deg: float, drag: float, lift: float, speed: float,
                     rho: float, nu: float, model: Model | None, fin: Fin | None
                     ) -> dict[str, Any]:
    """runs.csv's coefficient columns of one usable run.

    Parameters
    ----------
    config : str
        The run's configuration: "hull", "fin" or "sting".
    angle_deg : float
        Angle of attack [deg].
    drag, lift : float
        Steady mean forces, tare subtracted [N].
    speed : float
        Steady mean speed U [m/s].
    rho, nu : float
        Water density [kg/m³] and kinematic viscosity [m²/s] at the run's temperature.
    model, fin : Model or None, Fin or None
        The protocol's [model] and [fin].

    Returns
    -------
    dict
        The columns the run has: ``cd``, ``cl``, ``cd_lateral`` [-], ``cd_ref`` [-],
        ``ref_area`` ("frontal", "lateral", "fin"), ``ref_area_m2`` [m²], ``re``, ``fn`` [-].
    """
    out: dict[str, Any] = {}
    ref_len = None
    if config == "hull" and model is not None:
        area, ref_len = model.frontal_area, model.length_m
        out["cd"] = force_coefficient(drag, rho, area, speed)
        out["cl"] = force_coefficient(lift, rho, area, speed)
        out["cd_lateral"] = force_coefficient(drag, rho, model.lateral_area, speed)
        if abs(float(angle_deg) - 90.0) <= TRANSVERSE_TOL_DEG:  # a transverse tow
            out.update(cd_ref=out["cd_lateral"], ref_area="lateral",
                       ref_area_m2=model.lateral_area)
        else:
            out.update(cd_ref=out["cd"], ref_area="frontal", ref_area_m2=area)
    elif config == "fin" and fin is not None:
        area, ref_len = fin.area, fin.chord_m
        out["cd"] = force_coefficient(drag, rho, area, speed)
        out["cl"] = force_coefficient(lift, rho, area, speed)
        out.update(cd_ref=out["cd"], ref_area="fin", ref_area_m2=area)
    elif model is not None:
        ref_len = model.length_m
    elif fin is not None:
        ref_len = fin.chord_m
    if ref_len:
        out["re"] = float(reynolds_number(speed, ref_len, nu))
        out["fn"] = float(froude_number(speed, ref_len))
    return out
