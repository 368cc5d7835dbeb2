"""The Fossen-form manoeuvring model of a vehicle and its ``model.json`` (docs/formats.md).

``M nu_dot + C_RB(nu) nu + C_A(nu) nu + D(nu) nu + g(eta) = tau`` (Fossen 2011, eqs. 7.190 and
6.43; SUT-2 report eqs. 1-6), SI, body axes x forward, y starboard, z down, SNAME signs. The
added-mass matrix M_A comes from the ``..dot`` coefficients; the added-mass Coriolis and
centripetal terms C_A(nu) are computed from M_A (Fossen eq. 6.43), never folded into Y_ur,
N_uv and their twins. A coefficient set in Prestero's (2001) lumped form, whose Y_ur, N_uv,
N_ur... contain the added-mass terms (e.g. N_uv = N_uva + N_uvl + N_uvf with the Munk moment
N_uva), is converted by :func:`lumped_to_fossen`, which subtracts exactly the bilinear terms
that C_A(nu) gives.
"""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from scipy.integrate import trapezoid

from towtank.reference.constants import STANDARD_GRAVITY
from towtank.vehicle import hull as hulls
from towtank.vehicle import schema
from towtank.vehicle.fossen import (
    DOF,
    REQUIRED_KEYS,
    SYMBOL_RE,
    VELOCITIES,
    added_mass_matrix,
    coriolis_added_mass,
)
from towtank.vehicle.schema import ModelError, check_hull, joined

__all__ = [
    "G",
    "SYMBOL_RE",
    "REQUIRED_KEYS",
    "added_mass_matrix",
    "coriolis_added_mass",
    "lumped_to_fossen",
    "vehicle_profile",
    "mass_properties",
    "build_model",
    "write_model",
    "read_model",
]

G = STANDARD_GRAVITY  # [m/s²]
#: Prestero's lumped terms that carry an added-mass part, and the pair of velocities.
LUMPED = {"Y_ur": ("u", "r"), "Z_uq": ("u", "q"), "N_uv": ("u", "v"), "M_uw": ("u", "w"),
          "N_ur": ("u", "r"), "M_uq": ("u", "q"), "Y_uv": ("u", "v"), "Z_uw": ("u", "w")}


def _ca_bilinear(ma: np.ndarray, symbol: str) -> float:
    """The coefficient of the product of two velocities in the force -C_A(nu) nu."""
    dof = DOF.index(symbol[0])
    i, j = (VELOCITIES.index(c) for c in LUMPED[symbol])

    def force(x: float, y: float) -> float:
        nu = np.zeros(6)
        nu[i] += x
        nu[j] += y
        return -coriolis_added_mass(ma, nu)[dof]

    return force(1.0, 1.0) - force(1.0, 0.0) - force(0.0, 1.0)


def lumped_to_fossen(coefficients: dict[str, float]) -> dict[str, float]:
    """Prestero-style lumped coefficients to the Fossen-form ones of this model.

    Each of Y_ur, Z_uq, N_uv, M_uw, N_ur, M_uq (and Y_uv, Z_uw, whose added-mass part is zero)
    loses the bilinear term that -C_A(nu) nu gives: e.g. N_uv = N_uv,lumped - (Y_vdot - X_udot)
    (the Munk moment), Y_ur = Y_ur,lumped - X_udot, N_ur = N_ur,lumped - Y_rdot. Prestero's
    pure added-mass terms (X_vr, X_wq, X_qq, X_rr, Y_wp, Y_pq, Z_vp, Z_rp, M_vp, M_rp, N_wp,
    N_pq) are dropped: C_A(nu) gives them.
    """
    ma = added_mass_matrix(coefficients)
    out = {}
    dropped = {"X_vr", "X_wq", "X_qq", "X_rr", "Y_wp", "Y_pq", "Z_vp", "Z_rp", "M_vp", "M_rp",
               "N_wp", "N_pq"}
    for sym, val in coefficients.items():
        if sym in dropped:
            continue
        out[sym] = float(float(val) - (_ca_bilinear(ma, sym) if sym in LUMPED else 0.0))
    return out


def vehicle_profile(vehicle: Any) -> hulls.HullProfile:
    """The hull profile of a ``[vehicle]`` section (times its ``scale``).

    Raises
    ------
    ValueError
        A hull table that cannot be used, or a hull whose length or fineness ratio no vehicle
        has (:func:`towtank.vehicle.schema.check_hull`), in one sentence.
    """
    if vehicle.hull == "myring":
        profile = hulls.myring_profile(**vehicle.myring)
    elif vehicle.hull == "suboff":
        profile = hulls.suboff_profile(vehicle.length_m or hulls.SUBOFF_LENGTH_M)
    elif vehicle.hull == "series58":
        profile = hulls.series58_profile(**vehicle.series58)
    else:
        profile = hulls.table_profile(vehicle.hull_table)
    profile = profile.scaled(vehicle.scale) if vehicle.scale != 1.0 else profile
    with np.errstate(all="ignore"):
        scale = f", scale = {vehicle.scale:g}" if vehicle.scale != 1.0 else ""
        problems = check_hull(profile.x_m, profile.r_m, f"[vehicle] ({profile.name} hull{scale})")
    if problems:  # e.g. scale = 1e300: no vehicle is that long
        raise ValueError(joined(problems))
    return profile


def mass_properties(vehicle: Any, profile: hulls.HullProfile, rho: float) -> dict[str, Any]:
    """Mass, weight, buoyancy, centres and inertia of the vehicle about the reference point.

    What ``[vehicle]`` gives is used as given (a ``cb_m = [0, 0, 0]`` is the reference point,
    not "missing"); what is not given is computed, and ``sources`` says which is which
    (``"given"`` or how it was computed; written to model.json ``sources``):

    - buoyancy B = rho g V [N], V = ``volume_m3`` if given, else the hull's volume;
    - mass = ``weight_N``/g if the weight is given, else B/g (neutrally buoyant) [kg];
    - weight W = mass g [N] (Fossen 2011, eq. 4.3);
    - centre of buoyancy = the hull's, in body axes from the reference point [m];
    - centre of gravity = the centre of buoyancy [m];
    - inertia = that of a body of uniform density filling the hull (Ixx = integral of
      m'(x) r^2/2 dx, Iyy = Izz = integral of m'(x) ((x - x_ref)^2 + r^2/4) dx, m' the mass
      per length) [kg m^2].

    Parameters
    ----------
    vehicle : towtank.ingest.vehicle_protocol.Vehicle
        The ``[vehicle]`` section
    profile : towtank.vehicle.hull.HullProfile
        Its hull
    rho : float
        Water density [kg/m^3]
    """
    given = "given"
    volume = float(vehicle.volume_m3) if vehicle.volume_m3 is not None else profile.volume
    if vehicle.buoyancy_N is not None:
        buoyancy, b_src = float(vehicle.buoyancy_N), given
    else:
        buoyancy = rho * G * volume
        b_src = "rho g volume_m3" if vehicle.volume_m3 is not None else "hull volume"
    if vehicle.mass_kg is not None:
        mass, m_src = float(vehicle.mass_kg), given
    elif vehicle.weight_N is not None:
        mass, m_src = float(vehicle.weight_N) / G, "weight_N / g"
    else:
        mass, m_src = buoyancy / G, "neutrally buoyant: buoyancy_N / g"
    if vehicle.weight_N is not None:
        weight, w_src = float(vehicle.weight_N), given
    else:
        weight, w_src = mass * G, "mass_kg x g"
    x_ref = profile.x_buoyancy if vehicle.origin_m is None else float(vehicle.origin_m)
    if vehicle.cb_m is not None:
        cb, cb_src = tuple(vehicle.cb_m), given
    else:
        cb, cb_src = (x_ref - profile.x_buoyancy, 0.0, 0.0), "hull centre of buoyancy"
    if vehicle.cg_m is not None:
        cg, cg_src = tuple(vehicle.cg_m), given
    else:
        cg, cg_src = cb, "centre of buoyancy"
    source = "given in [vehicle]"
    if vehicle.inertia_kg_m2 is not None:
        inertia = tuple(float(v) for v in vehicle.inertia_kg_m2)
    else:
        area = np.pi * profile.r_m**2
        per_len = mass * area / trapezoid(area, profile.x_m)
        xb = x_ref - profile.x_m
        ixx = float(trapezoid(per_len * profile.r_m**2 / 2.0, profile.x_m))
        iyy = float(trapezoid(per_len * (xb**2 + profile.r_m**2 / 4.0), profile.x_m))
        inertia = (ixx, iyy, iyy)
        source = "estimated: uniform density filling the hull"
    sources = {"mass_kg": m_src, "weight_N": w_src, "buoyancy_N": b_src, "cg_m": cg_src,
               "cb_m": cb_src,
               "inertia_kg_m2": given if vehicle.inertia_kg_m2 is not None else
               "uniform density filling the hull"}
    return {"mass_kg": float(mass), "weight_N": float(weight),
            "buoyancy_N": float(buoyancy), "cg_m": [float(c) for c in cg],
            "cb_m": [float(c) for c in cb], "inertia_kg_m2": [float(i) for i in inertia],
            "inertia_source": source, "volume_m3": float(volume), "sources": sources}


def build_model(
    name: str, rho: float, masses: dict[str, Any], predicted: pd.DataFrame | None = None,
    measured: dict[str, float] | None = None,
    covariance: tuple[list[str], np.ndarray] | None = None,
    reference: dict[str, float] | None = None,
) -> dict[str, Any]:
    """The model.json dictionary: measured values first, then predicted, then reference.

    Parameters
    ----------
    name : str
        The vehicle's name
    rho : float
        Water density [kg/m^3]
    masses : dict
        :func:`mass_properties`
    predicted : pandas.DataFrame, optional
        predicted.csv (symbol, value)
    measured : dict, optional
        Measured coefficients in SI {symbol: value}
    covariance : (symbols, matrix), optional
        Covariance of the measured coefficients [SI^2]
    reference : dict, optional
        Reference values in SI, used where neither measured nor predicted
    """
    coefficients: dict[str, float] = {}
    sources: dict[str, str] = {}
    for source, values in (("reference", reference or {}),
                           ("predicted", {} if predicted is None else
                            dict(zip(predicted["symbol"], predicted["value"], strict=True))),
                           ("measured", measured or {})):
        for sym, val in values.items():
            if val is not None and math.isfinite(float(val)):
                coefficients[sym] = float(val)
                sources[sym] = source
    symbols, matrix = ([], np.zeros((0, 0))) if covariance is None else covariance
    return {
        "name": name,
        "rho_kg_m3": float(rho),
        **{k: masses[k] for k in ("mass_kg", "weight_N", "buoyancy_N", "cg_m", "cb_m",
                                  "inertia_kg_m2")},
        "coefficients": coefficients,
        "sources": {**sources, **masses.get("sources", {})},
        "covariance": {"symbols": list(symbols),
                       "matrix": np.asarray(matrix, dtype=float).tolist()},
        "notes": {
            "axes": "body axes x forward, y starboard, z down; SNAME signs; SI units",
            "added_mass_coriolis": "C_A(nu) is computed from the ..dot coefficients "
                                   "(Fossen 2011 eq. 6.43); it is not folded into Y_ur, N_uv",
            "missing": "a coefficient not listed is zero",
            "inertia": masses.get("inertia_source", "given"),
        },
    }


def write_model(model: dict[str, Any], path: str | Path) -> Path:
    """Write model.json (UTF-8, indented)."""
    path = Path(path)
    path.write_text(json.dumps(model, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def _read_bytes(path: Path, limit: int) -> bytes:
    """The bytes of ``path`` if it is a regular file of at most ``limit`` bytes.

    Opened without blocking (a named pipe or a device is refused, never waited on) and read
    no further than ``limit + 1`` bytes.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise ModelError([f"{path.name}: the model file cannot be read "
                          f"({exc.strerror or exc})."]) from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)
        raise ModelError([f"{path.name}: the model file cannot be read (it is not a regular "
                          "file but a folder, device or pipe)."])
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > limit:
            raise ModelError([f"{path.name}: the model file is {st.st_size} bytes, more than "
                              f"the {limit} a model.json may have."])
        data = fh.read(limit + 1)
    if len(data) > limit:
        raise ModelError([f"{path.name}: the model file is more than the {limit} bytes a "
                          "model.json may have."])
    return data


def read_model(path: str | Path) -> dict[str, Any]:
    """Read and check a model.json (docs/formats.md §6, "Limits and checks").

    The file must be a regular file of at most
    :data:`~towtank.vehicle.schema.MAX_MODEL_BYTES`, UTF-8 JSON nested at most
    :data:`~towtank.vehicle.schema.MAX_DEPTH` levels, and pass
    :func:`towtank.vehicle.schema.check_model`.

    Raises
    ------
    towtank.vehicle.schema.ModelError
        A ValueError whose ``problems`` hold one sentence per problem (all of them).
    """
    path = Path(path)
    data = _read_bytes(path, schema.MAX_MODEL_BYTES)
    try:
        model = json.loads(data.decode("utf-8"))
    except RecursionError:
        raise schema.ModelError([f"{path.name}: the model file nests objects and arrays "
                                 f"deeper than the {schema.MAX_DEPTH} levels a model.json may "
                                 "have."]) from None
    except ValueError as exc:  # not UTF-8, not JSON, an integer of 5000 digits
        raise schema.ModelError([f"{path.name}: the model file cannot be read "
                                 f"({exc}).".replace("\n", " ")]) from None
    if schema.json_depth(model) > schema.MAX_DEPTH:
        raise schema.ModelError([f"{path.name}: the model file nests objects and arrays "
                                 f"deeper than the {schema.MAX_DEPTH} levels a model.json may "
                                 "have."])
    problems = schema.check_model(model, path.name)
    if problems:
        raise schema.ModelError(problems)
    model.setdefault("sources", {})
    if model.get("covariance") is None:
        model["covariance"] = {"symbols": [], "matrix": []}
    model.setdefault("name", path.stem)
    return model
