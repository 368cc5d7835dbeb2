"""What a vehicle's model rests on: model.json ``assumptions`` (docs/formats.md §6).

Each entry is ``{"input", "value", "source", "note"}``: ``source`` is ``"given"`` (the
protocol's ``[vehicle]`` gives it), ``"computed"`` (derived from given inputs, e.g. the
buoyancy from the hull's volume) or ``"default"`` (towtank's own choice where nothing is given,
e.g. the centre of gravity at the centre of buoyancy). A given input the protocol itself marks
as a guess (``[vehicle.assumed]``: input = "why") keeps ``"given"`` with the note
``"assumed: why"``. :func:`guessed` are the entries a user should know were not measured: the
defaults and the protocol's assumed inputs; :func:`guessed_line` prints them in one line.
"""

from __future__ import annotations

from typing import Any

__all__ = ["SOURCES", "NEUTRAL_TOLERANCE", "vehicle_assumptions", "guessed", "guessed_line",
           "neutral_warning", "check_assumptions"]

#: The sources of an assumption.
SOURCES = ("given", "computed", "default")
#: Largest relative difference between the hull's displaced mass and the vehicle's mass of a
#: vehicle declared neutrally buoyant [-].
NEUTRAL_TOLERANCE = 0.05

#: model.json's mass properties: (key, how a default value is chosen, unit).
_MASS_KEYS = (("mass_kg", "kg"), ("weight_N", "N"), ("buoyancy_N", "N"), ("cg_m", "m"),
              ("cb_m", "m"), ("inertia_kg_m2", "kg m^2"))
#: The rules of mass_properties whose values are towtank's guesses, not derived from given
#: ones (the others, e.g. "hull centre of buoyancy", compute a value from the hull).
_DEFAULT_RULES = ("neutrally buoyant: buoyancy_N / g", "centre of buoyancy",
                  "uniform density filling the hull")


def _source(rule: str) -> str:
    """given, default or computed, from mass_properties' ``sources`` entry."""
    if rule == "given":
        return "given"
    return "default" if rule in _DEFAULT_RULES else "computed"


def vehicle_assumptions(vehicle: Any, masses: dict[str, Any],
                        assumed: dict[str, str] | None = None) -> list[dict[str, Any]]:
    """The ``assumptions`` of a ``[vehicle]``'s model.

    Parameters
    ----------
    vehicle : towtank.ingest.vehicle_protocol.Vehicle
        The ``[vehicle]`` section
    masses : dict
        :func:`towtank.vehicle.model.mass_properties` (its ``sources`` say which value was
        given and how the others were computed)
    assumed : dict, optional
        ``[vehicle.assumed]``: {input: why the protocol guessed it}

    Returns
    -------
    list of dict
        One entry per mass property, the hull, the fins and each glider input, then any input
        of ``assumed`` not among those.
    """
    assumed = dict(assumed or {})
    rows: list[dict[str, Any]] = []

    def add(name: str, value: Any, source: str, note: str) -> None:
        why = assumed.pop(name, None)
        if why is not None:
            note = f"assumed: {why}"
        rows.append({"input": name, "value": value, "source": source, "note": note})

    for key, unit in _MASS_KEYS:
        rule = masses["sources"][key]
        add(key, masses[key], _source(rule),
            f"[{unit}] " + ("given in [vehicle]" if rule == "given" else rule))
    add("hull", vehicle.hull, "given", "the hull's shape")
    add("fins", len(vehicle.fins), "given",
        "fin pairs of [[vehicle.fins]]" if vehicle.fins else "no fins")
    for key, value in sorted((getattr(vehicle, "glider", None) or {}).items()):
        add(f"glider.{key}", value, "given", "[vehicle.glider]")
    for key, why in assumed.items():
        rows.append({"input": key, "value": getattr(vehicle, key, None), "source": "given",
                     "note": f"assumed: {why}"})
    return rows


def guessed(assumptions: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The defaults and the inputs the protocol marks as assumed."""
    return [a for a in assumptions
            if a["source"] == "default" or str(a["note"]).startswith("assumed")]


def guessed_line(assumptions: list[dict[str, Any]] | None) -> str:
    """One line naming the guessed inputs (model.json ``assumptions``), "" when none."""
    names = [str(a["input"]) for a in guessed(assumptions or [])]
    if not names:
        return ""
    return ("assumed, not measured (model.json 'assumptions'): " + ", ".join(names))


def neutral_warning(name: str, masses: dict[str, Any], hull_volume_m3: float,
                    rho: float) -> str:
    """"" or the warning of a vehicle declared neutrally buoyant (its buoyancy equal to its
    weight within 1 %) whose hull displaces more than :data:`NEUTRAL_TOLERANCE` more or less
    than its mass."""
    weight, buoyancy = float(masses["weight_N"]), float(masses["buoyancy_N"])
    mass = float(masses["mass_kg"])
    displaced = rho * hull_volume_m3
    if abs(buoyancy - weight) > 0.01 * weight or abs(displaced - mass) <= NEUTRAL_TOLERANCE * mass:
        return ""
    return (f"{name}: the vehicle is declared neutrally buoyant at {mass:.4g} kg, but its hull "
            f"displaces {displaced:.4g} kg of water ({displaced / mass - 1:+.0%}); its "
            "buoyancy, or its hull, is an assumption (model.json 'assumptions').")


def check_assumptions(value: Any, name: str) -> list[str]:
    """Problems of model.json's ``assumptions``, one sentence each: a list of objects whose
    ``input`` and ``note`` are text and ``source`` one of :data:`SOURCES`."""
    if not isinstance(value, list):
        return [f"{name}: 'assumptions' must be a list of objects {{input, value, source, "
                f"note}}, not {type(value).__name__}."]
    problems = []
    for i, entry in enumerate(value, start=1):
        ok = (isinstance(entry, dict) and isinstance(entry.get("input"), str)
              and isinstance(entry.get("note"), str) and entry.get("source") in SOURCES
              and "value" in entry)
        if not ok:
            problems.append(f"{name}: 'assumptions' entry {i} must be an object with 'input' "
                            f"and 'note' (text), 'value' and 'source' ({', '.join(SOURCES)}).")
    return problems
