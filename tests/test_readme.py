"""The README's Python example runs as written (in a scratch directory with the examples beside it)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_readme_python_example_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "the README has a Python example"
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    monkeypatch.chdir(tmp_path)
    scope: dict = {}
    for block in blocks:  # every line as written, the synthesis given 1 s of its 10 (its answer is not asserted)
        exec(compile(block.replace("seconds=10,", "seconds=1,"), "README.md", "exec"), scope)  # noqa: S102 - our own documentation
    batch, lk = scope["batch"], scope["lk"]
    assert batch.xy("P").shape == (10_000, 360, 2)
    assert lk.load("copy.yaml") == scope["mech"]
    assert lk.load("design7.yaml") == batch.mechanism_of(7)


def test_ci_runs_exactly_the_readme_test_command():
    """`.ci/run` ends with the README's test command, which runs on two processes by pytest-xdist (in the test
    extra)."""
    import tomllib

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    command = next(b.strip() for b in re.findall(r"```bash\n(.*?)```", text, re.S) if '".[test]"' in b)
    assert (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1] == command
    assert command == 'pip install -e ".[test]" && pytest -n 2'
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]["optional-dependencies"]
    assert any(r.startswith("pytest-xdist") for r in extras["test"]) and any(
        r.startswith("pytest-xdist") for r in extras["dev"]
    )
