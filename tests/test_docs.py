"""The user's documentation: its examples run, and nothing it points to lies outside the repository.

* every ```yaml block of docs/mechanism-files.md is a whole mechanism file: `lk.load` reads it, or,
  when its first line is `# refused: MESSAGE`, refuses it with MESSAGE (a LinkageError, one line);
* no user-facing file (README, benchmarks/README, docs/, examples/, the package's source: help, messages,
  docstrings) names a path outside the repository (`../shared`, the authors' machines' absolute paths) or
  the authors' tracker ("issue 26", "the shared benchmark directory"), every
  relative Markdown link resolves to a file of the repository, and every backticked repository
  path (`docs/...`, `examples/...`) exists.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import linkagekit as lk
from linkagekit.errors import LinkageError

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "mechanism-files.md"
BLOCK = re.compile(r"^```yaml\n(.*?)^```", re.S | re.M)
REFUSED = "# refused: "


def yaml_blocks() -> list[str]:
    return BLOCK.findall(REFERENCE.read_text(encoding="utf-8"))


def test_the_reference_has_an_example_of_every_key():
    text = "\n".join(yaml_blocks())
    keys = [
        "format:", "name:", "units:", "joints:", "links:", "ground:", "lengths:", "drivers:", "pivot:", "toward:",
        "angles:", "speed:", "acceleration:", "sliders:", "on:", "through:", "direction:", "slider:",
        "displacements:", "cylinder:", "stroke:", "mass:", "cg:", "inertia:", "gravity:", "loads:", "force:",
        "torque:", "at:",
    ]  # fmt: skip
    assert [k for k in keys if k not in text] == []
    assert len(yaml_blocks()) >= 10


@pytest.mark.parametrize("index", range(len(yaml_blocks())))
def test_every_yaml_example_loads_or_is_refused_as_documented(tmp_path, index):
    block = yaml_blocks()[index]
    path = tmp_path / "example.yaml"
    path.write_text(block, encoding="utf-8")
    first = block.splitlines()[0]
    if first.startswith(REFUSED):
        with pytest.raises(LinkageError) as info:
            lk.load(path)
        message = str(info.value)
        assert first[len(REFUSED) :] in message and "\n" not in message, message
    else:
        mech = lk.load(path)
        assert lk.check(mech).dof == len(mech.drivers)
        res = lk.analyze(mech, rates=False)
        assert res.assembled.any(), block  # each example moves


def user_facing_files() -> list[Path]:
    files = [ROOT / "README.md", ROOT / "benchmarks" / "README.md"]
    files += sorted(p for p in (ROOT / "docs").rglob("*") if p.is_file() and p.suffix in (".md", ".py"))
    files += sorted(p for p in (ROOT / "examples").rglob("*") if p.is_file())
    files += sorted(p for p in (ROOT / "src").rglob("*") if p.suffix in (".py", ".js", ".html", ".css"))
    return files


#: what points outside a clone: the workspace this was written in, and absolute home/work paths
OUTSIDE = re.compile(
    r"\.\./shared|\bshared/(seeds|spec|design)\b|mechanism-format\.md|/work/|/home/|/root/"
    r"|\bissues? \d+|\bissue-\d+|shared benchmark"  # the tracker and workspace this was written in
)


def test_nothing_a_user_reads_points_outside_the_repository():
    bad = []
    for path in user_facing_files():
        for n, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            if OUTSIDE.search(line):
                bad.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert bad == []


def test_the_checker_finds_a_pointer_outside():
    assert OUTSIDE.search("The contract is `../shared/spec/mechanism-format.md`.")
    assert OUTSIDE.search("# (shared/seeds/000_b5466792cd19a3fb.txt)")
    assert not OUTSIDE.search("a joint shared by two links; see docs/method.md")
    assert OUTSIDE.search("Then issue 29's goals: the triad positions")
    assert OUTSIDE.search("read from the shared benchmark directory, not copied here")


LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")
REPO_PATH = re.compile(r"`((?:docs|examples|tests|src|benchmarks)/[\w./-]+\.\w+)`")


def test_every_relative_link_and_repository_path_exists():
    missing = []
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        text = path.read_text(encoding="utf-8")
        for target in LINK.findall(text):
            if re.match(r"[a-z]+:", target):
                continue  # a URL
            resolved = (path.parent / target).resolve()
            if not resolved.is_relative_to(ROOT) or not resolved.exists():
                missing.append(f"{path.relative_to(ROOT)}: ({target})")
        for target in REPO_PATH.findall(text):
            if not (ROOT / target).exists():
                missing.append(f"{path.relative_to(ROOT)}: `{target}`")
    assert missing == []
