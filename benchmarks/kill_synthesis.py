"""A synthesis killed again and again resumes to the uninterrupted result; a killed worker is survived.

Usage::

    PYTHONPATH=src python benchmarks/kill_synthesis.py [KILLS] [SEED]

1. An uninterrupted ``linkagekit synthesize`` of nine points of ``examples/seed000_fourbar.yaml``
   (three searches, no time limit) writes the reference file.
2. The same command with ``--checkpoint`` is started ``KILLS`` times (default 15), each time
   SIGKILLed after a random delay, then run to its end. Its file must equal the reference byte
   for byte. Each kill's loss is measured: the time between the checkpoint's last write and the
   kill, against the longest step (a generation, or one polished candidate) between two writes.
3. The command with ``--workers 2``: one pool process is SIGKILLed mid-run; the run must end with
   status 0 and the reference's file.
4. The command on a Dask ``LocalCluster`` (two worker processes): one worker is killed mid-run;
   the same is asked (skipped when ``distributed`` is not installed).

Exits non-zero on any failure; prints the numbers.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
COMMAND = ["synthesize", "t.csv", "--units", "cm", "--restarts", "3", "--generations", "60", "--seconds", "100000"]
COMMAND += ["--seed", "5", "--goal", "0"]


def cli(args: list[str], cwd: Path, **kw: object) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MPLBACKEND": "Agg"}
    return subprocess.Popen(  # type: ignore[call-overload, no-any-return]
        [sys.executable, "-m", "linkagekit.cli", *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


def header(path: Path) -> dict | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            return json.loads(str(z["header"]))
    except (OSError, ValueError, KeyError, EOFError):
        return None


def position(h: dict | None) -> tuple[int, ...]:
    """Where a checkpoint is: (searches done, generation, candidates polished, deep polishes, finished)."""
    if h is None:
        return (-1,)
    polished = h["polish"]["count"] if h.get("polish") else 0
    deep = sum(bool(d.get("deep")) for d in h["done"])
    return (h["restart"], h["generation"], polished, deep, h["stopped_by"] is not None)


def write_targets(d: Path) -> None:
    sys.path.insert(0, str(ROOT / "src"))
    import linkagekit as lk

    P = lk.analyze(lk.load(ROOT / "examples" / "seed000_fourbar.yaml"), {"crank": np.arange(0.0, 360.0, 40.0)})
    xy = P.xy("P")
    (d / "t.csv").write_text("x,y\n" + "".join(f"{float(x)!r},{float(y)!r}\n" for x, y in xy))


def run_to_end(args: list[str], d: Path, timeout: float = 1800) -> tuple[int, str, float]:
    t0 = time.monotonic()
    p = cli(args, d)
    _, err = p.communicate(timeout=timeout)
    return p.returncode, err, time.monotonic() - t0


def killed_runs(d: Path, kills: int, rng: random.Random, span: float) -> dict:
    """``kills`` runs SIGKILLed at random, then one to the end; the steps between checkpoint writes watched."""
    ck = d / "ck.npz"
    args = [*COMMAND, "-o", "killed.yaml", "--checkpoint", "ck.npz"]
    ages, steps, positions = [], [], []
    attempts = 0
    while len(ages) < kills:
        attempts += 1
        if attempts > 3 * kills:
            raise SystemExit(f"only {len(ages)} kills in {attempts} attempts: the run keeps ending first")
        p = cli(args, d)
        delay = rng.uniform(0.5, max(1.0, span / 5))  # 15 kills spread over about one run
        t_end = time.monotonic() + delay
        last_mtime = None
        while time.monotonic() < t_end and p.poll() is None:
            try:
                m = ck.stat().st_mtime
            except FileNotFoundError:
                m = None
            if m is not None and last_mtime is not None and m != last_mtime:
                steps.append(m - last_mtime)
            last_mtime = m
            time.sleep(0.002)
        if p.poll() is not None:  # it ended before its kill: the kills are spread too thin
            if p.returncode != 0:
                raise SystemExit(f"a run failed (status {p.returncode}): {p.stderr.read()}")
            raise SystemExit("the run ended before all its kills; use more kills or a longer run")
        p.send_signal(signal.SIGKILL)
        killed_at = time.time()
        p.communicate()
        ages.append(killed_at - ck.stat().st_mtime if ck.exists() else float("nan"))
        positions.append(position(header(ck)))
    code, err, _ = run_to_end(args, d)
    if code != 0:
        raise SystemExit(f"the resumed run failed ({code}): {err}")
    return {"ages": ages, "steps": steps, "positions": positions}


def children(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout
    return [int(x) for x in out.split()]


def pool_kill(d: Path) -> tuple[int, str]:
    """``--workers 2`` with one pool process SIGKILLed once its first checkpoint is written."""
    ck = d / "pool.npz"
    p = cli([*COMMAND, "-o", "pool.yaml", "--workers", "2", "--checkpoint", ck.name], d)
    deadline = time.monotonic() + 300
    while header(ck) is None and p.poll() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    time.sleep(0.5)
    victims = children(p.pid)
    if not victims:
        raise SystemExit("no pool process found to kill")
    os.kill(victims[0], signal.SIGKILL)
    _, err = p.communicate(timeout=1800)
    return p.returncode, err


def dask_kill(d: Path) -> tuple[int, str] | None:
    """The run on a Dask LocalCluster of two worker processes, one of them killed mid-run."""
    try:
        from distributed import LocalCluster
    except ImportError:
        return None
    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=50
    ) as cluster:
        ck = d / "dask.npz"
        args = [*COMMAND, "-o", "dask.yaml", "--scheduler", cluster.scheduler_address, "--checkpoint", ck.name]
        p = cli(args, d)
        deadline = time.monotonic() + 300
        while header(ck) is None and p.poll() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)
        pid = next(iter(cluster.workers.values())).process.process.pid  # the worker under its nanny
        os.kill(pid, signal.SIGKILL)
        _, err = p.communicate(timeout=1800)
    return p.returncode, err


def main() -> int:
    kills = int(sys.argv[1]) if len(sys.argv) > 1 else 15
    rng = random.Random(int(sys.argv[2]) if len(sys.argv) > 2 else 0)
    failures = []
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        write_targets(d)
        code, err, seconds = run_to_end([*COMMAND, "-o", "ref.yaml"], d)
        if code != 0:
            raise SystemExit(f"the reference run failed: {err}")
        reference = (d / "ref.yaml").read_bytes()
        print(f"reference run: {seconds:.1f} s")

        t0 = time.monotonic()
        got = killed_runs(d, kills, rng, seconds)
        same = (d / "killed.yaml").read_bytes() == reference
        print(f"{kills} kills at random, then to the end: {time.monotonic() - t0:.1f} s; same file: {same}")
        print("  checkpoint at each kill (searches, generation, polished, deep, finished):", got["positions"])
        ages, steps = np.array(got["ages"]), np.array(got["steps"])
        longest = float(steps.max()) if len(steps) else float("nan")
        print(
            f"  work lost per kill (time since the last checkpoint write): median {np.nanmedian(ages):.3f} s, "
            f"max {np.nanmax(ages):.3f} s; steps between writes: median {np.median(steps):.3f} s, "
            f"longest {longest:.3f} s ({len(steps)} seen)"
        )
        if not same:
            failures.append("the killed and resumed run's file differs from the uninterrupted run's")
        if np.nanmax(ages) > longest + 0.05:  # a kill lost more than one step (a generation or one polish)
            failures.append(f"a kill lost {np.nanmax(ages):.3f} s of work, more than the longest step {longest:.3f} s")
        monotone = all(a <= b for a, b in zip(got["positions"], got["positions"][1:], strict=False))
        if not monotone:
            failures.append("a resumed run went back behind its checkpoint")

        code, err = pool_kill(d)
        pool_same = code == 0 and (d / "pool.yaml").read_bytes() == reference
        print(f"a pool process killed: status {code}, same file: {pool_same}, stderr: {err.strip()[-200:]!r}")
        if not pool_same or "internal error" in err:
            failures.append(f"a killed pool process: status {code}, {err.strip()[-300:]}")

        dask = dask_kill(d)
        if dask is None:
            print("Dask: not installed, skipped")
        else:
            code, err = dask
            dask_same = code == 0 and (d / "dask.yaml").read_bytes() == reference
            print(f"a Dask worker killed: status {code}, same file: {dask_same}, stderr: {err.strip()[-200:]!r}")
            if not dask_same or "internal error" in err:
                failures.append(f"a killed Dask worker: status {code}, {err.strip()[-300:]}")
    for f in failures:
        print("FAIL:", f)
    print("PASS" if not failures else f"{len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
