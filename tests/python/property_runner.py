"""Runs one group of property_cases.py in a child process and checks its counts (issue 17).

A crash (the child dies from a signal) or a hang (the child outlives its time budget) fails
the test with the call that was running; otherwise the child's counts of silent NaN, unclear
messages, wrong error types and modified inputs must all be 0.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
GROUP_TIMEOUT_S = float(os.environ.get("PROPERTY_GROUP_TIMEOUT_S", "240"))


def _files() -> list:
    """The test folder's entries, without caches Python itself writes."""
    return sorted(p.name for p in HERE.iterdir() if p.name != "__pycache__" and not p.name.startswith("."))


def run_group(group: str) -> dict:
    before = _files()
    with tempfile.TemporaryDirectory() as tmp:
        status = Path(tmp) / "current_call.txt"
        env = dict(os.environ, PROPERTY_STATUS_FILE=str(status), PYTHONHASHSEED="0")
        # The child runs in its own empty folder: a writer given a bad relative path such as "x"
        # writes there, never into the test folder (a stray tests/python/x was once committed).
        work = Path(tmp) / "cwd"
        work.mkdir()
        try:
            proc = subprocess.run([sys.executable, str(HERE / "property_cases.py"), group],
                                  capture_output=True, text=True, timeout=GROUP_TIMEOUT_S, env=env,
                                  cwd=work)
        except subprocess.TimeoutExpired:
            last = status.read_text() if status.exists() else "?"
            raise AssertionError(f"{group}: hang: no result in {GROUP_TIMEOUT_S} s; last call {last}")
        last = status.read_text() if status.exists() else "?"
        assert proc.returncode >= 0, (f"{group}: crash (signal {-proc.returncode}) during {last}\n"
                                      f"{proc.stderr[-2000:]}")
        lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
        assert lines, f"{group}: no result (exit {proc.returncode}); last call {last}\n{proc.stderr[-2000:]}"
        counts = json.loads(lines[-1])
    if os.environ.get("PROPERTY_COUNTS_FILE"):  # one JSON line per group, for the totals in docs
        with open(os.environ["PROPERTY_COUNTS_FILE"], "a") as f:
            f.write(json.dumps({"group": group, **{k: v for k, v in counts.items() if k != "problems"}}) + "\n")
    after = _files()
    assert after == before, f"{group}: the probe wrote into {HERE}: {sorted(set(after) - set(before))}"
    print(f"{group}: {counts['cases']} cases, {counts['calls']} calls, {counts['returned']} returned, "
          f"{counts['rejected']} rejected")
    problems = "\n".join(counts["problems"])
    for kind in ("hangs", "silent_nan", "unclear", "wrong_type", "mutated"):
        assert counts[kind] == 0, f"{group}: {counts[kind]} {kind}\n{problems}"
    assert proc.returncode == 0, problems
    return counts
