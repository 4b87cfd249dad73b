"""The ``linkagekit`` command line.

Exit status: 0 on success, 2 on a bad file or bad arguments (one line on stderr), 1 on
anything else.  Commands: ``analyze``, ``modes``, ``check``.
"""

from __future__ import annotations

import csv
import io
import json
import math
import sys
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .errors import InputError, LinkageError
from .model import Mechanism, load
from .sweep import Result, analyze

app = typer.Typer(
    name="linkagekit",
    help="Analyse planar linkages described in YAML/JSON mechanism files.",
    add_completion=False,
    pretty_exceptions_enable=False,
    no_args_is_help=True,
)


class Method(StrEnum):
    natural = "natural"
    vector_loop = "vector-loop"


class Fmt(StrEnum):
    table = "table"
    csv = "csv"
    json = "json"


class ModeFmt(StrEnum):
    table = "table"
    json = "json"


# ---------------------------------------------------------------------- argument parsing
def _numbers(text: str, what: str) -> list[float]:
    out = []
    for part in text.split(","):
        part = part.strip()
        try:
            v = float(part)
        except ValueError:
            raise InputError(f"{what}: '{part}' is not a number") from None
        if not math.isfinite(v):
            raise InputError(f"{what}: '{part}' is not a finite number")
        out.append(v)
    return out


def _range(text: str, what: str) -> np.ndarray:
    parts = text.split(":")
    if len(parts) != 3:
        raise InputError(f"{what}: expected START:STOP:STEP, got '{text}'")
    start, stop, step = (_numbers(p, what)[0] for p in parts)
    if step == 0 or (stop - start) * step < 0:
        raise InputError(f"{what}: STEP must be non-zero and go from START toward STOP, got '{text}'")
    n = math.floor((stop - start) / step * (1 + 1e-12) + 1e-9) + 1
    if n > 10**8:
        raise InputError(f"{what}: more than 10^8 samples")
    return start + step * np.arange(n)


def _by_driver(mech: Mechanism, items: list[str], option: str, parse: Any) -> dict[str, Any]:
    """Split ``NAME=VALUE`` items (or a bare VALUE for a single driver) by driver."""
    names = [d.name for d in mech.drivers]
    out: dict[str, Any] = {}
    for item in items:
        if "=" in item:
            name, _, text = item.partition("=")
            name = name.strip()
            if name not in names:
                raise InputError(f"{option}: no driver named '{name}' (drivers: {', '.join(names)})")
        else:
            if len(names) != 1:
                raise InputError(f"{option}: this mechanism has drivers {', '.join(names)}: write {option} NAME=...")
            name, text = names[0], item
        if name in out:
            raise InputError(f"{option}: driver '{name}' given twice")
        out[name] = parse(text, f"{option} {item}")
    return out


def _inputs(mech: Mechanism, at: list[str] | None, angles: list[str] | None) -> dict[str, np.ndarray] | None:
    if at and angles:
        raise InputError("give --at or --angles, not both")
    if at:
        return {k: np.array(v) for k, v in _by_driver(mech, at, "--at", _numbers).items()}
    if angles:
        return _by_driver(mech, angles, "--angles", _range)
    return None


def _rates(mech: Mechanism, items: list[str] | None, option: str) -> dict[str, float] | None:
    if not items:
        return None
    return {k: v[0] if len(v) == 1 else _too_many(option) for k, v in _by_driver(mech, items, option, _numbers).items()}


def _too_many(option: str) -> float:
    raise InputError(f"{option}: one value per driver")


def _emit(text: str, out: Path | None) -> None:
    if out is None:
        sys.stdout.write(text)
        return
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InputError(f"-o {out}: cannot write: {exc.strerror or exc}") from None


# ---------------------------------------------------------------------- formatting
def _fmt(v: float, digits: int = 6) -> str:
    return "—" if not np.isfinite(v) else f"{v:.{digits}g}"


def result_csv(res: Result) -> str:
    """One row per sample: inputs, flags, every joint's x, y, vx, vy, ax, ay, every link's motion, forces."""
    m = res.mechanism
    cols: list[tuple[str, np.ndarray]] = [(f"input:{k}", v) for k, v in res.inputs.items()]
    cols += [("assembled", res.assembled.astype(float)), ("singular", res.singular.astype(float))]
    for j in m.joint_names:
        z, v, a = res.point(j), res.velocity(j), res.acceleration(j)
        cols += [
            (f"{j}.x", z.real),
            (f"{j}.y", z.imag),
            (f"{j}.vx", v.real),
            (f"{j}.vy", v.imag),
            (f"{j}.ax", a.real),
            (f"{j}.ay", a.imag),
        ]
    for ln in m.links:
        cols += [
            (f"{ln.name}.angle", res.link_angle[ln.name]),
            (f"{ln.name}.omega", res.link_omega[ln.name]),
            (f"{ln.name}.alpha", res.link_alpha[ln.name]),
        ]
    if res.forces is not None:
        cols += res.forces.columns()
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([c for c, _ in cols])
    for i in range(res.n):
        row = []
        for name, arr in cols:
            x = float(arr[i])
            if name in ("assembled", "singular"):
                row.append("true" if x else "false")
            else:
                row.append("" if not np.isfinite(x) else repr(x))
        w.writerow(row)
    return buf.getvalue()


def result_table(res: Result, console: Console) -> None:
    m = res.mechanism
    lu, au = m.length_unit, m.angle_unit
    moving = [j for j in m.joint_names if j not in m.link("ground").joints]
    inputs = list(res.inputs.items())

    def table(title: str, heads: list[str], values: list[np.ndarray]) -> None:
        t = Table(title=title, title_justify="left", header_style="bold")
        for name, _ in inputs:
            t.add_column(
                f"{name} [{au if m.drivers[[d.name for d in m.drivers].index(name)].kind == 'angle' else lu}]",
                justify="right",
            )
        t.add_column("state")
        for h in heads:
            t.add_column(escape(h), justify="right")  # "T[crank]" is not rich markup
        for i in range(res.n):
            state = (
                "ok"
                if res.assembled[i] and not res.singular[i]
                else ("singular" if res.assembled[i] else "not assembled")
            )
            t.add_row(*[_fmt(v[i]) for _, v in inputs], state, *[_fmt(v[i]) for v in values])
        console.print(t)

    table(
        f"{m.name or 'mechanism'}: joint positions [{lu}]",
        [f"{j}.{c}" for j in moving for c in "xy"],
        [f(res.point(j)) for j in moving for f in (np.real, np.imag)],
    )
    table(
        f"joint velocities [{lu}/s]",
        [f"{j}.v{c}" for j in moving for c in "xy"],
        [f(res.velocity(j)) for j in moving for f in (np.real, np.imag)],
    )
    table(
        f"joint accelerations [{lu}/s²]",
        [f"{j}.a{c}" for j in moving for c in "xy"],
        [f(res.acceleration(j)) for j in moving for f in (np.real, np.imag)],
    )
    links = [ln.name for ln in m.links if ln.name != "ground"]
    table(
        f"links: angle [{au}], ω [rad/s], α [rad/s²]",
        [f"{ln}.{c}" for ln in links for c in ("angle", "ω", "α")],
        [d[ln] for ln in links for d in (res.link_angle, res.link_omega, res.link_alpha)],
    )
    if res.forces is not None:
        heads, vals = zip(*res.forces.columns(compact=True), strict=True)
        table(
            "bearing loads |F| [N] (joint:by>on), driver torques T [N·m], forces F [N], input power [W]",
            list(heads),
            list(vals),
        )


def _console(out: Path | None) -> tuple[Console, io.StringIO | None]:
    if out is None:
        return Console(width=max(Console().width, 200) if not sys.stdout.isatty() else None), None
    buf = io.StringIO()
    return Console(file=buf, width=400, no_color=True, force_terminal=False), buf


# ---------------------------------------------------------------------- commands
FileArg = Annotated[Path, typer.Argument(help="Mechanism file (YAML or JSON).", show_default=False)]
OutOpt = Annotated[Path | None, typer.Option("-o", "--output", help="Write to this file instead of stdout.")]


@app.command("analyze")
def analyze_cmd(
    file: FileArg,
    angles: Annotated[
        list[str] | None, typer.Option("--angles", help="START:STOP:STEP, or NAME=START:STOP:STEP per driver.")
    ] = None,
    at: Annotated[list[str] | None, typer.Option("--at", help="V1,V2,..., or NAME=V1,V2,... per driver.")] = None,
    speed: Annotated[
        list[str] | None, typer.Option("--speed", help="Input speed (rad/s; length/s for a slider), or NAME=W.")
    ] = None,
    acceleration: Annotated[
        list[str] | None, typer.Option("--acceleration", help="Input acceleration, or NAME=A.")
    ] = None,
    fmt: Annotated[Fmt, typer.Option("--format", help="Output format.")] = Fmt.table,
    output: OutOpt = None,
    method: Annotated[
        Method,
        typer.Option(
            "--method",
            help="natural: triangulation in joint coordinates (any "
            "mechanism); vector-loop: link angles by iteration (four-bars, "
            "Stephenson six-bars).",
        ),
    ] = Method.natural,
    static: Annotated[
        bool,
        typer.Option(
            "--static", help="Zero input speed and acceleration: the driver torque that balances gravity and the loads."
        ),
    ] = False,
) -> None:
    """Positions, velocities and accelerations (and forces) over the input sweep."""
    mech = load(file)
    if static and (speed or acceleration):
        raise InputError("--static: do not give --speed or --acceleration with it")
    res = analyze(
        mech,
        _inputs(mech, at, angles),
        speed=_rates(mech, speed, "--speed"),
        acceleration=_rates(mech, acceleration, "--acceleration"),
        method=method.value,
        static=static,
    )
    if fmt is Fmt.json:
        _emit(json.dumps(res.to_dict(), allow_nan=False) + "\n", output)
    elif fmt is Fmt.csv:
        _emit(result_csv(res), output)
    else:
        console, buf = _console(output)
        result_table(res, console)
        if buf is not None:
            _emit(buf.getvalue(), output)


@app.command("modes")
def modes_cmd(
    file: FileArg,
    at: Annotated[list[str], typer.Option("--at", help="The input value, or NAME=V per driver.")],
    mirrors: Annotated[bool, typer.Option("--mirrors", help="Also flip each link of three or more joints.")] = False,
    fmt: Annotated[ModeFmt, typer.Option("--format", help="Output format.")] = ModeFmt.table,
    output: OutOpt = None,
) -> None:
    """Every assembly mode at one input value, with its joint positions."""
    from .analysis import modes
    from .positions import pose_inputs

    mech = load(file)
    given = _by_driver(mech, at, "--at", _numbers)
    q = pose_inputs(mech)[:, 0].copy()
    inp = {}
    for i, d in enumerate(mech.drivers):
        if d.name not in given:
            if len(mech.drivers) > 1:
                raise InputError(f"--at: give a value for every driver ({', '.join(x.name for x in mech.drivers)})")
            continue
        if len(given[d.name]) != 1:
            raise InputError(f"--at: one value per driver for modes, got {len(given[d.name])} for '{d.name}'")
        inp[d.name] = given[d.name][0]
        q[i] = given[d.name][0] * (mech.angle_to_rad if d.kind == "angle" else 1.0)
    data = modes(mech, q, mirrors)
    doc = {"format": "linkagekit-modes/1", "input": inp, "distinct": data["distinct"], "modes": data["modes"]}
    if fmt is ModeFmt.json:
        _emit(json.dumps(doc, allow_nan=False) + "\n", output)
        return
    console, buf = _console(output)
    t = Table(
        title=f"{mech.name or 'mechanism'}: assembly modes at " + ", ".join(f"{k} = {v:g}" for k, v in inp.items()),
        title_justify="left",
        header_style="bold",
    )
    t.add_column("#", justify="right")
    t.add_column("signs")
    if mirrors:
        t.add_column("mirrors")
    t.add_column("assembled")
    moving = [j for j in mech.joint_names if j not in mech.link("ground").joints]
    for j in moving:
        t.add_column(f"{j} [{mech.length_unit}]", justify="right")
    for i, mo in enumerate(doc["modes"]):
        row = [str(i), " ".join(f"{k}{'+' if v > 0 else '-'}" for k, v in mo["signs"].items())]
        if mirrors:
            row.append(" ".join(f"{k}{'+' if v > 0 else '-'}" for k, v in mo["mirrors"].items()))
        state = "yes" if mo["assembled"] else "no"
        if mo.get("reference"):
            state += " (pose)"
        if "same_as" in mo:
            state += f" = #{mo['same_as']}"
        row.append(state)
        row += [
            "—" if mo["joints"][j] is None else f"({mo['joints'][j][0]:.6g}, {mo['joints'][j][1]:.6g})" for j in moving
        ]
        t.add_row(*row)
    console.print(t)
    console.print(f"{data['distinct']} distinct assembled configuration(s) of {len(doc['modes'])}.")
    if buf is not None:
        _emit(buf.getvalue(), output)


@app.command("check")
def check_cmd(
    file: FileArg,
    fmt: Annotated[ModeFmt, typer.Option("--format", help="Output format.")] = ModeFmt.table,
    output: OutOpt = None,
) -> None:
    """Validate a file; print degrees of freedom, the solve plan and where it assembles."""
    from .analysis import check

    mech = load(file)
    rep = check(mech)
    if fmt is ModeFmt.json:
        _emit(json.dumps(rep, allow_nan=False) + "\n", output)
        return
    console, buf = _console(output)
    au = mech.angle_unit
    console.print(
        f"[bold]{mech.name or file}[/bold]: valid; {rep['dof']} degree(s) of freedom, "
        f"driven by {', '.join(rep['drivers'])}; solved in closed form."
    )
    console.print("[bold]Solve plan[/bold]")
    for line in rep["plan"]:
        console.print("  " + line)
    if rep["signs"]:
        console.print(
            "[bold]Assembly mode of the reference pose[/bold]: "
            + ", ".join(f"{j} {'+1' if s['sign'] > 0 else '-1'}" for j, s in rep["signs"].items())
        )
    for name, rng in rep["input_ranges"].items():
        d = mech.drivers[[x.name for x in mech.drivers].index(name)]
        unit = au if d.kind == "angle" else mech.length_unit
        text = ", ".join(f"[{a:.6f}, {b:.6f}]" for a, b in rng) if rng else "nowhere"
        console.print(f"[bold]Assembles[/bold] for {name} in {text} {unit}")
    if "grashof" in rep:
        console.print(f"[bold]Four-bar loop[/bold] {'-'.join(rep['fourbar']['joints'])}: {rep['grashof_detail']}")
    if "transmission_angle" in rep:
        ta = rep["transmission_angle"]
        console.print(f"[bold]Transmission angle[/bold]: min {ta['min']:.4f}°, max {ta['max']:.4f}°")
    if buf is not None:
        _emit(buf.getvalue(), output)


# ---------------------------------------------------------------------- entry point
def main(argv: list[str] | None = None) -> int:
    """Run the command line; return (and exit with) its status."""
    args = sys.argv[1:] if argv is None else argv
    try:
        rv = app(args=args, prog_name="linkagekit", standalone_mode=False)
        code = rv if isinstance(rv, int) else 0
    except LinkageError as exc:
        print(f"linkagekit: error: {exc}", file=sys.stderr)
        code = exc.exit_code
    except (typer.Abort, KeyboardInterrupt):
        print("linkagekit: aborted", file=sys.stderr)
        code = 1
    except Exception as exc:  # noqa: BLE001 - the promise is: never a traceback
        exit_code = getattr(exc, "exit_code", None)
        if hasattr(exc, "format_message") and isinstance(exit_code, int):
            # a usage error of the command-line parser: bad option, missing argument, bad choice
            msg = " ".join(exc.format_message().split())
            if not msg:  # `linkagekit` alone: the parser has printed the help
                pass
            else:
                print(f"linkagekit: error: {msg}", file=sys.stderr)
            code = exit_code
        else:
            print(f"linkagekit: internal error: {type(exc).__name__}: {exc}", file=sys.stderr)
            code = 1
    if argv is None:
        sys.exit(code)
    return code


if __name__ == "__main__":  # pragma: no cover
    main()
