import os

os.environ.setdefault("MPLBACKEND", "Agg")
import sys
from pathlib import Path

import pytest
from hypothesis import settings

sys.path.insert(0, str(Path(__file__).parent))
ROOT = Path(__file__).resolve().parents[1]

# Property tests draw the same examples on every run, so a run's verdict depends on the code
# only: a CI run is never red by the luck of the draw. HYPOTHESIS_PROFILE=explore draws new
# examples each run (for looking for bugs; a failure prints its seed to add as an explicit case).
settings.register_profile("suite", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "suite"))


@pytest.fixture
def examples() -> Path:
    return ROOT / "examples"


CHROMIUM = "/usr/bin/chromium"  # Debian's chromium; Playwright's own browser download cannot work here
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-quic",
]


@pytest.fixture(scope="module")
def browser():
    """Debian's headless Chromium through Playwright, one per test module.

    Without /usr/bin/chromium or playwright the browser tests FAIL (``.ci/run`` installs
    chromium); they are skipped only when LINKAGEKIT_NO_BROWSER=1.
    """
    if os.environ.get("LINKAGEKIT_NO_BROWSER") == "1":
        pytest.skip("LINKAGEKIT_NO_BROWSER=1: browser tests not run")
    if not Path(CHROMIUM).exists():
        pytest.fail(
            f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium) to run the "
            "browser tests, or set LINKAGEKIT_NO_BROWSER=1 to skip them",
            pytrace=False,
        )
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.fail(
            "the python package playwright is missing (pip install playwright; the browser is "
            f"{CHROMIUM}, from Debian's chromium), or set LINKAGEKIT_NO_BROWSER=1",
            pytrace=False,
        )
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


#: the test files that take longest (seconds on 2 cores), handed out first so that the two workers of ``pytest -n 2
#: --dist loadfile`` end together; with pytest-xdist's own order (most tests first) ``test_code_shape.py``, whose
#: cold mypy alone takes half a minute, came last and one worker idled meanwhile
FIRST = (
    "test_code_shape.py",
    "test_group.py",
    "test_report_browser.py",
    "test_editor_browser.py",
    "test_group_modes.py",
    "test_synthesis_cli.py",
    "test_editor.py",
    "test_branch.py",
)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Longest files first (see ``FIRST``); the rest in collection order."""
    items.sort(key=lambda item: FIRST.index(item.path.name) if item.path.name in FIRST else len(FIRST))
