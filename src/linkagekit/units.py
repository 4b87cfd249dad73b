"""Units accepted in mechanism files, and their conversion factors to SI."""

from __future__ import annotations

import math
from enum import Enum

#: metres per file length unit
LENGTH_UNITS: dict[str, float] = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254}
#: radians per file angle unit
ANGLE_UNITS: dict[str, float] = {"deg": math.pi / 180.0, "rad": 1.0}


class UnitKind(Enum):
    """What a quantity measures; :meth:`symbol` gives its unit in a file's units."""

    NONE = "none"
    LENGTH = "length"
    VELOCITY = "velocity"
    ACCELERATION = "acceleration"
    ANGLE = "angle"
    ANGULAR_VELOCITY = "angular velocity"
    ANGULAR_ACCELERATION = "angular acceleration"
    FORCE = "force"
    TORQUE = "torque"
    POWER = "power"
    TIME = "time"

    def symbol(self, length_unit: str, angle_unit: str) -> str:
        """The unit as shown in headers and on plots (``""`` for none).

        >>> UnitKind.ACCELERATION.symbol("mm", "deg"), UnitKind.TORQUE.symbol("mm", "deg")
        ('mm/s²', 'N·m')
        """
        fixed = {
            UnitKind.NONE: "",
            UnitKind.LENGTH: length_unit,
            UnitKind.VELOCITY: f"{length_unit}/s",
            UnitKind.ACCELERATION: f"{length_unit}/s²",
            UnitKind.ANGLE: angle_unit,
            UnitKind.ANGULAR_VELOCITY: "rad/s",
            UnitKind.ANGULAR_ACCELERATION: "rad/s²",
            UnitKind.FORCE: "N",
            UnitKind.TORQUE: "N·m",
            UnitKind.POWER: "W",
            UnitKind.TIME: "s",
        }
        return fixed[self]
