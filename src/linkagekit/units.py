"""Units accepted in mechanism files, and their conversion factors to SI."""

from __future__ import annotations

import math

#: metres per file length unit
LENGTH_UNITS: dict[str, float] = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254}
#: radians per file angle unit
ANGLE_UNITS: dict[str, float] = {"deg": math.pi / 180.0, "rad": 1.0}
