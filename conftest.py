"""Settings every test run shares: the tests under ``tests/`` and the doctests under ``src/`` alike.

Here at the root (not in ``tests/conftest.py``) because the doctests of ``src/linkagekit`` run
synthesis too, and a conftest applies only below its own directory.
"""

import os

# One BLAS thread per process: the run's parallelism is xdist's workers (and the synthesis tests' own worker
# processes). OpenBLAS's default, a thread per core in every process, spun idle threads against the other workers:
# the motion weights test took 10 s of CPU for 6 s of wall time, 6 s with one thread. Read when NumPy loads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # (the xdist workers start after it is set: they inherit it)

import pytest  # noqa: E402

#: entries of the four-bar atlas (synthesis/atlas.py) in the tests: none (it is off), unless a test sets a
#: small size itself (tests/test_atlas.py: 2048, one chunk built in a fraction of a second). Off, the other
#: synthesis tests search as they did before the atlas; on, its start cost ~0.2 CPU-s per run (measured: +5
#: CPU-s over test_synthesis*.py), which the suite's time budget has no room for.
TEST_ATLAS_SIZE = "0"


@pytest.fixture(scope="session", autouse=True)
def _small_atlas(tmp_path_factory: pytest.TempPathFactory):
    """No test builds the full atlas or writes to the user's cache: a temporary cache directory, no atlas.

    Set before any test of a session (of each worker) runs; the command line run in a
    subprocess inherits it.
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
