"""The Fossen-form manoeuvring model of a vehicle and its ``model.json`` (docs/formats.md).

``M nu_dot + C_RB(nu) nu + C_A(nu) nu + D(nu) nu + g(eta) = tau`` (Fossen 2011, eqs. 7.190 and
6.43; SUT-2 report eqs. 1-6), SI, body axes x forward, y starboard, z down, SNAME signs. The
added-mass matrix M_A comes from the ``..dot`` coefficients; the added-mass Coriolis and
centripetal terms C_A(nu) are computed from M_A (Fossen eq. 6.43), never folded into Y_ur,
N_uv and their twins. A coefficient set in Prestero's (2001) lumped form, whose Y_ur, N_uv,
N_ur... contain the added-mass terms (e.g. N_uv = N_uva + N_uvl + N_uvf with the Munk moment
N_uva), is converted by :func:`lumped_to_fossen`, which subtracts exactly the bilinear terms
that C_A(nu) gives; :func:`totals_to_fossen` does the same for measured captive derivatives
(totals), with their covariance and a record for model.json's ``conversions``.
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
    ADDED_MASS_RE,
    LUMPED,
    REQUIRED_KEYS,
    SYMBOL_RE,
    added_mass_matrix,
    ca_bilinear,
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
    "FORMS",
    "totals_to_fossen",
    "kept_conversions",
    "vehicle_profile",
    "mass_properties",
    "build_model",
    "write_model",
    "read_model",
]

G = STANDARD_GRAVITY  # [m/s²]
#: The forms a measured coefficient of :data:`~towtank.vehicle.fossen.LUMPED` comes in:
#: ``"total"`` (what a captive test measures: it holds the added-mass part that C_A(nu) gives,
#: converted by :func:`totals_to_fossen`) or ``"fossen"`` (without it, taken as given).
FORMS = ("total", "fossen")


def lumped_to_fossen(coefficients: dict[str, float]) -> dict[str, float]:
    """Prestero-style lumped coefficients to the Fossen-form ones of this model.

    Each of Y_ur, Z_uq, N_uv, M_uw, N_ur, M_uq (and Y_uv, Z_uw, whose added-mass part is zero)
    loses the bilinear term that -C_A(nu) nu gives: e.g. N_uv = N_uv,lumped - (Y_vdot - X_udot)
    (the Munk moment), Y_ur = Y_ur,lumped - X_udot, N_ur = N_ur,lumped - Y_rdot. Prestero's
    pure added-mass terms (X_vr, X_wq, X_qq, X_rr, Y_wp, Y_pq, Z_vp, Z_rp, M_vp, M_rp, N_wp,
    N_pq) are dropped: C_A(nu) gives them.
    """
    dropped = {"X_vr", "X_wq", "X_qq", "X_rr", "Y_wp", "Y_pq", "Z_vp", "Z_rp", "M_vp", "M_rp",
               "N_wp", "N_pq"}
    kept = {sym: float(val) for sym, val in coefficients.items() if sym not in dropped}
    return totals_to_fossen(kept, list(LUMPED))[0]


def _unit_added_mass(coefficients: dict[str, float], symbol: str) -> np.ndarray:
    """d M_A / d ``symbol``: M_A of the model's added masses all zero but ``symbol`` = 1 (a
    symmetric pair given both ways is averaged, as :func:`added_mass_matrix` does)."""
    return added_mass_matrix({s: float(s == symbol) for s in coefficients
                              if ADDED_MASS_RE.match(s)})


def totals_to_fossen(
    coefficients: dict[str, float], totals: list[str],
    covariance: tuple[list[str], np.ndarray] | None = None,
) -> tuple[dict[str, float], tuple[list[str], np.ndarray], dict[str, dict[str, Any]]]:
    """Measured totals to the Fossen form, with their covariance and a record of each.

    Each symbol of ``totals`` that :data:`~towtank.vehicle.fossen.LUMPED` lists loses the
    bilinear term that -C_A(nu) nu gives with the model's own added masses (those in
    ``coefficients``, measured or predicted): value = total - part, part =
    :func:`~towtank.vehicle.fossen.ca_bilinear` (e.g. N_uv: Y_vdot - X_udot; Y_ur: X_udot;
    N_ur: Y_rdot, the mean of Y_rdot and N_vdot when both are given). The map is linear,
    c_F = J c, with J = I less d(part)/d(added mass) in the added masses' columns, so that
    the covariance becomes J Sigma J^T: a converted symbol's variance gains those of the
    measured added masses it uses, and it is correlated with them.

    Parameters
    ----------
    coefficients : dict
        The model's coefficients in SI, the totals among them
    totals : list of str
        The symbols measured as totals; those outside LUMPED are left as they are
    covariance : (symbols, matrix), optional
        Covariance of the measured coefficients [SI^2]; a converted symbol not in it is added

    Returns
    -------
    coefficients : dict
        The same with the totals converted
    covariance : (symbols, matrix)
        The propagated covariance
    records : dict
        model.json's ``conversions`` entries: {symbol: {"form": "total", "total",
        "added_mass_part", "added_masses": {symbol: value}}}
    """
    symbols, matrix = ([], np.zeros((0, 0))) if covariance is None else covariance
    matrix = np.asarray(matrix, dtype=float).reshape(len(symbols), len(symbols))
    ma = added_mass_matrix(coefficients)
    convert = [s for s in dict.fromkeys(totals) if s in LUMPED and s in coefficients]
    names = list(symbols) + [s for s in convert if s not in symbols]
    sigma = np.zeros((len(names), len(names)))
    sigma[:len(symbols), :len(symbols)] = matrix
    jac = np.eye(len(names))
    out = dict(coefficients)
    records: dict[str, dict[str, Any]] = {}
    dots = [s for s in coefficients if ADDED_MASS_RE.match(s)]
    grads = {d: {s: ca_bilinear(_unit_added_mass(coefficients, d), s) for s in convert}
             for d in dots}
    for sym in convert:
        part = ca_bilinear(ma, sym)
        out[sym] = float(coefficients[sym]) - part
        used = {d: float(coefficients[d]) for d in dots if grads[d][sym] != 0.0}
        records[sym] = {"form": "total", "total": float(coefficients[sym]),
                        "added_mass_part": part, "added_masses": used}
        for d in used:
            if d in names:
                jac[names.index(sym), names.index(d)] -= grads[d][sym]
    cov = jac @ sigma @ jac.T
    return out, (names, 0.5 * (cov + cov.T)), records


def kept_conversions(conversions: dict[str, Any], changed: list[str]) -> dict[str, Any]:
    """The ``conversions`` entries that still hold once the coefficients ``changed`` have new
    values (e.g. identified): an entry goes when its own coefficient or an added mass it used
    changed."""
    return {s: e for s, e in conversions.items()
            if s not in changed and not set(e.get("added_masses", {})) & set(changed)}


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
    forms: dict[str, str] | None = None,
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
    forms : dict, optional
        The form (:data:`FORMS`) of measured coefficients of
        :data:`~towtank.vehicle.fossen.LUMPED`: ``"total"`` ones are converted by
        :func:`totals_to_fossen` with the model's added masses (covariance propagated),
        ``"fossen"`` ones taken as given; both recorded in ``conversions``
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
    measured_forms = {s: f for s, f in (forms or {}).items()
                      if s in LUMPED and sources.get(s) == "measured"}
    coefficients, (symbols, matrix), conversions = totals_to_fossen(
        coefficients, [s for s, f in measured_forms.items() if f == "total"],
        (symbols, matrix))
    conversions |= {s: {"form": "fossen"} for s, f in measured_forms.items() if f == "fossen"}
    model = {
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
    if conversions:
        model["conversions"] = conversions
        model["notes"]["conversions"] = (
            "measured totals (captive tests) hold the added-mass part of C_A(nu); it is "
            "subtracted once, with the model's added masses: value = total - added_mass_part")
    return model


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
