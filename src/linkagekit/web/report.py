"""The report page: one self-contained HTML file of a solved sweep or a simulated motion (docs/commands.md, `report`).

The page holds the scene (:mod:`linkagekit.viz.scene`) as JSON, the small SVG viewer
(``viewer.js``, inlined), its style, the text of ``check`` and the mechanism file.  It
loads nothing from anywhere: no CDN, no font, no image file.  The viewer only draws what
the scene holds, so every number on the page comes from the Python solver.

>>> import linkagekit as lk
>>> from linkagekit.web.report import report_html
>>> page = report_html(lk.analyze(lk.load("examples/seed000_fourbar.yaml")))
>>> page.startswith("<!DOCTYPE html>"), 'data-role="input"' in page, "http" in page.split("<body")[0]
(True, True, False)
"""

from __future__ import annotations

import html
import json
import os
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .. import __version__
from ..catalogue import input_units
from ..errors import InputError
from ..files import readable, write_atomic
from ..model import Mechanism
from ..result import Result
from ..viz.scene import Scene, build_scene

#: the most samples a page holds (each sample costs about 1 kB for a four-bar with rates)
MAX_REPORT_SAMPLES = 10_000

STYLE = """
:root { --ink: #1b1b1b; --muted: #666; --line: #d8d8d8; --accent: #e6007e; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color: var(--ink);
       margin: 0 auto; max-width: 1400px; padding: 12px 20px 40px; }
h1 { font-size: 20px; margin: 6px 0 2px; }
h2 { font-size: 16px; margin: 22px 0 6px; border-bottom: 1px solid var(--line); padding-bottom: 3px; }
.sub { color: var(--muted); margin: 0 0 10px; }
.top { display: grid; grid-template-columns: minmax(320px, 1fr) minmax(320px, 1fr); gap: 18px; align-items: start; }
@media (max-width: 900px) { .top { grid-template-columns: 1fr; } }
svg[data-role=mechanism] { width: 100%; height: auto; border: 1px solid var(--line); border-radius: 4px;
                           background: #fff; display: block; }
svg text.label { fill: #333; }
.controls { display: grid; grid-template-columns: auto 1fr auto; gap: 6px 10px; align-items: center; margin: 8px 0; }
.controls input[type=range] { width: 100%; }
.controls output { font-variant-numeric: tabular-nums; min-width: 12em; }
button { font: inherit; padding: 3px 12px; border: 1px solid #888; border-radius: 4px; background: #f6f6f6;
         cursor: pointer; }
button:hover { background: #eee; }
[data-role=message] { color: #b00000; min-height: 1.4em; }
#lk-plots figure { margin: 0 0 6px; }
#lk-plots svg { width: 100%; height: auto; display: block; }
pre { background: #f7f7f7; border: 1px solid var(--line); border-radius: 4px; padding: 8px 10px; overflow: auto;
      font: 12px/1.4 ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; max-height: 420px; }
.gaps { color: #8a4b00; }
footer { color: var(--muted); font-size: 12px; margin-top: 24px; }
.editor h3 { font-size: 14px; margin: 8px 0 4px; }
.editor .hint { color: var(--muted); font-size: 12px; }
.editor-grid { display: grid; grid-template-columns: repeat(auto-fit, minmax(260px, 1fr)); gap: 12px; }
.editor table { border-collapse: collapse; font-size: 13px; }
.editor td { padding: 1px 6px; }
.editor input[type=number] { width: 9em; }
[data-role=status] { margin-left: 8px; color: var(--muted); }
[data-role=modes] button { margin: 2px; }
svg[data-role=mechanism] [data-joint] { cursor: grab; }
svg[data-role=mechanism].adding { cursor: crosshair; }
"""


def _viewer_js() -> str:
    return resources.files("linkagekit.web").joinpath("viewer.js").read_text(encoding="utf-8")


def _editor_panel(editor: dict[str, Any], file_name: str) -> str:
    """The editing controls of ``linkagekit edit`` (drawn by editor.js)."""
    esc = html.escape
    name = esc(editor.get("file", file_name))
    return f"""<section class="editor" data-role="editor" aria-label="editing">
<h2>Edit</h2>
<p class="toolbar">
<button type="button" data-action="undo" disabled>Undo</button>
<button type="button" data-action="redo" disabled>Redo</button>
<button type="button" data-action="save">Save</button>
<button type="button" data-action="add-link" title="click joints or empty places, then Finish">Add link</button>
<button type="button" data-action="finish-link" hidden>Finish link</button>
<button type="button" data-action="ground" title="click a joint to fix it to the ground, or to free it">Ground</button>
<span data-role="status" aria-live="polite"></span>
</p>
<p class="hint">Drag any joint: the mechanism takes the drawn configuration, with that joint moved, as its
reference pose (its dimensions change, as if the file had been edited). Saving writes {name} in one step and keeps
the previous version as {name}.bak; the file's comments stay where their lines are.
To add a dyad, add a link from a joint to an empty place, a second link from that new joint to another empty place,
and mark the last one ground: the steps in between are kept as a dashed draft until the mechanism solves.</p>
<div class="editor-grid">
<div><h3>Assembly modes at this input</h3><div data-role="modes"></div></div>
<div><h3>Numbers</h3><table data-role="numbers"></table></div>
<div><h3>Driver</h3><div data-role="driver"></div></div>
</div>
</section>"""


def _editor_scripts(editor: dict[str, Any]) -> str:
    js = resources.files("linkagekit.web").joinpath("editor.js").read_text(encoding="utf-8")
    return f'<script type="application/json" id="lk-editor">{_script_json(editor)}</script>\n<script>{js}</script>'


def _script_json(doc: Any) -> str:
    """JSON safe inside a <script> element (no '</', no HTML comment openers)."""
    text = json.dumps(doc, allow_nan=False, separators=(",", ":"))
    return text.replace("<", "\\u003c").replace(">", "\\u003e").replace("&", "\\u0026")


def report_html(
    res: Result,
    source: str | None = None,
    checks_text: str | None = None,
    title: str | None = None,
    editor: dict[str, Any] | None = None,
    start: int | None = None,
) -> str:
    """The report page of one design's sweep, as a string.

    Parameters
    ----------
    res : Result
        From :func:`linkagekit.analyze` (one design), or a simulated motion from
        :func:`linkagekit.simulate`: its plots run along time, the slider and Play step
        through its times, and where it stopped at a toggle is said.
    source : str, optional
        The mechanism file's text, shown on the page (default: the mechanism written as YAML).
    checks_text : str, optional
        The text of ``linkagekit check`` (default: computed here).
    editor : dict, optional
        The editor's state (``linkagekit edit``): adds the editing controls and ``editor.js``.
    start : int, optional
        The sample shown first (default: the first that assembles).
    """
    _check_arguments(res, source, checks_text, title)
    sc = build_scene(res)
    mech = res.mechanism
    source = _yaml(mech) if source is None else source
    checks_text = _checks_text(mech) if checks_text is None else checks_text
    esc = html.escape
    title = title or mech.name or "mechanism"
    if start is None:
        ok = np.flatnonzero(sc.assembled)
        start = int(ok[0]) if ok.size else 0
    file_name = "" if mech.source.startswith("<") else Path(mech.source).name
    unit_text = f"lengths in {esc(mech.length_unit)}, angles in {esc(mech.angle_unit)}"
    return f"""<!DOCTYPE html>
<html lang="en">
{_head(title, bool(editor))}
<body data-name="{esc(Path(file_name).stem or "linkage")}">
<h1>{esc(title)}</h1>
<p class="sub">{esc(file_name)}{" · " if file_name else ""}{unit_text} · {_samples_text(sc)} ·
linkagekit {esc(__version__)}</p>
{_top(sc, start, editor, file_name)}
<h2>Checks</h2>
<pre data-role="checks">{esc(checks_text)}</pre>
<h2>Mechanism file</h2>
<pre data-role="source">{esc(source)}</pre>
<footer>Every number on this page was computed by the linkagekit solver (Python) and stored in the page;
the page only draws them. The coupler curves are in magenta, the other joint paths dashed grey.</footer>
<script type="application/json" id="lk-scene">{_script_json(sc.to_dict())}</script>
<script>{_viewer_js()}</script>
{_editor_scripts(editor) if editor else ""}
</body>
</html>
"""


def _check_arguments(res: Any, source: Any, checks_text: Any, title: Any) -> None:
    """Raise an InputError unless *res* is one design's Result a page can hold and the texts are text."""
    if not isinstance(res, Result):
        raise InputError(f"expected a linkagekit Result (lk.analyze(...)), got {type(res).__name__}")
    if res.n_samples > MAX_REPORT_SAMPLES:
        raise InputError(
            f"{res.n_samples} samples, more than a report page holds ({MAX_REPORT_SAMPLES}): report a coarser sweep"
        )
    for what, value in (("source", source), ("checks_text", checks_text), ("title", title)):
        if value is not None and not isinstance(value, str):
            raise InputError(f"{what}: expected text, got {type(value).__name__}")


def _yaml(mech: Mechanism) -> str:
    """The mechanism written as YAML (the page's file when none is given)."""
    import yaml

    return yaml.safe_dump(mech.to_dict(), sort_keys=False, allow_unicode=True)


def _checks_text(mech: Mechanism) -> str:
    """The text of ``linkagekit check`` for *mech*."""
    from ..checks import check, check_text

    return check_text(check(mech).to_dict(), input_units(mech), mech.name or "mechanism")


def _top(sc: Scene, start: int, editor: dict[str, Any] | None, file_name: str) -> str:
    """The mechanism, its sliders and buttons (and the editor's panel), and the place of the plots."""
    return f"""<div class="top">
<section>
<svg data-role="mechanism" xmlns="http://www.w3.org/2000/svg" role="img" aria-label="the mechanism"></svg>
<div class="controls">
{_input_controls(sc, start)}
</div>
<p><button type="button" data-action="play">Play</button>
<button type="button" data-action="csv">Download CSV</button></p>
<p data-role="message" aria-live="polite"></p>
<p class="gaps" data-role="gaps"></p>
{_stopped_text(sc)}
{_editor_panel(editor, file_name) if editor else ""}
</section>
<section id="lk-plots" aria-label="plots"></section>
</div>"""


def _head(title: str, editor: bool) -> str:
    """The page's ``<head>``: its title, its style, and (for the editor) no favicon request."""
    esc = html.escape
    return f"""<head>
<meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<meta name="generator" content="linkagekit {esc(__version__)}">
<title>{esc(title)} · linkagekit {"editor" if editor else "report"}</title>
{'<link rel="icon" href="data:,">' if editor else ""}
<style>{STYLE}</style>
</head>"""


def _samples_text(sc: Scene) -> str:
    """How many samples, and for a simulated motion over which times."""
    count = f'<span data-role="sample-count">{sc.n}</span> samples'  # the editor's page updates it
    if not sc.timed or sc.n == 0:
        return count
    t = sc.x
    return f"simulated motion, t = {t[0]:.6g} to {t[-1]:.6g} {html.escape(sc.x_unit)}, {count}"


def _stopped_text(sc: Scene) -> str:
    """Where a simulated motion stopped at a toggle (nothing otherwise)."""
    return f'<p class="gaps" data-role="stopped">{html.escape(sc.stopped)}</p>' if sc.stopped else ""


def _input_controls(sc: Scene, start: int) -> str:
    """A slider over the samples for each driver, at sample *start*, with the output that shows its input.

    A simulated motion also shows the time of the sample (``data-role="time-value"``).
    """
    esc = html.escape
    time = '<span>time</span><span></span><output data-role="time-value"></output>' if sc.timed else ""
    return time + "".join(
        f'<label for="lk-in-{esc(d)}">{esc(d)}</label>'
        f'<input type="range" id="lk-in-{esc(d)}" data-role="input" data-driver="{esc(d)}" '
        f'min="0" max="{sc.n - 1}" step="1" value="{start}">'
        f'<output data-role="input-value" data-driver="{esc(d)}"></output>'
        for d in sc.drivers
    )


def write_report(
    res: Result,
    path: str | Path,
    source: str | None = None,
    checks_text: str | None = None,
    title: str | None = None,
) -> Path:
    """Write :func:`report_html` to ``path`` atomically (a temporary file, then renamed)."""
    if not isinstance(path, str | os.PathLike):
        raise InputError(f"path: expected a file name ending in .html, got {type(path).__name__}")
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise InputError(f"{path}: the report must end in .html")
    text = readable(report_html(res, source=source, checks_text=checks_text, title=title))
    write_atomic(path, text.encode("utf-8"))
    return path
