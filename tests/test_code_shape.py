"""The shape of the code: short functions that read like the derivation.

No function or method in ``src/`` is longer than 60 lines or has a McCabe complexity above
15.  The complexity is ruff's C901 (``pyproject.toml`` sets its limit, so an editor's ruff
shows the same); the length is read off the syntax tree here.  ``mypy --strict`` passes on
``src/`` (``pyproject.toml`` sets ``strict``), so the annotations users' type checkers read
(``py.typed``) are checked.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "linkagekit"
MAX_LINES = 60


def long_functions(tree: ast.AST, limit: int = MAX_LINES) -> list[tuple[int, str, int]]:
    """``(line, name, length)`` of every function or method (nested ones too) longer than ``limit`` lines."""
    out = []
    for fn in ast.walk(tree):
        if isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            n = (fn.end_lineno or fn.lineno) - fn.lineno + 1
            if n > limit:
                out.append((fn.lineno, fn.name, n))
    return out


def test_no_function_over_60_lines():
    long = [
        f"{path.relative_to(SRC)}:{line} {name} ({n} lines)"
        for path in sorted(SRC.rglob("*.py"))
        for line, name, n in long_functions(ast.parse(path.read_text(encoding="utf-8")))
    ]
    assert not long, "cut these to named steps: " + "; ".join(long)


def test_the_length_counts_decorators_out_and_nested_functions_in():
    body = "\n".join(f"        x{i} = {i}" for i in range(60))
    tree = ast.parse(f"@property\ndef short():\n    def inner():\n{body}\n    return inner\n")
    assert [(name, n) for _, name, n in long_functions(tree)] == [("short", 63), ("inner", 61)]


def test_no_function_over_complexity_15():
    proc = subprocess.run(
        [sys.executable, "-m", "ruff", "check", "--no-cache", "--select", "C901", "--output-format", "concise", "src"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr


def test_the_complexity_limit_is_15(tmp_path):
    """ruff reads the limit from pyproject.toml: a function of complexity 16 fails, 15 passes."""
    branches = lambda n: "\n".join(f"    if a == {i}:\n        return {i}" for i in range(n))  # noqa: E731
    for n, code in ((14, 0), (15, 1)):  # n ifs: complexity n + 1
        src = tmp_path / "probe.py"
        src.write_text(f"def f(a):\n{branches(n)}\n    return -1\n")
        proc = subprocess.run(
            [
                sys.executable,
                "-m",
                "ruff",
                "check",
                "--no-cache",
                "--select",
                "C901",
                "--config",
                str(ROOT / "pyproject.toml"),
                str(src),
            ],
            capture_output=True,
            text=True,
        )
        assert proc.returncode == code, (n, proc.stdout, proc.stderr)


def test_mypy_strict_passes_on_src(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--strict", "--cache-dir", str(tmp_path), "src"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-1000:]
