"""Property-based probing of indoorloc's public entry points (issue 17).

Each probe starts from a valid call of an entry point and lets hypothesis replace one argument
with something a user might pass by mistake: NaN, +-inf, 1e300, 1e-300, 0, -1, 2**31, 2**64,
empty, wrong-shaped, complex, boolean, string, non-contiguous or transposed arrays, or the valid
array with one entry spoiled. Every call must either

  * return finite output (documented NaN outputs are listed per case), or
  * raise ValueError / TypeError / IndexError whose message names the argument replaced
    (or, for an Options object, the field replaced),

and must not modify its inputs, crash, hang (a per-call alarm) or allocate without bound.

This file is run as a script in a child process by the tests/python/test_properties_*.py
tests (``python property_harness.py <group>``), so that a crash of the extension module fails
one test instead of killing pytest. It prints one JSON line of counts and the first problems
found; the exit status is 0 when no problem was found. Hypothesis runs derandomized with a
fixed number of examples per case (``PROPERTY_EXAMPLES``, default 40) and no example database.
"""

from __future__ import annotations

import copy
import json
import math
import os
import signal
import sys
import tempfile
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Optional, Sequence

import numpy as np
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

EXAMPLES = int(os.environ.get("PROPERTY_EXAMPLES", "40"))
# A hang is judged on the process's CPU time (user + system, every thread), not on the wall
# clock: on a loaded machine (CI runners, parallel jobs) a bounded call can wait for a core far
# longer than it computes. A call blocked without computing (a deadlock) is caught by the wall
# clock at WALL_FACTOR times the limit.
CALL_TIMEOUT_S = float(os.environ.get("PROPERTY_CALL_TIMEOUT_S", "20"))
WALL_FACTOR = 10.0
# Long work by design is stopped sooner: that it unwinds cleanly on the alarm is what counts.
LONG_CALL_TIMEOUT_S = float(os.environ.get("PROPERTY_LONG_CALL_TIMEOUT_S", "3"))
STATUS_FILE = os.environ.get("PROPERTY_STATUS_FILE")
# Development aids: how many problems to report, and only the cases whose name contains one of
# the comma-separated PROPERTY_ONLY strings (unset in CI: every case runs).
MAX_PROBLEMS = int(os.environ.get("PROPERTY_MAX_PROBLEMS", "40"))
ONLY = [x for x in os.environ.get("PROPERTY_ONLY", "").split(",") if x]

settings.register_profile(
    "ci", max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
    phases=[Phase.explicit, Phase.generate], print_blob=False,
    suppress_health_check=list(HealthCheck))
settings.load_profile("ci")

ALLOWED = (ValueError, TypeError, IndexError)

# Scalars a user may pass by mistake (the valid value is kept out by the strategy's filter).
BAD_SCALARS: List[Any] = [
    math.nan, math.inf, -math.inf, 0.0, -1.0, -7, 1e300, -1e300, 1e-300, 2**31, 2**31 - 1,
    2**63, 2**64 - 1, -(2**31) - 1, 2.5, True, None, "x", complex(1.0, 1.0), [], [1.0, 2.0],
]


class CallTimeout(BaseException):
    """A call ran longer than CALL_TIMEOUT_S (a hang, or an unbounded loop)."""


def _arm(limit_s: float, cpu: bool = True) -> None:
    """Starts a call's alarms: `limit_s` of CPU time and WALL_FACTOR x `limit_s` of wall clock
    (cpu=True), or `limit_s` of wall clock alone (cpu=False: long work that must unwind soon)."""
    if cpu:
        signal.setitimer(signal.ITIMER_PROF, limit_s)
        signal.setitimer(signal.ITIMER_REAL, WALL_FACTOR * limit_s)
    else:
        signal.setitimer(signal.ITIMER_REAL, limit_s)


def _stop_alarms() -> None:
    signal.setitimer(signal.ITIMER_PROF, 0)
    signal.setitimer(signal.ITIMER_REAL, 0)


def _disarm() -> None:
    """Stops the call's alarms; an alarm that fires while the call's own error is being handled
    (the call answered just in time) is not a hang."""
    try:
        _stop_alarms()
    except CallTimeout:
        pass


def _alarm(signum: int, frame: Any) -> None:
    raise CallTimeout()


@dataclass
class Case:
    """One entry point with a valid call; `vary` names the arguments to spoil (default all)."""

    name: str
    fn: Callable[..., Any]
    kwargs: Dict[str, Any]
    vary: Optional[Sequence[str]] = None
    nan_outputs: Sequence[str] = ()  # output keys documented to hold NaN (e.g. "no value yet")
    # arg -> (factory of a valid Options object, fields to spoil one at a time)
    options_fields: Dict[str, Any] = field(default_factory=dict)
    minus_inf_ok: bool = False  # -inf is a documented output (the log of a zero weight)
    # Long work by design (Monte Carlo, solvers): a call stopped by the alarm must unwind
    # cleanly (it is interruptible); it then counts as interrupted, not as a hang.
    long_work_ok: bool = False
    # Solvers: a RuntimeError reporting a numerical failure of an ill-conditioned problem
    # (CONVENTIONS: std::runtime_error -> RuntimeError) is counted, not failed.
    solver: bool = False
    examples: Optional[int] = None  # fewer examples for slow entry points (solvers)


@dataclass
class Tally:
    cases: int = 0
    calls: int = 0
    returned: int = 0
    rejected: int = 0
    interrupted: int = 0  # long_work_ok calls stopped by the alarm (Ctrl-C path)
    numerical_failures: int = 0  # solver RuntimeErrors (not positive definite, singular)
    crashes: int = 0  # counted by the parent process
    hangs: int = 0
    silent_nan: int = 0
    unclear: int = 0
    wrong_type: int = 0
    mutated: int = 0
    problems: List[str] = field(default_factory=list)
    seconds: Dict[str, float] = field(default_factory=dict)  # per case: where the CI time goes

    def problem(self, kind: str, text: str) -> None:
        setattr(self, kind, getattr(self, kind) + 1)
        if len(self.problems) < MAX_PROBLEMS:
            self.problems.append(f"{kind}: {text}")


TALLY = Tally()


# ---------------------------------------------------------------------------------------------
# Strategies


def _spoil_array(valid: np.ndarray) -> st.SearchStrategy[Any]:
    """Arrays near the valid one: same shape with one bad entry, wrong shapes, odd dtypes."""
    bad_values = st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 1e-300, -1.0, 0.0])
    shape = valid.shape
    strategies: List[st.SearchStrategy[Any]] = []
    if valid.size:
        def one_entry(draw_index: int, value: float) -> np.ndarray:
            a = np.array(valid, dtype=np.float64, copy=True)
            a.flat[draw_index % a.size] = value
            return a
        strategies.append(st.builds(one_entry, st.integers(0, 10**6), bad_values))
        strategies.append(st.just(np.array(valid, dtype=np.complex128) + 1j))
        strategies.append(st.just(np.asarray(valid, dtype=np.float64)[::-1].copy()))
        if valid.ndim == 2:
            strategies.append(st.just(np.asfortranarray(valid)))  # layout only: must be accepted
            strategies.append(st.just(np.ascontiguousarray(np.asarray(valid).T)))
        strategies.append(st.just(np.asarray(valid).astype(np.float32)))
        strategies.append(st.just(np.asarray(valid).reshape(-1)))
        strategies.append(st.just(np.asarray(valid)[..., None]))
        strategies.append(st.just(np.full(shape, 1e300)))
        strategies.append(st.just(np.full(shape, -1e300)))
    strategies.append(st.just(np.zeros((0,) + tuple(shape[1:]))))
    strategies.append(st.just(np.zeros((0,))))
    strategies.append(st.just(np.array(["a"] * max(1, valid.size)).reshape(-1)))
    strategies.append(st.just(np.zeros(shape, dtype=bool)))
    strategies.append(st.builds(lambda n: np.full((n,) + tuple(shape[1:]), math.nan),
                                st.integers(0, 4)))
    strategies.append(st.sampled_from([None, 3.0, "x", [[1.0, 2.0], [3.0]]]))
    return st.one_of(strategies)


def _spoil_scalar(valid: Any) -> st.SearchStrategy[Any]:
    floats = st.floats(allow_nan=True, allow_infinity=True, width=64)
    ints = st.integers(min_value=-(2**65), max_value=2**65)
    return st.one_of(st.sampled_from(BAD_SCALARS), floats, ints).filter(
        lambda v: not (type(v) is type(valid) and _same(v, valid)))


def _same(a: Any, b: Any) -> bool:
    try:
        return bool(a == b)
    except Exception:
        return False


# ---------------------------------------------------------------------------------------------
# Checks


def _snapshot(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, (list, tuple, dict)):
        try:
            return copy.deepcopy(value)
        except Exception:  # holds objects that cannot be copied (bound C++ types): compare items
            return [_snapshot(v) for v in value] if isinstance(value, (list, tuple)) else None
    return None


def _unchanged(before: Any, after: Any) -> bool:
    if before is None:
        return True
    if isinstance(before, list) and not isinstance(after, list) and isinstance(after, (tuple,)):
        after = list(after)
    if isinstance(before, list) and isinstance(after, (list, tuple)) and any(
            b is None for b in before) and len(before) == len(after):
        return all(_unchanged(b, a) for b, a in zip(before, after))  # per item, from _snapshot's fallback
    if isinstance(before, np.ndarray):
        return (before.shape == after.shape and before.dtype == after.dtype
                and np.array_equal(before, after, equal_nan=before.dtype.kind in "fc"))
    try:
        return bool(before == after) or repr(before) == repr(after)
    except Exception:
        return repr(before) == repr(after)


def _non_finite(value: Any, nan_ok: Sequence[str], minus_inf_ok: bool = False,
                path: str = "") -> Optional[str]:
    """Where `value` (output) holds NaN or inf, or None (a typed result: its fields, to_dict())."""
    value = _as_dict(value)
    if isinstance(value, dict):
        for k, v in value.items():
            if k in nan_ok:
                continue
            bad = _non_finite(v, nan_ok, minus_inf_ok, f"{path}[{k!r}]")
            if bad:
                return bad
        return None
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            bad = _non_finite(v, nan_ok, minus_inf_ok, f"{path}[{i}]")
            if bad:
                return bad
        return None
    if isinstance(value, (np.ndarray, float, np.floating)):
        a = np.asarray(value)
        if a.dtype.kind in "fc" and a.size:
            ok = np.isfinite(a) | ((a == -np.inf) if minus_inf_ok else False)
            if not np.all(ok):
                return path or "output"
    return None


_MISMATCH = ("expected shape", "expected length", "one entry per", "for N = ", "K mismatch",
             "number of rows", "rows but", "is shorter than")


def _names(message: str, argument: str, fields: Sequence[str], others: Sequence[str] = ()) -> bool:
    """The message names the spoiled argument (or field), or it reports a mismatch between the
    spoiled argument and another one and names that other argument."""
    if "incompatible function arguments" in message or "incompatible constructor arguments" in message:
        return True  # pybind11's TypeError: prints the signature and the values passed
    keys = [argument] + list(fields)
    if any(k in message for k in keys):
        return True
    return any(m in message for m in _MISMATCH) and any(f"'{o}'" in message for o in others)


def _short(value: Any) -> str:
    if isinstance(value, np.ndarray):
        flat = value.reshape(-1)[:4]
        return f"array(shape={value.shape}, dtype={value.dtype}, head={flat.tolist()})"
    text = repr(value)
    return text if len(text) < 60 else text[:57] + "..."


def call(case: Case, argument: str, value: Any, fields: Sequence[str] = (), shown: Optional[str] = None) -> None:
    """Calls case.fn with `argument` replaced by `value` and records the outcome."""
    kwargs = dict(case.kwargs)
    kwargs[argument] = value
    before = {k: _snapshot(v) for k, v in kwargs.items()}
    label = f"{case.name}({argument}={shown or _short(value)})"
    if STATUS_FILE:  # the parent reports this line if the process dies
        with open(STATUS_FILE, "w") as f:
            f.write(label)
    TALLY.calls += 1
    limit = LONG_CALL_TIMEOUT_S if case.long_work_ok else CALL_TIMEOUT_S
    _arm(limit, cpu=not case.long_work_ok)
    started = time.monotonic()
    try:
        out = case.fn(**kwargs)
    except CallTimeout:
        # Interruptible means it unwound soon after the alarm, not when the work was done.
        if case.long_work_ok and time.monotonic() - started < limit + 5.0:
            TALLY.interrupted += 1
        else:
            TALLY.problem("hangs", f"{label}: no answer in {CALL_TIMEOUT_S} s of CPU "
                                   f"({time.monotonic() - started:.0f} s wall)")
        return
    except ALLOWED as exc:
        _disarm()
        TALLY.rejected += 1
        if not _names(str(exc), argument, fields, [k for k in kwargs if k != argument]):
            TALLY.problem("unclear", f"{label}: {type(exc).__name__}: {str(exc)[:200]}")
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:  # RuntimeError, OverflowError, MemoryError, ...
        _stop_alarms()
        if case.solver and type(exc) is RuntimeError and str(exc).startswith("indoorloc:"):
            TALLY.numerical_failures += 1
        else:
            TALLY.problem("wrong_type", f"{label}: {type(exc).__name__}: {str(exc)[:200]}")
    else:
        _stop_alarms()
        TALLY.returned += 1
        bad = _non_finite(out, case.nan_outputs, case.minus_inf_ok)
        if bad:
            TALLY.problem("silent_nan", f"{label}: non-finite {bad}")
    finally:
        _disarm()
    for k, v in kwargs.items():
        if not _unchanged(before[k], v):
            TALLY.problem("mutated", f"{label}: argument {k!r} was modified")


def probe(case: Case) -> None:
    """Runs the valid call once (must return finite output), then the spoiled calls."""
    if ONLY and not any(o in case.name for o in ONLY):
        return
    started = time.monotonic()
    try:
        _probe(case)
    finally:
        TALLY.seconds[case.name] = round(time.monotonic() - started, 2)


def _probe(case: Case) -> None:
    TALLY.cases += 1
    valid_out = None
    try:
        _arm(CALL_TIMEOUT_S)
        valid_out = case.fn(**case.kwargs)
    except BaseException as exc:
        TALLY.problem("wrong_type", f"{case.name}: the valid call failed: {type(exc).__name__}: {exc}")
    finally:
        _stop_alarms()
    if valid_out is not None:
        bad = _non_finite(valid_out, case.nan_outputs, case.minus_inf_ok)
        if bad:
            TALLY.problem("silent_nan", f"{case.name}: the valid call returned non-finite {bad}")
    names = list(case.vary if case.vary is not None else case.kwargs)
    for argument in names:
        valid = case.kwargs[argument]
        if argument in case.options_fields:
            _probe_options(case, argument)
            continue
        strategy = (_spoil_array(np.asarray(valid)) if isinstance(valid, np.ndarray)
                    else _spoil_scalar(valid))

        @settings(max_examples=case.examples or EXAMPLES)
        @given(value=strategy)
        def run(value: Any) -> None:
            call(case, argument, value)

        run()


def _probe_options(case: Case, argument: str) -> None:
    """Options objects: spoil one field at a time (the message must name that field)."""
    factory, names = case.options_fields[argument]
    for name in names:
        good = getattr(factory(), name)

        @settings(max_examples=case.examples or EXAMPLES)
        @given(value=_spoil_scalar(good))
        def run(value: Any) -> None:
            options = factory()
            try:
                setattr(options, name, value)
            except ALLOWED:
                TALLY.rejected += 1  # pybind11 refused the type at assignment: fine
                return
            except BaseException as exc:
                TALLY.problem("wrong_type", f"{case.name}: setting {argument}.{name} = {_short(value)}: "
                                            f"{type(exc).__name__}: {exc}")
                return
            if _same(getattr(options, name), good):
                return  # e.g. True assigned to an int field that was already 1
            call(case, argument, options, fields=[name], shown=f"<{name}={_short(value)}>")

        run()


def same_for_threads(name: str, fn: Callable[[int], Any]) -> None:
    """Seeded results must not depend on the thread count."""
    TALLY.cases += 1
    a, b = fn(1), fn(2)
    if repr(_canonical(a)) != repr(_canonical(b)):
        TALLY.problem("unclear", f"{name}: results differ for 1 and 2 threads")


def _as_dict(x: Any) -> Any:
    """A typed result of the bindings (result_binding.h: a read-only mapping with to_dict()) as
    its dict of fields; anything else as it is."""
    if not isinstance(x, dict) and hasattr(x, "to_dict") and hasattr(x, "_fields"):
        return x.to_dict()
    return x


def _canonical(x: Any) -> Any:
    x = _as_dict(x)
    if isinstance(x, dict):
        return {k: _canonical(v) for k, v in x.items() if "seconds" not in k}
    if isinstance(x, (list, tuple)):
        return [_canonical(v) for v in x]
    if isinstance(x, np.ndarray):
        return x.tobytes()
    return x


def main(groups: Dict[str, Callable[[], None]]) -> int:
    signal.signal(signal.SIGALRM, _alarm)
    signal.signal(signal.SIGPROF, _alarm)
    # Spoiled path arguments ("x", "") are relative: run in a fresh temporary folder so that
    # writers never write beside the tests, also when this script is run by hand.
    os.chdir(tempfile.mkdtemp(prefix="indoorloc_properties_"))
    name = sys.argv[1]
    try:
        groups[name]()
    except Exception:
        TALLY.problem("wrong_type", "harness error: " + traceback.format_exc()[-800:])
    result = {k: v for k, v in TALLY.__dict__.items()}
    print(json.dumps(result))
    bad = TALLY.hangs + TALLY.silent_nan + TALLY.unclear + TALLY.wrong_type + TALLY.mutated
    return 1 if bad else 0
