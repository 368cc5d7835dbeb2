"""A lab's run-file columns: names and load-cell calibrations of the synthetic files.

:class:`LabChannels` is shared by the run-file writers (:mod:`towtank.testing.instruments`)
and the other labs' layouts (:mod:`towtank.testing.layouts`), so that neither imports the other
for it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["LabChannels"]


@dataclass(frozen=True)
class LabChannels:
    """A lab's column names and load-cell calibrations (value = gain * (raw - offset)).

    Parameters
    ----------
    time, speed, accel : str
        Column names of the time [s], carriage speed [m/s] and acceleration [m/s^2] channels.
    drag, lift : str
        Column names of the load cells, recorded in volts.
    drag_gain, lift_gain : float
        Calibrations [N/V]; the lift cell is mounted reversed (negative gain).
    drag_offset, lift_offset : float
        Electrical offsets [V].
    """

    time: str = "Time (s)"
    speed: str = "Carriage speed (m/s)"
    accel: str = "Carriage accel (m/s^2)"
    drag: str = "Fx load cell (V)"
    lift: str = "Fy load cell (V)"
    drag_gain: float = 20.0
    drag_offset: float = 0.0
    lift_gain: float = -25.0
    lift_offset: float = 0.0

    def protocol_section(self, accel: bool = False) -> dict[str, dict[str, Any]]:
        """The protocol's ``[channels]`` table for files written in this style."""
        out: dict[str, dict[str, Any]] = {
            "time": {"column": self.time},
            "speed": {"column": self.speed},
        }
        if accel:
            out["accel"] = {"column": self.accel}
        out["drag"] = {"column": self.drag, "gain": self.drag_gain, "offset": self.drag_offset}
        out["lift"] = {"column": self.lift, "gain": self.lift_gain, "offset": self.lift_offset}
        return out
