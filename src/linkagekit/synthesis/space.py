"""Design spaces: which joints of a template mechanism move, within which bounds.

A candidate design is a reference pose (docs/mechanism-files.md): the template's joints, with the
free ones moved to the candidate's coordinates. Its link lengths, its assembly mode and its
driver's input at the pose all come from that pose, exactly as for a mechanism file, so a
batch of candidates is one :func:`linkagekit.params.compile` over the design axis.

The design vector of a space is ``[x_0, y_0, x_1, y_1, ...]`` over its free joints, in
the template's length unit.

Three built-in topologies carry a tracer point ``P`` and a driver link ``crank``:

``fourbar``
    Ground pivots A, B; crank A-C; coupler C-D-P; rocker B-D.
``watt2``
    Two four-bars in series: ground A, B, E; crank A-C; coupler1 C-D; ternary rocker
    B-D-F; coupler2 F-G-P; output E-G.
``stephenson3``
    A four-bar whose coupler drives a dyad to a third ground pivot (Norton's Stephenson
    type III): ground A, B, F; crank A-C; coupler C-D-E; rocker B-D; link5 E-G-P; link6 F-G.

Examples
--------
>>> import numpy as np
>>> sp = builtin_space("fourbar", center=(0.0, 0.0), size=1.0, unit="m")
>>> sp.free, sp.dim
(('A', 'B', 'C', 'D', 'P'), 10)
>>> sp.poses(np.zeros((3, 10))).shape
(3, 5, 2)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import InputError, UnknownNameError
from ..model import CrankType

if TYPE_CHECKING:
    from ..model import Mechanism
    from ..plan import Plan

#: the topologies built in, by name (``--topology``)
TOPOLOGIES = ("fourbar", "watt2", "stephenson3")

# joint -> a pose in a unit square (any distinct points are a valid pose: lengths come from it)
_TEMPLATES: dict[str, dict[str, Any]] = {
    "fourbar": {
        "joints": {"A": [0, 0], "B": [1, 0], "C": [0.3, 0], "D": [0.8, 0.6], "P": [0.5, 0.9]},
        "links": {"ground": ["A", "B"], "crank": ["A", "C"], "coupler": ["C", "D", "P"], "rocker": ["B", "D"]},
        "transmission": [("D", "C", "B")],
    },
    "watt2": {
        "joints": {
            "A": [0, 0],
            "B": [0.6, 0],
            "E": [1.1, 0.8],
            "C": [0.17, 0.1],
            "D": [0.77, 0.47],
            "F": [1.02, 0.27],
            "G": [1.3, 0.53],
            "P": [1.1, 0.55],
        },
        "links": {
            "ground": ["A", "B", "E"],
            "crank": ["A", "C"],
            "coupler1": ["C", "D"],
            "rocker": ["B", "D", "F"],
            "coupler2": ["F", "G", "P"],
            "output": ["E", "G"],
        },
        "transmission": [("D", "C", "B"), ("G", "F", "E")],
    },
    "stephenson3": {
        "joints": {
            "A": [0, 0],
            "B": [1, 0],
            "F": [1.6, 0.9],
            "C": [0.3, 0],
            "D": [0.9, 0.7],
            "E": [0.6, 1.1],
            "G": [1.3, 1.5],
            "P": [0.9, 1.6],
        },
        "links": {
            "ground": ["A", "B", "F"],
            "crank": ["A", "C"],
            "coupler": ["C", "D", "E"],
            "rocker": ["B", "D"],
            "link5": ["E", "G", "P"],
            "link6": ["F", "G"],
        },
        "transmission": [("D", "C", "B"), ("G", "E", "F")],
    },
}


@dataclass(frozen=True, eq=False)
class DesignSpace:
    """A template mechanism and the bounds of its free joints.

    Attributes
    ----------
    template : Mechanism
        The topology (links, driver, units); joints not in ``free`` keep its pose.
    free : tuple of str
        The joints the design moves, in design-vector order.
    lower, upper : ndarray, shape (2 * len(free),)
        Bounds of ``[x_0, y_0, x_1, y_1, ...]`` in the template's length unit.
    tracer : str
        The joint whose path is synthesised.
    transmission : tuple of (joint, a, b)
        Angles ``a - joint - b`` kept within ``[MIN, 180 - MIN]`` degrees over the motion
        (the transmission angle of each dyad that carries the motion).
    topology : str
        The built-in name, or the template's source.
    """

    template: Mechanism
    free: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    tracer: str = "P"
    transmission: tuple[tuple[str, str, str], ...] = ()
    topology: str = ""
    _index: dict[str, int] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        names = self.template.joint_names
        for j in (*self.free, self.tracer, *(n for t in self.transmission for n in t)):
            if j not in names:
                raise UnknownNameError(f"{self.topology or 'design space'}: no joint named '{j}'")
        if len(self.template.drivers) != 1 or not isinstance(self.template.drivers[0].type, CrankType):
            raise InputError(f"{self.topology}: synthesis needs exactly one crank driver (a driven angle)")
        if len(self.lower) != self.dim or len(self.upper) != self.dim or np.any(self.lower >= self.upper):
            raise InputError(f"{self.topology}: every free coordinate needs bounds low < high")
        self._index.update({n: i for i, n in enumerate(names)})

    @property
    def dim(self) -> int:
        """Length of the design vector."""
        return 2 * len(self.free)

    @property
    def driver(self) -> str:
        """The driven link's name."""
        return self.template.drivers[0].name

    @cached_property
    def plan(self) -> Plan:
        """The template's solve plan, compiled once (topology only)."""
        from ..plan import make_plan

        return make_plan(self.template)

    def joint(self, name: str) -> int:
        """Index of a joint in the plan's (and the poses') joint order."""
        return self._index[name]

    def poses(self, X: np.ndarray) -> np.ndarray:
        """Reference poses ``(N, n_joints, 2)`` of the design vectors ``X`` (N, dim)."""
        X = np.asarray(X, float)
        base = self.template.pose_array()
        out = np.broadcast_to(base, (X.shape[0], *base.shape)).copy()
        idx = [self._index[j] for j in self.free]
        out[:, idx, :] = X[:, : self.dim].reshape(X.shape[0], len(self.free), 2)
        return out

    def vector(self, mech: Mechanism) -> np.ndarray:
        """The design vector of a mechanism of this topology (its pose's free joints)."""
        pose = mech.pose_array()
        names = mech.joint_names
        return np.concatenate([pose[names.index(j)] for j in self.free])

    def mechanism(
        self,
        x: np.ndarray,
        name: str | None = None,
        place: tuple[complex, complex] = (1.0, 0.0),
        sweep: tuple[float, float, float] | None = None,
    ) -> Mechanism:
        """The mechanism of one design vector (the template with the candidate's pose, lengths from it).

        ``place``: ``(a, b)``, the pose is moved, turned and scaled to ``a z + b`` (complex
        ``z = x + iy``); ``sweep``: the driver's ``angles`` ``(start, stop, step)`` in radians
        (written in the template's angle unit).
        """
        from ..model import Mechanism as _M
        from ..units import ANGLE_UNITS

        data = self.template.to_dict()
        pose = self.poses(np.asarray(x, float)[None])[0]
        z = place[0] * (pose[:, 0] + 1j * pose[:, 1]) + place[1]
        data["joints"] = {j: [float(z[i].real), float(z[i].imag)] for j, i in self._index.items()}
        for link in data["links"].values():
            if isinstance(link, dict):
                link.pop("lengths", None)
        if sweep is not None:
            per_radian = 1.0 / ANGLE_UNITS[self.template.angle_unit]
            start, stop, step = (v * per_radian for v in sweep)
            data["drivers"][0]["angles"] = {"start": start, "stop": stop, "step": step}
        if name is not None:
            data["name"] = name
        return _M.from_dict(data, source=name or "<synthesis>")


def builtin_space(
    topology: str,
    center: tuple[float, float],
    size: float,
    unit: str = "m",
    reach: float = 1.0,
    tracer_box: tuple[np.ndarray, np.ndarray] | None = None,
    pivot_box: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> DesignSpace:
    """A built-in topology (``TOPOLOGIES``) with bounds scaled to the targets.

    Every joint lies within ``reach * size`` of ``center`` along x and y (``size``: the
    targets' bounding-box diagonal); the tracer, at the pose, within ``tracer_box`` (the
    targets' box with a margin) when given; ground pivots within ``pivot_box``
    ``((xmin, xmax), (ymin, ymax))`` when given.
    """
    from ..model import Mechanism

    t = _template(topology)
    joints = {j: [center[0] + size * (x - 0.5), center[1] + size * (y - 0.5)] for j, (x, y) in t["joints"].items()}
    data = {
        "format": "linkagekit/1",
        "name": f"synthesised {topology}",
        "units": {"length": unit, "angle": "deg"},
        "joints": joints,
        "links": t["links"],
        "drivers": [{"link": "crank", "pivot": "A", "toward": "C", "angles": {"start": 0, "stop": 360, "step": 1}}],
    }
    mech = Mechanism.from_dict(data, source=topology)
    free = tuple(t["joints"])
    ground = set(t["links"]["ground"])
    lo = np.empty(2 * len(free))
    hi = np.empty(2 * len(free))
    for i, j in enumerate(free):
        box = (
            (center[0] - reach * size, center[0] + reach * size),
            (center[1] - reach * size, center[1] + reach * size),
        )
        if j == "P" and tracer_box is not None:
            box = ((tracer_box[0][0], tracer_box[1][0]), (tracer_box[0][1], tracer_box[1][1]))
        if j in ground and pivot_box is not None:
            box = pivot_box
        lo[2 * i : 2 * i + 2] = box[0][0], box[1][0]
        hi[2 * i : 2 * i + 2] = box[0][1], box[1][1]
    return DesignSpace(mech, free, lo, hi, "P", tuple(t["transmission"]), topology)


def is_builtin(topology: str) -> bool:
    """A built-in topology's name: ``TOPOLOGIES``, or an enumerated one of :mod:`.topologies` (``sixbar-3``)."""
    from .topologies import by_name

    if topology in _TEMPLATES:
        return True
    try:
        by_name(topology)
    except InputError:
        return False
    return True


def _template(topology: str) -> dict[str, Any]:
    """Joints in a unit pose, links and transmission angles of a built-in topology (hand-drawn or enumerated)."""
    if topology in _TEMPLATES:
        return _TEMPLATES[topology]
    if topology == "auto":
        raise InputError("topology: 'auto' is a search of its own: linkagekit.synthesis.auto.synthesize_auto(targets)")
    if not is_builtin(topology):
        raise InputError(  # the command line names its files itself: this is the Python argument's message
            f"topology: unknown topology '{topology}' (built in: {', '.join(TOPOLOGIES)}, or a name that "
            "--topology auto (synthesis.auto.synthesize_auto) reports, such as 'sixbar-1'; a template file is given "
            "as a Mechanism: lk.load(FILE))"
        )
    from .topologies import by_name

    t = by_name(topology)
    pose = t.pose()
    return {
        "joints": {j: [0.5 + 0.5 * pose[j][0], 0.5 + 0.5 * pose[j][1]] for j in t.order},
        "links": {name: list(joints) for name, joints in t.links},
        "transmission": list(t.transmission),
    }


def fixed(space: DesignSpace, joints: Sequence[str]) -> DesignSpace:
    """``space`` with ``joints`` no longer free: they stay at the template's pose.

    ``--shape-only`` fixes a built-in topology's ground pivots ``A`` and ``B`` so: a curve is
    matched up to a similarity, which moves, turns and scales the ground line anyway, so
    their four coordinates would only add a flat valley of equal designs to the search.

    >>> sp = fixed(builtin_space("fourbar", (0.0, 0.0), 1.0), ["A", "B"])
    >>> sp.free, sp.dim, sp.poses(np.zeros((1, 6)))[0, :2].tolist()
    (('C', 'D', 'P'), 6, [[-0.5, -0.5], [0.5, -0.5]])
    """
    keep = [i for i, j in enumerate(space.free) if j not in joints]
    cols = [c for i in keep for c in (2 * i, 2 * i + 1)]
    free = tuple(space.free[i] for i in keep)
    return DesignSpace(
        space.template, free, space.lower[cols], space.upper[cols], space.tracer, space.transmission, space.topology
    )


def template_space(
    mech: Mechanism,
    free: Mapping[str, Sequence[Sequence[float]]] | Sequence[str],
    center: tuple[float, float],
    size: float,
    reach: float = 1.0,
    tracer: str = "P",
    transmission: Sequence[tuple[str, str, str]] | None = None,
) -> DesignSpace:
    """A design space from a mechanism file used as a template.

    ``free`` names the joints that move: a mapping ``joint -> ((xmin, xmax), (ymin, ymax))``,
    or a list of joints that each move within ``reach * size`` of ``center``. The other joints
    stay where the template has them. ``transmission`` defaults to every joint of two binary
    links whose other ends are both placed before it (the joint where a dyad closes).
    A template with sliders is refused (:class:`~linkagekit.errors.InputError`): the bound on
    the transmission angle is checked at pin joints only, so a slider's would go unchecked.
    """
    if mech.sliders:  # the dyads' transmission angles are pin angles: a slider's has no (joint, a, b) form
        raise InputError(
            f"{mech.source}: a template with sliders ({', '.join(s.link for s in mech.sliders)}) cannot be"
            " synthesized: its transmission angle would go unchecked (pin-jointed templates only)"
        )
    names = mech.joint_names
    if isinstance(free, Mapping):
        items = [(j, free[j]) for j in free]
    else:
        box = (
            (center[0] - reach * size, center[0] + reach * size),
            (center[1] - reach * size, center[1] + reach * size),
        )
        items = [(j, box) for j in free]
    for j, _ in items:
        if j not in names:
            raise UnknownNameError(f"{mech.source}: --free: no joint named '{j}' (joints: {', '.join(names)})")
    if any(tracer in ln.joints for ln in mech.links if ln.name == "ground"):
        raise InputError(f"{mech.source}: the tracer {tracer} is on the ground link: it draws no curve")
    lo = np.array([b[k][0] for _, b in items for k in (0, 1)], float)
    hi = np.array([b[k][1] for _, b in items for k in (0, 1)], float)
    if transmission is None:
        transmission = _dyad_angles(mech)
    return DesignSpace(mech, tuple(j for j, _ in items), lo, hi, tracer, tuple(transmission), mech.source)


def _dyad_angles(mech: Mechanism) -> list[tuple[str, str, str]]:
    """(joint, a, b) for every joint where exactly two links meet, one of them binary, and neither is ground.

    That is where a dyad closes (the rocker's joint with the coupler); its angle is the dyad's
    transmission angle.
    """
    out = []
    grounded = {j for ln in mech.links if ln.name == "ground" for j in ln.joints}
    for j in mech.joint_names:
        links = [ln for ln in mech.links if j in ln.joints]
        if len(links) != 2 or j in grounded or any(ln.name == "ground" or len(ln.joints) < 2 for ln in links):
            continue
        a, b = (next(o for o in ln.joints if o != j) for ln in links)
        if any(len(ln.joints) == 2 for ln in links) and a != b and not (a in grounded and b in grounded):
            out.append((j, a, b))
    drivers = {d.name for d in mech.drivers}
    return [t for t in out if not any(ln.name in drivers and t[0] in ln.joints for ln in mech.links)]
