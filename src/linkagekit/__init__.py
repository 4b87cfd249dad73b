"""linkagekit: analysis and design of planar linkages.

The public names load lazily, so ``import linkagekit`` is light (NumPy comes with the
first solve, pydantic with the first file read).

>>> import linkagekit as lk
>>> sorted(n for n in lk.__all__ if not n.endswith("Error"))[:6]
['Mechanism', 'Result', 'analyze', 'analyze_chunks', 'animate', 'build_scene']
"""

from typing import TYPE_CHECKING

from .errors import (
    InputError,
    LinkageError,
    MechanismFileError,
    MethodNotApplicableError,
    NotSolvableError,
    UnknownNameError,
)

__version__ = "0.1.0"

_LAZY = {
    "Mechanism": "model",
    "load": "files",
    "save": "files",
    "analyze": "api",
    "analyze_chunks": "api",
    "reference_signs": "api",
    "Result": "result",
    "check": "checks",
    "modes": "checks",
    "simulate": "dynamics",
    "reduced": "dynamics",
    "size_flywheel": "flywheel",
    "build_scene": "viz.scene",
    "draw_mechanism": "viz.draw",
    "plot_quantity": "viz.draw",
    "animate": "viz.animate",
    "write_report": "web.report",
    "synthesize": "synthesis.run",
    "read_targets": "synthesis.targets",
}

__all__ = [
    "InputError",
    "LinkageError",
    "Mechanism",
    "MechanismFileError",
    "MethodNotApplicableError",
    "NotSolvableError",
    "Result",
    "UnknownNameError",
    "analyze",
    "analyze_chunks",
    "animate",
    "build_scene",
    "check",
    "draw_mechanism",
    "load",
    "modes",
    "plot_quantity",
    "read_targets",
    "reduced",
    "reference_signs",
    "save",
    "simulate",
    "size_flywheel",
    "synthesize",
    "write_report",
]

if TYPE_CHECKING:  # pragma: no cover
    from .api import analyze, analyze_chunks, reference_signs
    from .checks import check, modes
    from .dynamics import reduced, simulate
    from .files import load, save
    from .flywheel import size_flywheel
    from .model import Mechanism
    from .result import Result
    from .synthesis.run import synthesize
    from .synthesis.targets import read_targets
    from .viz.animate import animate
    from .viz.draw import draw_mechanism, plot_quantity
    from .viz.scene import build_scene
    from .web.report import write_report


def __getattr__(name: str) -> object:
    """The public name ``name``, imported from its module on first use (PEP 562)."""
    from importlib import import_module

    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'linkagekit' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public names (``__all__``) and the module's dunder attributes, not its helpers or submodules."""
    return sorted(set(__all__) | {n for n in globals() if n.startswith("__") and n.endswith("__")})


del TYPE_CHECKING  # a helper of this file, not a name of the package
