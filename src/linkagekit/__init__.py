"""linkagekit: analysis and design of planar linkages.

>>> import linkagekit as lk
>>> sorted(n for n in lk.__all__ if not n.endswith("Error"))[:4]
['Mechanism', 'Result', 'analyze', 'load']
"""

from .errors import InputError, LinkageError, MechanismFileError, NotSolvableError
from .model import Mechanism, load
from .sweep import Result, analyze

__version__ = "0.1.0"
__all__ = [
    "InputError",
    "LinkageError",
    "Mechanism",
    "MechanismFileError",
    "NotSolvableError",
    "Result",
    "analyze",
    "load",
]
