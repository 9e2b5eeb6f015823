"""The property harness's hang alarms: judged on CPU time, so that a call that waits for a core
on a loaded machine is not a hang, while a spinning call and a blocked call still are."""
import signal
import time

import pytest

import property_harness as ph


@pytest.fixture
def harness(monkeypatch):
    monkeypatch.setattr(ph, "CALL_TIMEOUT_S", 0.3)
    monkeypatch.setattr(ph, "WALL_FACTOR", 5.0)
    monkeypatch.setattr(ph, "TALLY", ph.Tally())
    old = {s: signal.signal(s, ph._alarm) for s in (signal.SIGALRM, signal.SIGPROF)}
    yield ph
    ph._stop_alarms()
    for s, h in old.items():
        signal.signal(s, h)


def _spin(x: float) -> float:
    end = time.process_time() + 30.0
    while time.process_time() < end:
        x = x * 1.0000001
    return x


def _wait(x: float) -> float:
    time.sleep(x)
    return x


def test_a_spinning_call_is_a_hang(harness):
    ph.call(ph.Case("spin", _spin, {"x": 1.0}), "x", 1.0)
    assert harness.TALLY.hangs == 1


def test_a_call_waiting_longer_than_the_cpu_limit_but_within_the_wall_limit_is_not_a_hang(harness):
    ph.call(ph.Case("wait", _wait, {"x": 0.5}), "x", 0.5)  # 0.5 s wall > 0.3 s, but no CPU
    assert harness.TALLY.hangs == 0 and harness.TALLY.returned == 1


def test_a_blocked_call_is_caught_by_the_wall_clock(harness):
    started = time.monotonic()
    ph.call(ph.Case("blocked", _wait, {"x": 10.0}), "x", 10.0)
    assert harness.TALLY.hangs == 1
    assert time.monotonic() - started < 5.0  # 5 x 0.3 s, not the 10 s of the call
