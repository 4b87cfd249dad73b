"""The import layers of the package, and what ``import linkagekit`` costs.

Each module may import only modules of its own layer or below (docs/design.md), and no two
modules import each other (directly or through others).  Function-level imports count too:
every ``import`` statement in the file is read with :mod:`ast`, nothing is executed.
"""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "linkagekit"

#: lower layers first; a module may import its own layer and the layers before it
LAYERS = [
    {"errors", "units", "geometry", "options", "threads"},
    {"schema", "model", "files"},
    {"steps", "group", "plan", "params", "catalogue"},
    {"positions", "rates", "branch", "forces", "vectorloop", "groupmodes"},
    {"result", "api", "checks"},
    {"dynamics"},
    {"flywheel"},
    {"viz.scene"},
    {"viz.draw", "viz.animate", "web.report", "web.editor"},
    {
        "synthesis.base",
        "synthesis.targets",
        "synthesis.space",
        "synthesis.objective",
        "synthesis.cmaes",
        "synthesis.function",
        "synthesis.motion",
        "synthesis.burmester",
        "synthesis.front",
        "synthesis.topologies",
        "synthesis.tracer",
        "synthesis.descriptors",
        "synthesis.tolerance",
    },
    {"synthesis.distribute"},
    {"synthesis.optimize"},
    {"synthesis.atlas", "synthesis.autosave"},
    {"synthesis.function_run"},
    {"synthesis.run"},
    {"synthesis.auto"},
    {"cli"},
    {"__main__"},
]
RANK = {m: i for i, layer in enumerate(LAYERS) for m in layer}


def module_name(path: Path) -> str:
    """``viz.scene`` for src/linkagekit/viz/scene.py."""
    return ".".join(path.relative_to(SRC).with_suffix("").parts)


def _resolve(package: list[str], level: int, module: str | None, names: list[str]) -> set[str]:
    """The linkagekit modules named by ``from <level dots><module> import <names>`` in ``package``."""
    base = package[: len(package) - (level - 1)] if level else []
    parts = base + (module.split(".") if module else [])
    out = set()
    dotted = ".".join(parts)
    for name in names:  # from .viz import draw: a submodule
        if f"{dotted}.{name}".strip(".") in RANK:
            out.add(f"{dotted}.{name}".strip("."))
    if dotted in RANK:
        out.add(dotted)
    elif parts and parts[0] in RANK:
        out.add(parts[0])
    return out


def imports_of(path: Path) -> set[str]:
    """The linkagekit modules a source file imports, anywhere in it."""
    package = list(path.relative_to(SRC).parts[:-1]) if path.is_relative_to(SRC) else []
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            names = [a.name for a in node.names]
            if node.level >= 1:
                out |= _resolve(package, node.level, node.module, names)
            elif node.module and (node.module == "linkagekit" or node.module.startswith("linkagekit.")):
                out |= _resolve([], 0, node.module.partition(".")[2] or None, names)
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("linkagekit."):
                    out |= _resolve([], 0, a.name.partition(".")[2], [])
    return out


FILES = {module_name(p): p for p in SRC.rglob("*.py") if p.name != "__init__.py"}
MODULES = sorted(FILES)


def test_every_module_has_a_layer():
    assert set(MODULES) == set(RANK), set(MODULES) ^ set(RANK)


@pytest.mark.parametrize("module", MODULES)
def test_imports_point_down(module):
    for target in imports_of(FILES[module]):
        assert RANK[target] <= RANK[module], f"{module} (layer {RANK[module]}) imports {target} (layer {RANK[target]})"


def test_no_import_cycles():
    graph = {m: imports_of(FILES[m]) - {m} for m in MODULES}

    def reach(start):
        seen, todo = set(), list(graph[start])
        while todo:
            m = todo.pop()
            if m not in seen:
                seen.add(m)
                todo.extend(graph[m])
        return seen

    for m in MODULES:
        assert m not in reach(m), (
            f"{m} imports itself through {sorted(reach(m) & {x for x in MODULES if m in graph[x]})}"
        )


def test_the_layer_test_can_fail(tmp_path):
    bad = tmp_path / "positions.py"
    bad.write_text("def f():\n    from .api import analyze\n")
    assert "api" in imports_of(bad) and RANK["api"] > RANK["positions"]


HEAVY = ("matplotlib", "scipy", "pandas", "dask", "typer", "rich", "pydantic", "yaml")


def loaded_after(code):
    probe = f"import sys\n{code}\nprint(' '.join(m for m in {HEAVY + ('numpy',)!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True, cwd=SRC.parents[1])
    return set(out.stdout.split())


def test_import_linkagekit_is_light():
    assert loaded_after("import linkagekit") == set()


def test_reading_and_solving_loads_only_what_it_needs():
    mech = "lk.load('examples/seed000_fourbar.yaml')"
    loaded = loaded_after(f"import linkagekit as lk\nlk.analyze({mech})\nlk.check({mech})")
    assert loaded == {"numpy", "yaml", "pydantic"}, loaded


def test_subpackage_imports_are_resolved():
    assert imports_of(FILES["web.report"]) >= {"viz.scene", "result"}
    assert imports_of(FILES["viz.draw"]) >= {"viz.scene", "result"}
    assert {"viz.draw", "viz.animate", "web.report"} <= imports_of(FILES["cli"])


def test_the_command_line_module_imports_nothing_heavy():
    assert loaded_after("import linkagekit.cli") == set()


def test_python_m_linkagekit_runs_the_command_line():
    # a review: `python -m linkagekit` said "No module named linkagekit.__main__"; importing the package stays light
    import os

    env = {**os.environ, "PYTHONPATH": str(SRC.parent)}
    done = subprocess.run([sys.executable, "-m", "linkagekit", "--version"], capture_output=True, text=True, env=env)
    assert (done.returncode, done.stdout, done.stderr) == (0, "linkagekit 0.1.0\n", "")
    done = subprocess.run([sys.executable, "-m", "linkagekit", "check", ""], capture_output=True, text=True, env=env)
    assert (done.returncode, done.stderr) == (2, "linkagekit: error: the file path is empty: give the file to read\n")
