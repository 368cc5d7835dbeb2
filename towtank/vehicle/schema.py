"""Checks of the vehicle stage's inputs: model.json, the options of ``towtank simulate`` and
the dimensions of a hull (docs/formats.md §6, "Limits and checks").

Every function here is pure: it takes parsed values and returns the list of problems, one
sentence each naming the key (or option) and the value, empty when all is well. The callers
(:func:`towtank.vehicle.model.read_model`, ``towtank simulate``, the hull profiles) turn a
non-empty list into one error listing every problem, so that a user fixes a file in one pass.

The limits are module constants, stated in the sentences and in docs/formats.md:

- a model.json is at most :data:`MAX_MODEL_BYTES`, nested at most :data:`MAX_DEPTH` levels and
  holds at most :data:`MAX_COEFFICIENTS` coefficients of at most :data:`MAX_FACTORS` factors;
- densities lie in :data:`RHO_RANGE_KG_M3`, speeds in (0, :data:`MAX_SPEED_M_S`], hull and
  vehicle lengths in :data:`LENGTH_RANGE_M`;
- the centres of gravity and buoyancy lie within the vehicle's length of the reference point
  (:func:`centre_problem`, for model.json and ``[vehicle]`` alike), and a ``[vehicle]``'s
  reference point, fins and their sizes inside the hull it describes
  (:func:`vehicle_geometry_problems`);
- a simulation covers at most :data:`MAX_DURATION_S` of simulated time in at most
  :data:`MAX_STEPS` integration steps, and ``--samples`` is at most :data:`MAX_SAMPLES`.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

import numpy as np

from towtank.errors import ProtocolError
from towtank.ingest.design_inputs import parse_propeller
from towtank.ingest.values import finite_number
from towtank.reference.constants import STANDARD_GRAVITY
from towtank.vehicle.assumptions import check_assumptions
from towtank.vehicle.fossen import (
    ADDED_MASS_RE,
    LUMPED,
    REQUIRED_KEYS,
    SYMBOL_RE,
    added_mass_matrix,
    ca_bilinear,
    rigid_body_mass_matrix,
)

__all__ = [
    "NEGATIVE_COEFFICIENTS",
    "sign_warnings",
    "vehicle_mass_problems",
    "stability_warning",
    "MAX_MODEL_BYTES",
    "MAX_DEPTH",
    "MAX_COEFFICIENTS",
    "MAX_FACTORS",
    "MAX_PROBLEMS",
    "RHO_RANGE_KG_M3",
    "WEIGHT_TOLERANCE",
    "MAX_NET_BUOYANCY_RATIO",
    "MAX_SPEED_M_S",
    "LENGTH_RANGE_M",
    "FINENESS_RANGE",
    "MAX_CONTROL_DEG",
    "MAX_DURATION_S",
    "MAX_STEPS",
    "MAX_SAMPLES",
    "COVARIANCE_TOLERANCE",
    "MASS_MATRIX_TOLERANCE",
    "MM_PER_M",
    "GEOMETRY_TOLERANCE",
    "ModelError",
    "json_depth",
    "check_model",
    "check_covariance",
    "check_conversions",
    "CONVERSION_TOLERANCE",
    "check_simulation",
    "check_hull",
    "centre_problem",
    "vehicle_geometry_problems",
    "unit_slip",
    "default_duration",
    "joined",
]

#: Largest model.json read [bytes] (a model with a full 100 x 100 covariance is about 250 kB).
MAX_MODEL_BYTES = 4 * 1024 * 1024
#: Deepest nesting of objects and arrays in model.json (the format itself needs 4: the
#: file's object, covariance, matrix, row).
MAX_DEPTH = 16
#: Most coefficients in a model (towtank's own models have about 40).
MAX_COEFFICIENTS = 1000
#: Most factors in one coefficient's product (``Y_uudr`` has 3, ``N_r|r|`` 2).
MAX_FACTORS = 6
#: Most problems listed in one error; the rest are counted.
MAX_PROBLEMS = 40
#: Plausible water densities, hot fresh water to dense brine [kg/m^3].
RHO_RANGE_KG_M3 = (900.0, 1300.0)
#: Largest relative difference between weight_N and mass_kg * g [-].
WEIGHT_TOLERANCE = 0.01
#: Largest |buoyancy - weight| as a fraction of the weight [-] (the model's, and that which
#: ``--net-buoyancy-N`` asks for).
MAX_NET_BUOYANCY_RATIO = 1.0
#: Fastest design or simulated speed [m/s].
MAX_SPEED_M_S = 100.0
#: Shortest and longest hull or vehicle length [m].
LENGTH_RANGE_M = (0.01, 1000.0)
#: Smallest and largest fineness ratio L/D of a hull [-].
FINENESS_RANGE = (0.5, 500.0)
#: Largest rudder or stern-plane angle [deg].
MAX_CONTROL_DEG = 45.0
#: Longest simulated time [s].
MAX_DURATION_S = 3600.0
#: Most integration steps of one simulation [-] (a REMUS zigzag over 3600 s takes 125 000).
MAX_STEPS = 200_000
#: Most draws of ``--samples`` [-] (each is a whole simulation).
MAX_SAMPLES = 1000
#: Relative tolerance of the covariance's symmetry and positive semi-definiteness [-].
COVARIANCE_TOLERANCE = 1e-9
#: Relative tolerance of a conversion entry's arithmetic (value = total - added_mass_part)
#: and of its added masses against the model's [-].
CONVERSION_TOLERANCE = 1e-9
#: Smallest eigenvalue of the mass matrix relative to its largest [-].
MASS_MATRIX_TOLERANCE = 1e-10

_G = STANDARD_GRAVITY  # [m/s²]
_FACTOR = re.compile(r"\|[uvwpqr]\||dr|ds|[uvwpqr]")
_ADDED_MASS = ADDED_MASS_RE


class ModelError(ValueError):
    """A model.json, or the options of a simulation, that cannot be used.

    ``problems`` holds one sentence per problem; ``str()`` is :func:`joined` of them.
    """

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        super().__init__(joined(self.problems))


def joined(problems: list[str]) -> str:
    """The problems one per line, at most :data:`MAX_PROBLEMS` and a count of the others."""
    shown = list(problems[:MAX_PROBLEMS])
    if len(problems) > MAX_PROBLEMS:
        shown.append(f"... and {len(problems) - MAX_PROBLEMS} more problems like these.")
    return "\n".join(shown)


def _show(value: Any, width: int = 60) -> str:
    """A value as a sentence quotes it: as JSON writes it (null, NaN, "text"), shortened."""
    try:
        text = json.dumps(value, ensure_ascii=False)
    except (TypeError, ValueError, RecursionError):
        text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _kind(value: Any) -> str:
    return {dict: "an object", list: "a list", str: "text", bool: "true/false",
            type(None): "null"}.get(type(value), "a number")


def _times(weight: float) -> str:
    """The largest net buoyancy in words: "the weight_N (298.9 N)" or "0.5 times ..."."""
    limit = MAX_NET_BUOYANCY_RATIO * weight
    factor = "" if MAX_NET_BUOYANCY_RATIO == 1.0 else f"{MAX_NET_BUOYANCY_RATIO:g} times "
    return f"{factor}the model's weight_N ({limit:g} N)"


def json_depth(value: Any, limit: int = MAX_DEPTH) -> int:
    """Nesting depth of parsed JSON: a number 0, ``[1]`` and ``[]`` 1, ``{"a": [1]}`` 2.

    Parameters
    ----------
    value : object
        Parsed JSON (dict, list, str, number, bool, None)
    limit : int
        Depth beyond which counting stops [-]

    Returns
    -------
    int
        The depth, at most ``limit + 1``; counted level by level, without recursion.
    """
    depth = 0
    level = [value]
    while level and depth <= limit:
        nxt: list[Any] = []
        for item in level:
            if isinstance(item, dict):
                nxt.extend(item.values())
            elif isinstance(item, list):
                nxt.extend(item)
        if not nxt and not any(isinstance(i, dict | list) for i in level):
            break
        depth += 1
        level = nxt
    return depth


def _symbol_problem(sym: Any, name: str, where: str = "") -> str | None:
    """The sentence for a symbol that is not a coefficient's (``where``: " in ..." when it is
    not a key of 'coefficients'), else None."""
    shown = f"'{sym}'" if isinstance(sym, str) and len(sym) <= 60 else _show(sym)
    if not isinstance(sym, str) or not (SYMBOL_RE.match(sym) or _ADDED_MASS.match(sym)):
        return (f"{name}: {shown}{where} is not a coefficient symbol this model knows "
                "(e.g. Y_uv, N_r|r|, Y_vdot, N_uudr).")
    if not _ADDED_MASS.match(sym) and len(_FACTOR.findall(sym.partition("_")[2])) > MAX_FACTORS:
        return (f"{name}: the coefficient symbol {shown}{where} is a product of more than "
                f"{MAX_FACTORS} factors.")
    return None


def check_model(model: Any, name: str = "model.json") -> list[str]:
    """Problems of a parsed model.json (docs/formats.md §6), one sentence each.

    Types: the required keys present; ``rho_kg_m3``, ``mass_kg``, ``weight_N``,
    ``buoyancy_N`` finite numbers; ``cg_m``, ``cb_m``, ``inertia_kg_m2`` three finite numbers;
    ``coefficients`` an object of at most :data:`MAX_COEFFICIENTS` known symbols with finite
    numbers; ``name`` text, ``sources`` an object of text, ``notes`` an object,
    ``design_speed_m_s`` and ``length_m`` finite numbers, ``covariance`` null or as
    :func:`check_covariance` wants it. Physical ranges: density within
    :data:`RHO_RANGE_KG_M3`; mass, weight, buoyancy and inertias > 0; weight = mass g within
    :data:`WEIGHT_TOLERANCE`; |buoyancy - weight| at most :data:`MAX_NET_BUOYANCY_RATIO`
    times the weight; design speed in (0, :data:`MAX_SPEED_M_S`]; length within
    :data:`LENGTH_RANGE_M`; centres of gravity and buoyancy within one length of the
    reference point. When all of that holds, the mass matrix M_RB + M_A must be positive
    definite (its smallest eigenvalue above :data:`MASS_MATRIX_TOLERANCE` times its largest):
    otherwise the vehicle would accelerate against the forces.

    Parameters
    ----------
    model : object
        The parsed JSON
    name : str
        The file's name, which starts every sentence

    Returns
    -------
    list of str
        The problems; empty for a usable model.
    """
    if not isinstance(model, dict):
        return [f"{name}: the model file is not a JSON object but {_kind(model)}."]
    problems = [f"{name}: the model lacks the key '{key}'." for key in REQUIRED_KEYS
                if key not in model]

    def scalar(key: str, low: float, high: float, unit: str, what: str,
               low_open: bool = True) -> float | None:
        if key not in model:
            return None
        value = finite_number(model[key])
        inside = value is not None and (value > low if low_open else value >= low) \
            and value <= high
        if not inside:
            problems.append(f"{name}: '{key}' must be {what} [{unit}], not "
                            f"{_show(model[key])}.")
            return None
        return value

    scalar("rho_kg_m3", RHO_RANGE_KG_M3[0], RHO_RANGE_KG_M3[1], "kg/m^3",
           f"a water density from {RHO_RANGE_KG_M3[0]:g} to {RHO_RANGE_KG_M3[1]:g}",
           low_open=False)
    mass = scalar("mass_kg", 0.0, math.inf, "kg", "a finite number > 0")
    weight = scalar("weight_N", 0.0, math.inf, "N", "a finite number > 0")
    buoyancy = scalar("buoyancy_N", 0.0, math.inf, "N", "a finite number > 0")
    length = scalar("length_m", LENGTH_RANGE_M[0], LENGTH_RANGE_M[1], "m",
                    f"a length from {LENGTH_RANGE_M[0]:g} to {LENGTH_RANGE_M[1]:g}",
                    low_open=False)
    scalar("design_speed_m_s", 0.0, MAX_SPEED_M_S, "m/s",
           f"a speed > 0 and at most {MAX_SPEED_M_S:g}")

    triples: dict[str, list[float]] = {}
    for key, positive, unit, labels in (("cg_m", False, "m", "x, y, z"),
                                        ("cb_m", False, "m", "x, y, z"),
                                        ("inertia_kg_m2", True, "kg m^2", "Ixx, Iyy, Izz")):
        if key not in model:
            continue
        value = model[key]
        raw = [finite_number(v) for v in value] if isinstance(value, list) else []
        nums = [n for n in raw if n is not None]
        if len(raw) != 3 or len(nums) != 3:
            problems.append(f"{name}: '{key}' must be a list of three numbers [{labels}], "
                            f"finite [{unit}], not {_show(value)}.")
        elif positive and min(nums) <= 0:
            problems.append(f"{name}: '{key}' must be three moments of inertia > 0 "
                            f"[{labels}] [{unit}], not {_show(value)}.")
        elif not positive and length is not None and (far := centre_problem(
                key, nums, length, f"{name}: '{key}'", "the vehicle's length_m")):
            problems.append(far)
        else:
            triples[key] = nums

    coefficients = model.get("coefficients")
    if "coefficients" in model:
        if not isinstance(coefficients, dict):
            problems.append(f"{name}: 'coefficients' must be an object {{symbol: value}}, not "
                            f"{_show(coefficients)}.")
        elif len(coefficients) > MAX_COEFFICIENTS:
            problems.append(f"{name}: 'coefficients' holds {len(coefficients)} coefficients, "
                            f"more than the {MAX_COEFFICIENTS} a model may have.")
        else:
            for sym, val in coefficients.items():
                bad = _symbol_problem(sym, name)
                if bad:
                    problems.append(bad)
                elif finite_number(val) is None:
                    problems.append(f"{name}: the coefficient {sym} is not a finite number "
                                    f"but {_show(val)}.")
    for key, kind, test in (("name", "text", lambda v: isinstance(v, str)),
                            ("sources", "an object {symbol: text}",
                             lambda v: isinstance(v, dict)
                             and all(isinstance(s, str) for s in v.values())),
                            ("notes", "an object", lambda v: isinstance(v, dict))):
        if key in model and not test(model[key]):
            problems.append(f"{name}: '{key}' must be {kind}, not {_show(model[key])}.")
    if model.get("covariance") is not None:
        problems += check_covariance(model["covariance"], name)
    if "assumptions" in model:
        problems += check_assumptions(model["assumptions"], name)
    if "propeller" in model:  # the B-series propeller of simulate --propeller rps
        try:
            parse_propeller(model["propeller"], name, label="propeller")
        except ProtocolError as exc:
            problems.append(str(exc))
    if problems:  # the checks below need every value above
        return problems
    # no problem: every required key is there and valid (the scalars are numbers)
    assert mass is not None and weight is not None and buoyancy is not None
    assert isinstance(coefficients, dict)

    if abs(weight - mass * _G) > WEIGHT_TOLERANCE * mass * _G:
        problems.append(f"{name}: 'weight_N' must be mass_kg x g ({mass * _G:.6g} N for "
                        f"{mass:g} kg) within {WEIGHT_TOLERANCE:.0%}, not {weight:g}.")
    if abs(buoyancy - weight) > MAX_NET_BUOYANCY_RATIO * weight:
        problems.append(f"{name}: 'buoyancy_N' must differ from the weight by at most "
                        f"{_times(weight)}, not {buoyancy:g} N.")
    if "conversions" in model:
        problems += check_conversions(model["conversions"], coefficients, name)
    if problems:
        return problems
    return _check_mass_matrix(mass, triples["cg_m"], triples["inertia_kg_m2"], coefficients,
                              name)


def _check_mass_matrix(mass: float, cg: list[float], inertia: list[float],
                       coefficients: dict[str, float], name: str) -> list[str]:
    m_rb = rigid_body_mass_matrix(mass, np.asarray(cg, dtype=float), np.diag(inertia))
    with np.errstate(all="ignore"):
        total = m_rb + added_mass_matrix(coefficients)
        eig = np.linalg.eigvalsh(total) if np.all(np.isfinite(total)) else None
    if eig is None or not np.all(np.isfinite(eig)):
        return [f"{name}: the mass matrix M_RB + M_A (mass_kg, cg_m, inertia_kg_m2 and the "
                "..dot coefficients) overflows; check their magnitudes."]
    if eig[0] <= MASS_MATRIX_TOLERANCE * eig[-1]:
        return [f"{name}: the mass matrix M_RB + M_A (mass_kg, cg_m, inertia_kg_m2 and the "
                f"..dot coefficients) must be positive definite, but its smallest eigenvalue "
                f"is {eig[0]:.4g} against a largest of {eig[-1]:.4g}; check the signs of the "
                "added masses (X_udot, Y_vdot... are negative) and the inertias."]
    return []


def _close(a: float, b: float, scale: float) -> bool:
    return abs(a - b) <= CONVERSION_TOLERANCE * max(scale, abs(a), abs(b), 1e-300)


def check_conversions(conversions: Any, coefficients: dict[str, Any],
                      name: str = "model.json") -> list[str]:
    """Problems of model.json's ``conversions`` (docs/formats.md §6), one sentence each.

    Each key is a coefficient of :data:`~towtank.vehicle.fossen.LUMPED` that the model
    holds; its entry is ``{"form": "fossen"}`` (a measured value taken as given) or
    ``{"form": "total", "total", "added_mass_part", "added_masses"}``: the added masses those
    of the model, ``added_mass_part`` the bilinear term of -C_A(nu) nu they give
    (:func:`~towtank.vehicle.fossen.ca_bilinear`) and the coefficient ``total -
    added_mass_part``, all within :data:`CONVERSION_TOLERANCE`.

    Parameters
    ----------
    conversions : object
        The parsed ``conversions``
    coefficients : dict
        The model's coefficients, already checked (known symbols, finite numbers)
    name : str
        The file's name, which starts every sentence
    """
    if not isinstance(conversions, dict):
        return [f"{name}: 'conversions' must be an object {{symbol: entry}}, not "
                f"{_show(conversions)}."]
    ma = added_mass_matrix(coefficients)
    problems = []
    for sym, entry in conversions.items():
        where = f"{name}: 'conversions' '{sym}'" if isinstance(sym, str) and len(sym) <= 60 \
            else f"{name}: 'conversions' {_show(sym)}"
        if sym not in LUMPED:
            problems.append(f"{where} is not a coefficient with an added-mass part "
                            f"({', '.join(LUMPED)}).")
        elif sym not in coefficients:
            problems.append(f"{where} converts a coefficient the model does not hold.")
        elif not isinstance(entry, dict) or entry.get("form") not in ("total", "fossen"):
            problems.append(f"{where} must be an object whose 'form' is 'total' or 'fossen', "
                            f"not {_show(entry)}.")
        elif entry["form"] == "total":
            problems += _total_problems(where, sym, entry, coefficients, ma)
    return problems


def _total_problems(where: str, sym: str, entry: dict[str, Any],
                    coefficients: dict[str, Any], ma: np.ndarray) -> list[str]:
    """The problems of one ``{"form": "total"}`` entry of ``conversions``."""
    total, part = finite_number(entry.get("total")), finite_number(entry.get("added_mass_part"))
    used = entry.get("added_masses")
    if total is None or part is None or not isinstance(used, dict):
        return [f"{where} must hold 'total' and 'added_mass_part' (finite numbers) and "
                f"'added_masses' (an object), not {_show(entry)}."]
    problems = [f"{where} used {d} = {_show(v)}, but the model's is "
                f"{_show(coefficients.get(d))}." for d, v in used.items()
                if not (isinstance(d, str) and ADDED_MASS_RE.match(d) and d in coefficients
                        and finite_number(v) is not None
                        and _close(float(v), float(coefficients[d]), 0.0))]
    expected = ca_bilinear(ma, sym)
    if not _close(part, expected, abs(total)):
        problems.append(f"{where} 'added_mass_part' is {part:.10g}, but the model's added "
                        f"masses give {expected:.10g} for it.")
    value = float(coefficients[sym])
    if not _close(value, total - part, abs(total)):
        problems.append(f"{where}: the coefficient {sym} = {value:.10g} is not 'total' - "
                        f"'added_mass_part' = {total - part:.10g}.")
    return problems


def check_covariance(covariance: Any, name: str = "model.json") -> list[str]:
    """Problems of model.json's ``covariance`` {symbols, matrix}, one sentence each.

    Parameters
    ----------
    covariance : object
        The parsed ``covariance``: ``symbols`` a list of distinct coefficient symbols,
        ``matrix`` a square list of lists of finite numbers of the same size [SI^2],
        symmetric and positive semi-definite within :data:`COVARIANCE_TOLERANCE` times its
        largest entry (no eigenvalue below minus that). An empty ``symbols`` with an empty
        ``matrix`` is a model without measured covariance.
    name : str
        The file's name, which starts every sentence

    Returns
    -------
    list of str
        The problems; empty for a usable covariance.
    """
    where = f"{name}: 'covariance'"
    if not isinstance(covariance, dict):
        return [f"{where} must be an object {{symbols, matrix}}, not {_show(covariance)}."]
    symbols, matrix = covariance.get("symbols", []), covariance.get("matrix", [])
    if not isinstance(symbols, list):
        return [f"{where} 'symbols' must be a list of coefficient symbols, not "
                f"{_show(symbols)}."]
    problems = [p for p in (_symbol_problem(s, name, " in 'covariance' 'symbols'")
                            for s in symbols) if p]
    if len(set(map(repr, symbols))) != len(symbols):
        problems.append(f"{where} 'symbols' names a coefficient twice: {_show(symbols)}.")
    n = len(symbols)
    rows = matrix if isinstance(matrix, list) else None
    if rows is None or len(rows) != n or any(not isinstance(r, list) or len(r) != n
                                             for r in rows):
        problems.append(f"{where} 'matrix' must be a {n} x {n} list of lists, one row per "
                        f"symbol, not {_show(matrix)}.")
        return problems
    values = [[finite_number(v) for v in row] for row in rows]
    if any(v is None for row in values for v in row):
        bad = next(rows[i][j] for i, row in enumerate(values) for j, v in enumerate(row)
                   if v is None)
        problems.append(f"{where} 'matrix' must hold finite numbers [SI^2], not {_show(bad)}.")
        return problems
    if problems or n == 0:
        return problems
    a = np.array(values, dtype=float)
    scale = float(np.max(np.abs(a)))
    tol = COVARIANCE_TOLERANCE * scale
    if not np.isfinite(scale):
        return [f"{where} 'matrix' overflows; its largest entry is too large."]
    asym = float(np.max(np.abs(a - a.T)))
    if asym > tol:
        return [f"{where} 'matrix' must be symmetric, but entries differ from their mirror "
                f"by up to {asym:.4g}."]
    with np.errstate(all="ignore"):
        eig = np.linalg.eigvalsh(0.5 * (a + a.T))
    if not np.all(np.isfinite(eig)) or eig[0] < -tol:
        return [f"{where} 'matrix' must be positive semi-definite (a covariance), but it has "
                f"the eigenvalue {eig[0]:.4g}; no 95 % band can be drawn from it."]
    return []


def check_simulation(model: dict[str, Any] | None, manoeuvre: str, *, speed_m_s: Any,
                     rudder_deg: Any, sternplane_deg: Any, duration_s: Any = None,
                     net_buoyancy_n: Any = None, samples: Any = 0,
                     name: str = "model.json") -> list[str]:
    """Problems of the options of one ``towtank simulate``, one sentence each.

    Parameters
    ----------
    model : dict or None
        The checked model (:func:`check_model` found nothing); None when it has problems of
        its own, then only the checks that do not need it are made
    manoeuvre : str
        turning, zigzag, dive, spiral or glide
    speed_m_s : float
        Speed [m/s], in (0, :data:`MAX_SPEED_M_S`]
    rudder_deg, sternplane_deg : float
        Control angles [deg], within ± :data:`MAX_CONTROL_DEG`
    duration_s : float, optional
        Simulated time [s], in (0, :data:`MAX_DURATION_S`]; None for the manoeuvre's default
        (:func:`default_duration`), which must also lie there
    net_buoyancy_n : float, optional
        Buoyancy minus weight [N]: finite, at most :data:`MAX_NET_BUOYANCY_RATIO` times the
        model's weight_N in size, and leaving the vehicle a weight > 0
    samples : int
        Draws of the measured coefficients, 0 to :data:`MAX_SAMPLES`; more than 0 needs a
        model with a covariance of measured coefficients
    name : str
        The model file's name, for the sentences

    Returns
    -------
    list of str
        The problems; empty when the simulation may run.
    """
    problems = []
    for opt, value in (("--rudder-deg", rudder_deg), ("--sternplane-deg", sternplane_deg)):
        v = finite_number(value)
        if v is None or abs(v) > MAX_CONTROL_DEG:
            problems.append(f"{opt} must lie within ±{MAX_CONTROL_DEG:g} degrees, not "
                            f"{_show(value)}.")
    speed = finite_number(speed_m_s)
    if speed is None or not 0.0 < speed <= MAX_SPEED_M_S:
        problems.append(f"--speed must be a speed > 0 and at most {MAX_SPEED_M_S:g} m/s, not "
                        f"{_show(speed_m_s)}.")
        speed = None
    if duration_s is not None:
        d = finite_number(duration_s)
        if d is None or not 0.0 < d <= MAX_DURATION_S:
            problems.append(f"--duration-s must be a simulated time > 0 and at most "
                            f"{MAX_DURATION_S:g} s (the longest towtank simulates), not "
                            f"{_show(duration_s)}.")
    elif model is not None and speed is not None:
        d = default_duration(model, manoeuvre, speed)
        if d > MAX_DURATION_S:
            problems.append(f"{name}: the default simulated time of a {manoeuvre} at "
                            f"{speed:g} m/s is {d:.6g} s, more than the {MAX_DURATION_S:g} s "
                            "towtank simulates; give a shorter --duration-s.")
    n = samples if isinstance(samples, int) and not isinstance(samples, bool) else None
    if n is None or not 0 <= n <= MAX_SAMPLES:
        problems.append(f"--samples must be a whole number from 0 to {MAX_SAMPLES} (each draw "
                        f"is a whole simulation), not {_show(samples)}.")
    elif n and model is not None:
        cov = model.get("covariance") or {}
        if not cov.get("symbols"):
            problems.append(f"{name}: the model has no covariance of measured coefficients; "
                            "--samples needs a model written by 'towtank process' with "
                            "measured values.")
    if net_buoyancy_n is not None:
        net = finite_number(net_buoyancy_n)
        weight = None if model is None else finite_number(model.get("weight_N"))
        buoyancy = None if model is None else finite_number(model.get("buoyancy_N"))
        if net is None:
            problems.append(f"--net-buoyancy-N must be a finite force [N], not "
                            f"{_show(net_buoyancy_n)}.")
        elif weight is not None and abs(net) > MAX_NET_BUOYANCY_RATIO * weight:
            problems.append(f"--net-buoyancy-N must be at most {_times(weight)} in size, "
                            f"not {net:g} N.")
        elif buoyancy is not None and buoyancy - net <= 0:
            problems.append(f"--net-buoyancy-N {net:g} would leave the vehicle no weight (its "
                            f"buoyancy_N is {buoyancy:g} N); it must be less than that.")
    return problems


def default_duration(model: dict[str, Any], manoeuvre: str, speed_m_s: float) -> float:
    """The simulated time of a manoeuvre without ``duration_s`` [s]: 40 vehicle lengths of
    travel at ``speed_m_s`` [m/s] (a glide 200; turning, spiral and zigzag at least 120),
    the length the model's ``length_m`` [m], else 1 m."""
    length = float(model.get("length_m", 1.0))
    duration = (200.0 if manoeuvre == "glide" else 40.0) * length / speed_m_s
    if manoeuvre in ("turning", "spiral", "zigzag", "sine", "schedule"):
        duration = max(duration, 120.0 * length / speed_m_s)
    return duration


#: A length typed in millimetres for metres is this many times too large [-].
MM_PER_M = 1000.0
#: Relative tolerance of the bounds of :func:`vehicle_geometry_problems` [-] (a fin at the
#: tail's very end is on the hull).
GEOMETRY_TOLERANCE = 1e-9


#: Coefficients negative for any vehicle in the SNAME convention model.json uses: the added
#: masses and inertias of each axis (added mass is positive, its coefficient −m_a), the
#: quadratic damping of each motion and the lift slope of the hull in sway and heave (drag and
#: lift oppose the motion). docs/method.md "Sign conventions".
NEGATIVE_COEFFICIENTS = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot",
                         "X_u|u|", "Y_v|v|", "Z_w|w|", "K_p|p|", "M_q|q|", "N_r|r|",
                         "Y_uv", "Z_uw")


def sign_warnings(coefficients: dict[str, Any]) -> list[str]:
    """One sentence per coefficient of :data:`NEGATIVE_COEFFICIENTS` that model.json gives
    positive: a sign convention reversed by hand (simulate runs it, its motion wrong)."""
    out = []
    for sym in NEGATIVE_COEFFICIENTS:
        v = coefficients.get(sym)
        if isinstance(v, int | float) and not isinstance(v, bool) and v > 0:
            out.append(f"{sym} = {v:+.4g} is positive, but it is negative for any vehicle "
                       "(SNAME: an added mass is −m_a, a damping opposes the motion): is its "
                       "sign reversed?")
    return out


def stability_warning(cg_m: Any, cb_m: Any, where: str = "model.json") -> str | None:
    """The sentence for a centre of gravity above the centre of buoyancy (its z, positive
    down, less than the buoyancy's): the vehicle has no righting moment in roll and pitch and
    turns over (a z given positive up); None otherwise or without both centres [m]."""
    try:
        zg, zb = float(cg_m[2]), float(cb_m[2])
    except (TypeError, ValueError, IndexError):
        return None
    if not zg < zb:
        return None
    return (f"{where}: the centre of gravity lies {zb - zg:.3g} m above the centre of "
            f"buoyancy (cg_m z = {zg:g}, cb_m z = {zb:g}, z positive down): the vehicle "
            "has no righting moment and turns over; was z given positive up?")


def unit_slip(value_m: float, low_m: float, high_m: float) -> str:
    """The end of the sentence that refuses a length ``value_m`` [m] outside [``low_m``,
    ``high_m``] [m]: ``": was it given in mm for m?"`` when a thousandth of it lies inside
    while a tenth of it still lies outside (far out, as millimetres are), else ``"."``."""
    def inside(v: float) -> bool:
        return low_m <= v <= high_m

    if inside(value_m / MM_PER_M) and not inside(value_m / 10.0):
        return ": was it given in mm for m?"
    return "."


def centre_problem(key: str, value: list[float] | tuple[float, ...], length_m: float,
                   where: str, length_name: str) -> str | None:
    """The sentence for a centre of gravity or buoyancy farther than the vehicle's length from
    the reference point in any axis, else None: the one bound of model.json (``simulate``,
    ``steady``) and of ``[vehicle]`` (``predict``), so that ``predict`` writes no model that
    ``simulate`` refuses.

    Parameters
    ----------
    key : str
        ``cg_m`` or ``cb_m``
    value : list of float
        Its x, y, z from the reference point, finite [m]
    length_m : float
        The vehicle's length [m]
    where : str
        The start of the sentence, naming the key (``"model.json: 'cg_m'"``)
    length_name : str
        What the length is called (``"the vehicle's length_m"``, ``"the hull's length"``)
    """
    far = max((float(v) for v in value), key=abs)
    if abs(far) <= length_m:
        return None
    return (f"{where} must lie within {length_name} ({length_m:g} m) of the reference point "
            f"[m], not {_show([float(v) for v in value])}"
            f"{unit_slip(far, -length_m, length_m)}")


#: A vehicle's mass against the mass of water its hull displaces (ρV, ρ = 1000 kg/m³): an
#: underwater vehicle is built near neutral buoyancy (a glider or a ballasted AUV within a few
#: per cent, a vehicle with a free-flooding hull or a heavy payload within a factor of 2 or
#: 3); outside this range of ratios the mass, or the hull's size, is in other units.
MASS_DISPLACEMENT_RANGE = (0.2, 5.0)
#: A given volume_m3 against the hull's own volume: a vehicle displaces about its hull's
#: volume (fins and appendages add little, a free-flooding part takes some away).
VOLUME_RANGE = (0.5, 2.0)


def vehicle_mass_problems(vehicle: Any, volume_m3: float, length_m: float) -> list[str]:
    """Problems of a ``[vehicle]``'s mass, volume and inertia against the hull it describes
    (its displaced volume ``volume_m3`` [m³] and length ``length_m`` [m]), one sentence each
    naming the key, its value, the bound and the likely slip: a mass outside
    :data:`MASS_DISPLACEMENT_RANGE` times ρV (a mass in grams, or a hull table in mm: its
    volume 10⁹ times too large), a ``volume_m3`` outside :data:`VOLUME_RANGE` times the
    hull's (litres for m³), an inertia above m·(L/2)², the most any body of mass m and length
    L can have about an axis through it (kg·mm² for kg·m²)."""
    problems = []
    mass = getattr(vehicle, "mass_kg", None)
    weight = getattr(vehicle, "weight_N", None)
    if mass is None and weight is not None:
        mass = float(weight) / _G
    disp = 1000.0 * volume_m3
    if mass is not None and disp > 0:
        ratio = mass / disp
        lo, hi = MASS_DISPLACEMENT_RANGE
        if not lo <= ratio <= hi:
            key = "mass_kg" if getattr(vehicle, "mass_kg", None) is not None else "weight_N"
            slip = ("was it given in g (or weight_N in kgf·1000)?" if ratio > hi else
                    "is the hull's size in mm (its table, or length_m), or the mass in t?")
            problems.append(f"'{key}' in [vehicle] gives {mass:.4g} kg, {ratio:.3g} times the "
                            f"{disp:.4g} kg of water its hull displaces ({volume_m3:.4g} m³, "
                            f"{length_m:.4g} m long); a vehicle weighs {lo:g}–{hi:g} times "
                            f"that: {slip}")
    volume = getattr(vehicle, "volume_m3", None)
    if volume is not None and volume_m3 > 0:
        ratio = float(volume) / volume_m3
        lo, hi = VOLUME_RANGE
        if not lo <= ratio <= hi:
            slip = ("was it given in litres?" if abs(math.log10(ratio) - 3.0) < 0.5
                    else "is it in other units?")
            problems.append(f"'volume_m3' in [vehicle] is {float(volume):g} m³, {ratio:.3g} "
                            f"times its hull's {volume_m3:.4g} m³ ({lo:g}–{hi:g} times is a "
                            f"vehicle's): {slip}")
    inertia = getattr(vehicle, "inertia_kg_m2", None)
    if inertia is not None and mass is not None and mass > 0:
        most = mass * (length_m / 2.0) ** 2
        big = [float(v) for v in inertia if float(v) > most]
        if big:
            slip = ": was it given in kg·mm²?" if max(big) / 1e6 <= most else "."
            problems.append(f"'inertia_kg_m2' in [vehicle] is {_show(list(inertia))}, more "
                            f"than m·(L/2)² = {most:.4g} kg·m², the most a body of {mass:.4g} "
                            f"kg and {length_m:.4g} m can have about an axis through it{slip}")
    return problems


def vehicle_geometry_problems(vehicle: Any, length_m: float, x_ref_m: float) -> list[str]:
    """Problems of a ``[vehicle]``'s positions and sizes against the hull it describes, one
    sentence each naming the key, its value, the bound and the likely slip (geometry typed in
    millimetres: :func:`unit_slip`).

    ``origin_m`` (the reference point aft of the nose tip) lies from 0 to L; each fin's
    ``x_m`` and ``x_drag_m`` (from the reference point, positive forward) on the hull, from
    ``x_ref_m - L`` (the tail) to ``x_ref_m`` (the nose); its ``span_m`` and ``chord_m`` at most
    L; ``cg_m`` and ``cb_m`` within L of the reference point (:func:`centre_problem`, as in
    model.json).

    Parameters
    ----------
    vehicle : towtank.ingest.vehicle_protocol.Vehicle
        The ``[vehicle]`` section
    length_m : float
        The length L of the hull it describes (after ``scale``) [m]
    x_ref_m : float
        The reference point aft of the nose tip: ``origin_m``, else the hull's centre of
        buoyancy [m]

    Returns
    -------
    list of str
        The problems, the reference point's first; empty when all lie on the hull.
    """
    tol = GEOMETRY_TOLERANCE * length_m
    hull = f"the hull's length of {length_m:.4g} m"
    problems = []
    origin = getattr(vehicle, "origin_m", None)
    if origin is not None and not -tol <= origin <= length_m + tol:
        problems.append(f"'origin_m' in [vehicle] is {origin:g} m aft of the nose tip, outside "
                        f"{hull} (it lies from 0 to {length_m:.4g} m)"
                        f"{unit_slip(origin, 0.0, length_m)}")
    ref = (f"origin_m, {x_ref_m:.4g} m aft of the nose tip" if origin is not None else
           f"the centre of buoyancy, {x_ref_m:.4g} m aft of the nose tip")
    low, high = x_ref_m - length_m, x_ref_m
    for i, fin in enumerate(getattr(vehicle, "fins", ()), start=1):
        label = f"[vehicle.fins #{i}]"
        for key in ("x_m", "x_drag_m"):
            x = getattr(fin, key, None)
            if x is not None and not low - tol <= x <= high + tol:
                problems.append(
                    f"'{key}' in {label} is {x:g} m, off the {length_m:.4g} m hull: it is "
                    f"measured from the reference point ({ref}), positive forward, so a fin "
                    f"lies from {low:.4g} m (the tail) to {high:.4g} m (the nose)"
                    f"{unit_slip(x, low, high)}")
        for key in ("span_m", "chord_m"):
            size = getattr(fin, key)
            if size > length_m + tol:
                problems.append(f"'{key}' in {label} is {size:g} m, more than {hull} that "
                                f"carries the fin{unit_slip(size, 0.0, length_m)}")
    for key in ("cg_m", "cb_m"):
        value = getattr(vehicle, key, None)
        if value is not None:
            far = centre_problem(key, value, length_m, f"'{key}' in [vehicle]",
                                 "the hull's length")
            if far:
                problems.append(far)
    return problems


def check_hull(x_m: np.ndarray, r_m: np.ndarray, name: str) -> list[str]:
    """Problems of a hull's dimensions, one sentence each.

    Parameters
    ----------
    x_m : numpy.ndarray
        Stations from the nose, increasing [m]
    r_m : numpy.ndarray
        Radius at each station [m]
    name : str
        Where the hull comes from (the table's file name, or the [vehicle] section)

    Returns
    -------
    list of str
        Empty when the stations are finite and increase strictly, the radii are finite and
        >= 0, the length lies within :data:`LENGTH_RANGE_M` and the fineness ratio L/D within
        :data:`FINENESS_RANGE`.
    """
    x = np.asarray(x_m, dtype=float)
    r = np.asarray(r_m, dtype=float)
    if len(x) < 3 or len(x) != len(r) or not (np.all(np.isfinite(x))
                                              and np.all(np.isfinite(r))):
        return [f"{name}: the hull needs at least 3 stations of finite numbers x_m, r_m."]
    problems = []
    if np.any(np.diff(x) <= 0):
        problems.append(f"{name}: x_m must increase strictly from nose to tail.")
    if np.any(r < 0) or r.max() <= 0:
        problems.append(f"{name}: r_m must be >= 0 m with at least one positive radius, not "
                        f"from {r.min():g} to {r.max():g} m.")
    if problems:
        return problems
    length = float(x[-1] - x[0])
    low, high = LENGTH_RANGE_M
    if not (math.isfinite(length) and low <= length <= high):
        return [f"{name}: the hull's length (x_m from {x[0]:g} to {x[-1]:g} m) must lie from "
                f"{low:g} to {high:g} m, not {length:g} m."]
    fineness = length / (2.0 * float(r.max()))
    if not FINENESS_RANGE[0] <= fineness <= FINENESS_RANGE[1]:
        problems.append(f"{name}: the hull's fineness ratio L/D must lie from "
                        f"{FINENESS_RANGE[0]:g} to {FINENESS_RANGE[1]:g}, not {fineness:.4g} "
                        f"(L = {length:g} m, largest r_m = {r.max():g} m).")
    return problems
