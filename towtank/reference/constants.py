"""Physical constants shared by the stages: the one home of each."""

from __future__ import annotations

#: Standard acceleration of gravity g_n [m/s²] (CGPM 1901; CODATA, exact by definition).
STANDARD_GRAVITY = 9.80665
