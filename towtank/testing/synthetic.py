"""Synthetic towing-tank runs whose truth is exactly known (the generator's public face).

The generator behind the shipped sample days and every physics test. A run is built in four
small, vectorised steps (no per-sample Python loops)::

    plan_profile / carriage_profile        carriage speed U(t) and acceleration a(t)
    hull_forces / fin_forces / tare_forces true forces on the model and on the mounting
    simulate_run                           + zero offset, drift, noise, vibration, mains hum
    write_run_file / write_run_sheet       CSV, CSV.gz or TDMS files and a run sheet

and whole days are made by :func:`make_hull_day` and :func:`make_fin_day`, which also write a
``truth.json`` holding everything needed to check a reduction: the truth dataclasses, the twelve
coefficients at the tank water's density, and per-run truth (plateau forces, tare, phases).

Conventions are those of docs/formats.md and docs/method.md: SI units, angles in degrees at the
interface, SNAME signs (added mass and damping negative). ``drag`` is the balance force along the
tow direction, positive when it pulls the model forward, so that at constant acceleration ``a``

    D_model = R(U, alpha) + (m - X_udot cos^2 alpha - Y_vdot sin^2 alpha) a.

Randomness comes only from the :class:`numpy.random.Generator` passed in (or derived from a
seed), so a seed gives identical numbers and, through the writers, identical file bytes.

The generator lives in four modules, in the order a run is made: :mod:`~towtank.testing.truth`
(truths and true forces), :mod:`~towtank.testing.profiles` (carriage profiles),
:mod:`~towtank.testing.instruments` (the recorded channels and run files) and
:mod:`~towtank.testing.days` (sheets, plans, truth files, protocols, sample days); this module
gathers their public names.
"""

# ruff: noqa: F405 - __all__ names the re-exported public names
from towtank.testing.air_day import *  # noqa: F403
from towtank.testing.days import *  # noqa: F403
from towtank.testing.instruments import *  # noqa: F403
from towtank.testing.profiles import *  # noqa: F403
from towtank.testing.truth import *  # noqa: F403

__all__ = [
    "GENERATOR_VERSION",
    "SUT2_TABLE4_PRIME",
    "CarriagePlan",
    "plan_profile",
    "carriage_profile",
    "HullTruth",
    "sut2_hull_truth",
    "TareTruth",
    "FinTruth",
    "Noise",
    "hull_forces",
    "fin_forces",
    "tare_forces",
    "simulate_run",
    "LabChannels",
    "to_file_frame",
    "write_run_file",
    "write_run_sheet",
    "RunSpec",
    "DayTruth",
    "hull_day_plan",
    "fin_day_plan",
    "make_hull_day",
    "make_fin_day",
    "air_hull_day_plan",
    "make_air_hull_day",
    "air_protocol_sections",
    "AIR_SPEED_FACTOR",
    "AIR_MODEL_MASS_KG",
    "write_truth",
    "load_truth",
    "write_protocol",
    "hull_protocol_sections",
    "fin_protocol_sections",
    "write_sample_protocols",
    "write_sample_days",
]
