"""The output catalogue is the one description of every column, whatever the names.

Joints, links and drivers are named to confuse any reader that guesses a column's meaning
from its name (``boom:1``, ``T[x``, ``omega``, ``x``, ``crank.angle``, a name with a comma
and a quote): a cylinder-driven excavator and a slider-crank with masses (so they have
forces), and a four-bar without.  For each, every column's unit, group and owner must be
the catalogue's in the CSV, the JSON, the CLI tables, ``plot --quantity`` and the report
page, and the page's CSV must be ``analyze --format csv``, column for column.

Before the catalogue, the driver ``boom:1`` lost its "Driver forces" plot (``F[boom:1]``
was taken for a reaction) and the joint ``T[x`` made a "Driver torques" plot in N·m of a
mechanism without forces (its ``T[x.x`` started with ``T[``).
"""

from __future__ import annotations

import csv
import io
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import linkagekit as lk
from linkagekit import cli
from linkagekit.catalogue import Group, Owner, Section, UnitKind

COMMA = 'e,"1"'  # a joint name the CSV must quote

EXCAVATOR = {  # examples/excavator_boom.yaml, renamed
    "format": "linkagekit/1",
    "name": "confusing excavator",
    "units": {"length": "m", "angle": "deg"},
    "joints": {
        "x": [0.0, 0.0],
        "omega": [0.45, -0.75],
        "boom:1": [1.891, 1.169],
        "T[x": [4.3665, 3.6639],
        "crank.angle": [1.868, 2.2854],
        "S1": [4.4512, 4.3103],
        COMMA: [5.592, 1.0356],
    },
    "links": {
        "ground": ["x", "omega"],
        "crank.angle": {
            "joints": ["x", "T[x", "boom:1", "crank.angle"],
            "lengths": {"x-T[x": 5.7},
            "mass": 950.0,
            "cg": [2.1128, 1.8381],
            "inertia": 2600.0,
        },
        "omega": {
            "joints": ["T[x", "S1", COMMA],
            "mass": 480.0,
            "cg": [4.8736, 2.5763],
            "inertia": 340.0,
        },
    },
    "drivers": [
        {"cylinder": ["omega", "boom:1"], "name": "boom:1", "stroke": [1.8, 2.9],
         "lengths": {"start": 1.8, "stop": 2.9, "step": 0.022}, "speed": 0.1},
        {"cylinder": ["crank.angle", "S1"], "name": "x", "stroke": [2.5, 3.4],
         "lengths": {"start": 2.5, "stop": 3.4, "step": 0.018}, "speed": 0.1},
    ],
    "gravity": [0, -9.81],
}  # fmt: skip

SLIDER_CRANK = {  # examples/slider_crank.yaml, renamed: a torque, a slider's moment
    "format": "linkagekit/1",
    "name": "confusing slider-crank",
    "units": {"length": "m", "angle": "deg"},
    "joints": {"omega": [0, 0], "T[x": [0.03, 0.04], "x": [0.115, 0]},
    "links": {
        "ground": ["omega"],
        "boom:1": {"joints": ["omega", "T[x"], "mass": 0.5, "cg": [0.015, 0.02], "inertia": 1.0e-4},
        "crank.angle": {"joints": ["T[x", "x"], "mass": 0.3, "cg": [0.0725, 0.02], "inertia": 2.2e-4},
        "x": {"joints": ["x"], "mass": 0.4, "cg": [0.115, 0], "inertia": 1.0e-4},
    },
    "drivers": [
        {"link": "boom:1", "pivot": "omega", "toward": "T[x", "angles": {"start": 0, "stop": 360, "step": 10},
         "speed": 10},
    ],
    "sliders": [{"link": "x", "on": "ground", "through": "x", "direction": [1, 0]}],
    "gravity": [0, -9.81],
}  # fmt: skip

FOURBAR = {  # examples/seed000_fourbar.yaml, renamed, no masses: no forces
    "format": "linkagekit/1",
    "name": "confusing four-bar",
    "units": {"length": "cm", "angle": "deg"},
    "joints": {
        "x": [0, 0],
        "omega": [4, 1],
        "T[x": [2, 0],
        "crank.angle": [0.820550528229663, 4.85889894354067],
        "boom:1": [5.61820518364243, 3.45088267680359],
    },
    "links": {
        "ground": ["x", "omega"],
        "T[x": {"joints": ["x", "T[x"]},
        "x": {"joints": ["T[x", "crank.angle", "boom:1"]},
        "omega": {"joints": ["omega", "crank.angle"]},
    },
    "drivers": [{"link": "T[x", "pivot": "x", "toward": "T[x", "angles": {"start": 0, "stop": 360, "step": 5}}],
}

MECHANISMS = {"excavator": EXCAVATOR, "slider_crank": SLIDER_CRANK, "fourbar": FOURBAR}


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    out = tmp_path_factory.mktemp("confusing")
    paths = {}
    for name, doc in MECHANISMS.items():
        paths[name] = out / f"{name}.yaml"
        lk.save(lk.Mechanism.from_dict(doc), paths[name])
    return paths


def analysis(path: Path) -> Any:
    return lk.analyze(lk.load(path))


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = cli.main(argv)
    out, err = capsys.readouterr()
    return code, out, err


# ----------------------------------------------------------------------------- the catalogue itself
def test_the_catalogue_says_what_each_confusing_column_is(files):
    cat = analysis(files["excavator"]).catalogue
    q = cat["F[boom:1]"]
    assert (q.owner, q.owner_name, q.group, q.unit_symbol) == (Owner.DRIVER, "boom:1", Group.DRIVER_FORCES, "N")
    q = cat["input:boom:1"]
    assert (q.owner, q.owner_name, q.unit, q.unit_symbol) == (Owner.DRIVER, "boom:1", UnitKind.LENGTH, "m")
    q = cat["T[x.x"]
    assert (q.owner, q.owner_name, q.kind.component, q.unit_symbol) == (Owner.JOINT, "T[x", "x", "m")
    q = cat["crank.angle.angle"]
    assert (q.owner, q.owner_name, q.group, q.period) == (Owner.LINK, "crank.angle", Group.LINK_ANGLES, 360.0)
    q = cat["crank.angle.x"]  # the joint crank.angle, not the link's angle
    assert (q.owner, q.group, q.period) == (Owner.JOINT, Group.JOINT_POSITIONS, None)
    assert cat["|F|[T[x:crank.angle>omega]"].group is Group.BEARING_LOADS
    assert cat["F[T[x:crank.angle>omega].fx"].group is Group.REACTIONS
    assert not cat.of_group(Group.DRIVER_TORQUES)
    assert [q.name for q in cat.of_group(Group.DRIVER_FORCES)] == ["F[boom:1]", "F[x]"]

    four = analysis(files["fourbar"]).catalogue
    assert all(q.kind.needs.value != "forces" for q in four)
    assert not four.of_group(Group.DRIVER_TORQUES) and not four.of_group(Group.DRIVER_FORCES)
    assert four["T[x.y"].group is Group.JOINT_POSITIONS and four["T[x.y"].unit_symbol == "cm"
    assert four["input:T[x"].unit_symbol == "deg" and four["T[x.angle"].unit_symbol == "deg"

    slider = analysis(files["slider_crank"]).catalogue
    assert slider["T[boom:1]"].owner is Owner.DRIVER and slider["T[boom:1]"].unit_symbol == "N·m"
    moment = slider["F[x:ground>x].moment"]
    assert moment.owner is Owner.REACTION and moment.unit_symbol == "N·m" and moment.group is Group.REACTIONS


# ----------------------------------------------------------------------------- CSV and JSON
@pytest.mark.parametrize("name", list(MECHANISMS))
def test_csv_is_the_catalogue_table(files, name, capsys):
    res = analysis(files[name])
    code, out, _ = run(["analyze", str(files[name]), "--format", "csv"], capsys)
    assert code == 0
    rows = list(csv.reader(io.StringIO(out)))
    assert rows[0] == [q.name for q in res.catalogue.table] == list(res.columns())
    assert len(rows) == res.n_samples + 1
    cols = res.columns()
    for c, head in enumerate(rows[0]):
        want = np.asarray(cols[head])
        got = [r[c] for r in rows[1:]]
        if want.dtype == bool:
            assert got == ["true" if v else "false" for v in want], head
        else:
            assert got == [repr(float(v)) if np.isfinite(v) else "" for v in want], head


def _at(doc: Any, path: list[Any]) -> Any:
    for key in path:
        doc = doc[key]
    return doc


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_json_places_and_describes_every_quantity(files, name, capsys):
    res = analysis(files[name])
    code, out, _ = run(["analyze", str(files[name]), "--format", "json"], capsys)
    assert code == 0
    doc = json.loads(out)
    assert doc["quantities"] == [q.to_dict() for q in res.catalogue]
    cols = res.columns()
    for entry, q in zip(doc["quantities"], res.catalogue, strict=True):
        assert (entry["owner"], entry["owner_name"], entry["unit"], entry["group"]) == (
            q.owner.value,
            q.owner_name,
            q.unit_symbol,
            q.group.title,
        )
        if not q.kind.table:
            assert entry["path"] is None and q.name not in cols
            continue
        values = np.array([np.nan if v is None else v for v in _at(doc, entry["path"])], float)
        np.testing.assert_array_equal(values, np.asarray(cols[q.name], float), err_msg=q.name)
    if res.forces is not None:
        assert {r["joint"] for r in doc["reactions"]} <= set(res.mechanism.joint_names)


# ----------------------------------------------------------------------------- the CLI tables
HEADER = re.compile(r"^(?P<name>.*) \[(?P<unit>[^\[\]]*)\]$")


def _table_headers(text: str) -> list[str]:
    """Every header cell of the analyze tables (the line above each rule of dashes), split on two spaces."""
    lines = text.splitlines()
    heads = []
    for i, line in enumerate(lines[1:], 1):
        if line and set(line) <= {"-", " "}:
            heads += [h.strip() for h in re.split(r" {2,}", lines[i - 1].strip())]
    return heads


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_cli_tables_show_catalogue_units(files, name, capsys, monkeypatch):
    monkeypatch.setattr(cli, "terminal_width", lambda: 400)
    res = analysis(files[name])
    cat = res.catalogue
    code, out, _ = run(["analyze", str(files[name])], capsys)
    assert code == 0
    heads = set(_table_headers(out))
    inputs = {q.owner_name: q for q in cat if q.owner is Owner.DRIVER and q.kind.component == "input"}
    shown = {}
    for h in heads - {"state"}:
        m = HEADER.match(h)
        assert m, f"a header without a unit: {h!r}"
        shown[m["name"]] = m["unit"]
    for d, q in inputs.items():
        assert shown.pop(d) == q.unit_symbol
    want = {q.name: q.unit_symbol for section in Section for q in cat.in_section(section)}
    assert shown == want
    if name == "fourbar":
        assert "forces" not in out and "T[x.x" in shown and "T[x.x [cm]" in heads


# ----------------------------------------------------------------------------- plot --quantity
def _captured_plot(files, name, quantity, monkeypatch, tmp_path) -> Any:
    from linkagekit.viz import draw

    got = {}

    def keep(fig, path, ax=None):
        got["fig"] = fig
        return Path(path)

    monkeypatch.setattr(draw, "save_figure", keep)
    code = cli.main(["plot", str(files[name]), "-q", quantity, "-o", str(tmp_path / "q.png")])
    return code, got.get("fig")


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_plot_quantity_groups_are_the_catalogue_groups(files, name, monkeypatch, tmp_path, capsys):
    cat = analysis(files[name]).catalogue
    for group in (g for g in Group if g.plotted):
        series = [q.name for q in cat.of_group(group)]
        code, fig = _captured_plot(files, name, group.short, monkeypatch, tmp_path)
        if not series:
            assert code == 2 and fig is None, f"{name}: plot -q {group.short} drew a plot of no quantity"
            assert f"no {group.title.lower()}" in capsys.readouterr().err
            continue
        assert code == 0, capsys.readouterr().err
        (ax,) = fig.axes
        assert [ln.get_label() for ln in ax.get_lines()] == series, f"{name}: plot -q {group.short}"
        unit = cat.of_group(group)[0].unit_symbol
        assert ax.get_ylabel() == (f"{series[0]} [{unit}]" if len(series) == 1 else unit)
    for q in (q for q in cat if q.owner in (Owner.DRIVER, Owner.REACTION) or q.name.startswith("T[x")):
        code, fig = _captured_plot(files, name, q.name, monkeypatch, tmp_path)  # one column by its name
        assert code == 0 and fig.axes[0].get_ylabel() == f"{q.name} [{q.unit_symbol}]", q.name


def test_the_two_bugs(files, monkeypatch, tmp_path, capsys):
    """The driver boom:1 has its Driver forces plot; the joint T[x makes no Driver torques plot."""
    code, fig = _captured_plot(files, "excavator", "forces", monkeypatch, tmp_path)
    assert code == 0 and [ln.get_label() for ln in fig.axes[0].get_lines()] == ["F[boom:1]", "F[x]"]
    code, fig = _captured_plot(files, "fourbar", "torques", monkeypatch, tmp_path)
    assert code == 2 and fig is None
    from linkagekit.viz.scene import build_scene

    titles = [p.title for p in build_scene(analysis(files["fourbar"])).plots]
    assert "Driver torques" not in titles and "Driver forces" not in titles
    plots = {p.title: p for p in build_scene(analysis(files["excavator"])).plots}
    assert plots["Driver forces"].series == ("F[boom:1]", "F[x]") and plots["Driver forces"].unit == "N"


# ----------------------------------------------------------------------------- the report page
def _report(files, name, tmp_path) -> Path:
    out = tmp_path / f"{name}.html"
    assert cli.main(["report", str(files[name]), "-o", str(out)]) == 0
    return out


def _embedded_scene(page_text: str) -> dict[str, Any]:
    m = re.search(r'<script type="application/json" id="lk-scene">(.*?)</script>', page_text, re.S)
    assert m
    return json.loads(m.group(1).replace("<\\/", "</"))


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_report_plots_are_the_catalogue_groups(files, name, tmp_path):
    cat = analysis(files[name]).catalogue
    scene = _embedded_scene(_report(files, name, tmp_path).read_text())
    assert scene["quantities"] == [q.to_dict() for q in cat]
    want = [
        {"title": g.title, "unit": qs[0].unit_symbol, "series": [q.name for q in qs], "period": qs[0].period}
        for g in Group
        if g.plotted and (qs := cat.of_group(g))
    ]
    assert scene["plots"] == want
    assert scene["units_of"] == {q.name: q.unit_symbol for q in cat}


PAGE_PLOTS = """
() => {
  const plots = [...document.querySelectorAll('[data-role="plot"]')].map(p => ({
    title: p.getAttribute('data-title'),
    legend: [...p.querySelectorAll('[data-legend]')].map(e => e.getAttribute('data-legend'))}));
  return {plots: plots};
}
"""


@pytest.mark.parametrize("name", list(MECHANISMS))
def test_page_csv_is_analyze_csv_and_plots_are_the_catalogue(browser, files, name, tmp_path, capsys):
    cat = analysis(files[name]).catalogue
    page_path = _report(files, name, tmp_path)
    code, want, _ = run(["analyze", str(files[name]), "--format", "csv"], capsys)
    assert code == 0
    ctx = browser.new_context()
    try:
        page = ctx.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.goto(page_path.as_uri(), wait_until="load")
        page.wait_for_function("() => window.linkagekit && window.linkagekit.scene")
        with page.expect_download() as dl:
            page.locator('[data-action="csv"]').click()
        downloaded = Path(dl.value.path()).read_text()
        got = page.evaluate(PAGE_PLOTS)
    finally:
        ctx.close()
    assert not errors, errors
    page_rows = list(csv.reader(io.StringIO(downloaded)))
    cli_rows = list(csv.reader(io.StringIO(want)))
    assert page_rows[0] == cli_rows[0], "the page's CSV columns are not analyze's"
    assert page_rows == cli_rows
    assert downloaded == want
    plots = [{"title": g.title, "legend": [q.name for q in qs]} for g in Group if g.plotted and (qs := cat.of_group(g))]
    assert got["plots"] == plots


MIXED = """
format: linkagekit/1
name: mixed drivers
units: {length: m, angle: deg}
joints: {O: [0, 0], A: [0.1, 0], E: [0.3, 0.15], B: [0.5, 0]}
links:
  ground: [O]
  crank: {joints: [O, A], mass: 0.5, cg: [0.05, 0], inertia: 0.001}
  rod1: {joints: [A, E], mass: 0.3, cg: [0.2, 0.075], inertia: 0.001}
  rod2: {joints: [E, B], mass: 0.3, cg: [0.4, 0.075], inertia: 0.001}
  block: {joints: [B], mass: 0.4, cg: [0.5, 0], inertia: 0.001}
sliders: [{link: block, on: ground, through: B, direction: [1, 0]}]
drivers:
  - {slider: 0, displacements: {start: -0.02, stop: 0.02, step: 0.01}, speed: 0.1}
  - {link: crank, pivot: O, toward: A, angles: {start: 0, stop: 40, step: 10}, speed: 2}
gravity: [0, -9.81]
"""


def test_driver_efforts_come_torques_first_whatever_the_drivers_order(tmp_path):
    """Every ``T[...]`` column before every ``F[...]`` one (as before the catalogue), even when a
    slider driver is listed before a crank: CSV, pandas and the forces table keep their order."""
    path = tmp_path / "mixed.yaml"
    path.write_text(MIXED, encoding="utf-8")
    res = lk.analyze(lk.load(path))
    efforts = [q.name for q in res.catalogue.table if q.kind.owner is Owner.DRIVER and q.kind.component != "input"]
    assert efforts == ["T[crank]", "F[block]"]
    assert [k for k in res.columns() if k in efforts] == efforts
    assert set(res.forces.driver_torque) == {"crank"} and set(res.forces.driver_force) == {"block"}


def test_two_quantities_with_one_column_name_are_a_file_error(tmp_path):
    """A joint ``input:a`` and a crank link (so driver) ``a.x`` would both give ``input:a.x``: one line, exit 2."""
    mech = lk.load(Path(__file__).resolve().parents[1] / "examples" / "seed000_fourbar.yaml")
    doc = mech.to_dict()
    doc["joints"] = {("input:a" if j == "P" else j): p for j, p in doc["joints"].items()}
    doc["links"] = {
        ("a.x" if name == "crank" else name): [
            ("input:a" if j == "P" else j) for j in (v["joints"] if isinstance(v, dict) else v)
        ]
        for name, v in doc["links"].items()
    }
    for d in doc["drivers"]:
        d["link"] = "a.x"
    clash = lk.Mechanism.from_dict(doc, source="clash.yaml")
    with pytest.raises(
        lk.MechanismFileError,
        match=r"clash.yaml: the driver 'a.x' and the joint 'input:a' .* column 'input:a.x': rename one",
    ):
        lk.analyze(clash)
    path = tmp_path / "clash.yaml"
    lk.save(clash, path)
    proc = subprocess.run(
        [sys.executable, "-m", "linkagekit.cli", "analyze", str(path)], capture_output=True, text=True
    )
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1 and "rename one" in proc.stderr
