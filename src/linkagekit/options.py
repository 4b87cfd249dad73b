"""Analysis options declared once: what each value means, parsed at the boundary from the words files and the CLI use.

Light (standard library only): the command line builds its choices from here without loading NumPy.

Examples
--------
>>> BranchMode.parse("continuous")
<BranchMode.CONTINUOUS: 'continuous'>
>>> BranchMode.words()
('pose', 'continuous')
"""

from __future__ import annotations

from enum import Enum

from .errors import InputError, shorten

__all__ = ["BranchMode"]


class BranchMode(Enum):
    """Which assembly mode a sweep keeps (``analyze(..., branch=)``, ``analyze --branch``).

    ``POSE``: every sign step keeps the reference pose's sign at every input (the default).
    ``CONTINUOUS``: the signs are followed through change points from the pose's input
    (:mod:`linkagekit.branch`), and a sample exactly at a change point takes the branch's limit there.
    """

    POSE = "pose"
    CONTINUOUS = "continuous"

    @classmethod
    def words(cls) -> tuple[str, ...]:
        """The words that name the modes, in declaration order."""
        return tuple(m.value for m in cls)

    @classmethod
    def parse(cls, value: object) -> BranchMode:
        """A mode from its word (or the mode itself); anything else is an :class:`InputError` naming ``branch``."""
        if isinstance(value, cls):
            return value
        try:
            return cls(value)
        except ValueError:
            choices = " or ".join(repr(w) for w in cls.words())
            raise InputError(f"branch: expected {choices}, got {shorten(repr(value))}") from None
