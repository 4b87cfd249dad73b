"""Settings every test run shares: the tests under ``tests/`` and the doctests under ``src/`` alike.

Here at the root (not in ``tests/conftest.py``) because the doctests of ``src/linkagekit`` run
synthesis too, and a conftest applies only below its own directory.
"""

import os

import pytest

#: entries of the four-bar atlas the tests build (synthesis/atlas.py): one small chunk, well under a second
TEST_ATLAS_SIZE = "2048"


@pytest.fixture(scope="session", autouse=True)
def _small_atlas(tmp_path_factory: pytest.TempPathFactory):
    """Every test builds and reads a tiny atlas in a temporary directory, never the user's cache.

    Set before any test of a session (of each worker) runs, so no synthesis test builds the
    full atlas; the command line run in a subprocess inherits it.
    """
    saved = {k: os.environ.get(k) for k in ("LINKAGEKIT_CACHE_DIR", "LINKAGEKIT_ATLAS_SIZE")}
    os.environ["LINKAGEKIT_CACHE_DIR"] = str(tmp_path_factory.mktemp("linkagekit-cache"))
    os.environ["LINKAGEKIT_ATLAS_SIZE"] = TEST_ATLAS_SIZE
    yield
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
