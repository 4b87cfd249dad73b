"""The long runs of tests that the suite runs small: the same checks, at the size they had before the suite was
cut to five minutes (linkagekit issue 22).

Each check is a function of the test module (the suite calls it with a small budget or a few random cases);
here it runs with the search as shipped or with the original number of random cases. Every check prints what it
reached and its CPU and wall seconds; a check whose assertion fails prints one ``FAILED name: ...`` line, and
the script ends with exit status 1 if any did.

    python benchmarks/bench_long_tests.py              # every check (about 4 CPU-minutes)
    python benchmarks/bench_long_tests.py fourbar-1 triads   # the checks whose names start so
    python benchmarks/bench_long_tests.py marked   # the tests marked ``long`` (pytest -m long)
"""

from __future__ import annotations

import resource
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _recovery_checks() -> dict[str, Callable[[], str]]:
    import test_synthesis as ts

    def fourbar(which: int) -> Callable[[], str]:
        # the test before the suite was cut: seed 0, restarts until the goal (1e-5 of the diagonal), no time limit
        return lambda: f"max error {100 * ts.check_fourbar_recovery(which, seed=0):.4f} % of the diagonal"

    def sixbar(topology: str) -> Callable[[], str]:
        # the test before: seed 0, 8 restarts (differential evolution and CMA-ES in turn) on 2 workers
        return lambda: (
            f"max error {100 * ts.check_sixbar_recovery(topology, seed=0, restarts=8, workers=2):.4f} % of the diagonal"
        )

    return {
        **{f"fourbar-{w}": fourbar(w) for w in (0, 1, 2)},
        **{t: sixbar(t) for t in ("watt2", "stephenson3")},
    }


def _random_cases(check: Callable[..., None], strategies: dict, n: int) -> Callable[[], str]:
    """``check`` over ``n`` random cases drawn by hypothesis (a fresh draw every run, as in the suite)."""
    from hypothesis import HealthCheck, given, settings

    def run() -> str:
        seen: list[dict] = []

        def one(**case) -> None:
            seen.append(case)
            check(**case)

        settings(max_examples=n, deadline=None, suppress_health_check=list(HealthCheck), database=None)(
            given(**strategies)(one)
        )()
        return f"{len(seen)} random cases"

    return run


def _group_checks(n_linkages: int = 12, n_triads: int = 15) -> dict[str, Callable[[], str]]:
    import test_group as tg

    return {
        "forced-numerical": _random_cases(tg.check_forced_numerical_random, tg.RANDOM_LINKAGES, n_linkages),
        "triads": _random_cases(tg.check_random_triad, tg.RANDOM_TRIADS, n_triads),
    }


def _marked() -> str:
    """The tests marked ``long`` (searches the suite leaves out to stay under five minutes), by pytest on 2 workers."""
    import subprocess

    cmd = [sys.executable, "-m", "pytest", "-q", "-n", "2", "-m", "long", "-p", "no:cacheprovider"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    last = (proc.stdout.strip().splitlines() or [""])[-1]
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-1000:]
    return last


def checks() -> dict[str, Callable[[], str]]:
    """Every long check by name, in the order they run."""
    return {**_recovery_checks(), **_group_checks(), "marked": _marked}


def cpu_seconds() -> float:
    """User + system time of this process and of its finished children (the search's worker processes)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def main(only: list[str] | None = None, table: dict[str, Callable[[], str]] | None = None) -> list[str]:
    """Run the checks (those whose names start with one of ``only``); returns the names of the failed ones."""
    table = checks() if table is None else table
    names = [n for n in table if not only or any(n.startswith(o) for o in only)]
    if not names:
        raise SystemExit(f"no check named {only}; the checks: {', '.join(table)}")
    failed = []
    for name in names:
        cpu, wall = cpu_seconds(), time.monotonic()
        try:
            got = table[name]()
        except Exception as exc:  # noqa: BLE001 - an assertion, or an error of the code under test: both fail
            failed.append(name)
            first = (str(exc).strip().splitlines() or [""])[0]
            print(f"FAILED {name}: {type(exc).__name__}: {first[:300]}", flush=True)
            continue
        print(f"{name:18s} {got}  ({cpu_seconds() - cpu:.1f} CPU-s, {time.monotonic() - wall:.1f} s)", flush=True)
    held = f"{len(names) - len(failed)} of {len(names)} checks held"
    print(f"FAILED: {held}; failed: {', '.join(failed)}" if failed else f"passed: {held}")
    return failed


if __name__ == "__main__":
    sys.exit(1 if main(sys.argv[1:]) else 0)
