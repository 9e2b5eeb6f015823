"""Parameter sweeps and Monte Carlo studies on Dask: the same tasks in-process on the
local cores or on a cluster, with results that do not depend on where or in which order they ran.

A sweep maps a pure, picklable task function ``fn(params: dict, seed: int, **shared) -> dict``
over the grid ``product(grid values) x runs``. Each task has a key (canonical JSON of its
parameters and run index) and a seed derived from (base seed, key) by SHA-256, so its result
depends only on its own parameters — not on the scheduler, the number of workers or the order
of completion. Large inputs (a road network, a catalog, a floor plan) go in ``shared``: they
are sent to the workers once (``Client.scatter(..., broadcast=True)``), not once per task.

Results are streamed to a JSON-lines file as they finish (one line per task: key, params, run,
seed, status, result or error), so an interrupted sweep resumes: tasks whose key already has an
``ok`` line are not run again; failed tasks are reported with their parameters and re-run on
the next call. The returned :class:`SweepResult` is in task order.

Schedulers: ``scheduler=None`` starts an in-process Dask client (threads, no cluster: the C++
work releases the GIL); ``"tcp://host:8786"`` connects to a running ``dask scheduler`` with
workers on other machines; a ``distributed.Client`` is used as given (e.g. on a
``LocalCluster``, dask-jobqueue or Kubernetes). Dask is an optional dependency: ``pip install
"indoorloc[sweep]"``.

The tidy table is a list of rows plus :meth:`SweepResult.to_structured` (a numpy structured
array): numpy is already a dependency and the rows are flat scalars, so pandas is not needed
(``pandas.DataFrame(result.rows)`` works for those who have it).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

INSTALL_HINT = 'the sweep layer needs Dask: pip install "indoorloc[sweep]" (dask[distributed])'


def task_seed(base_seed: int, key: str) -> int:
    """The seed of a task: the first 63 bits of SHA-256 of "base_seed:key" (independent of any
    scheduler; distinct keys give unrelated seeds)."""
    digest = hashlib.sha256(f"{int(base_seed)}:{key}".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


@dataclass(frozen=True)
class Task:
    """One task of a sweep: its parameters, run index, key and seed."""

    params: Dict[str, Any]
    run: int
    key: str
    seed: int


def make_tasks(grid: Mapping[str, Sequence[Any]], runs: int = 1, base_seed: int = 0) -> List[Task]:
    """The tasks of ``grid`` (name -> values; the Cartesian product) x ``runs`` runs each, in
    grid order then run order. Values must be JSON scalars (numbers, strings, booleans, None).
    Raises ValueError on an empty grid value list, a non-scalar value or runs < 1."""
    if int(runs) != runs or runs < 1:
        raise ValueError(f"indoorloc: argument 'runs': expected an integer >= 1, got {runs!r}")
    names = list(grid)
    for name in names:
        values = list(grid[name])
        if not values:
            raise ValueError(f"indoorloc: argument 'grid': parameter {name!r} has no value")
        for v in values:
            if not (v is None or isinstance(v, (bool, int, float, str, np.integer, np.floating))):
                raise ValueError(f"indoorloc: argument 'grid': value {v!r} of {name!r} is not a JSON scalar")
    tasks = []
    for values in itertools.product(*(list(grid[n]) for n in names)):
        params = {n: (v.item() if isinstance(v, np.generic) else v) for n, v in zip(names, values)}
        for r in range(int(runs)):
            key = json.dumps({"params": params, "run": r}, sort_keys=True)
            tasks.append(Task(params, r, key, task_seed(base_seed, key)))
    return tasks


def _run_task(fn: Callable[..., Mapping[str, Any]], task: Task, shared: Mapping[str, Any]) -> Dict[str, Any]:
    """Runs one task on a worker; an exception becomes a ``failed`` row (never lost)."""
    start = time.perf_counter()
    row = {"key": task.key, "params": task.params, "run": task.run, "seed": task.seed}
    try:
        result = fn(dict(task.params), task.seed, **shared)
        row.update(status="ok", result=dict(result))
    except Exception as exc:  # noqa: BLE001 - reported with the task's parameters
        row.update(status="failed", error=f"{type(exc).__name__}: {exc}",
                   traceback=traceback.format_exc(limit=5))
    row["seconds"] = time.perf_counter() - start
    return row


@dataclass
class SweepResult:
    """Rows in task order: ``params`` flattened, ``run``, ``seed``, the task's result fields;
    ``failed``: the failed tasks with their parameters and error; counts of what ran now and
    what was already on disk."""

    rows: List[Dict[str, Any]]
    failed: List[Dict[str, Any]] = field(default_factory=list)
    n_run: int = 0
    n_cached: int = 0
    seconds: float = 0.0

    def to_structured(self) -> np.ndarray:
        """The rows as a numpy structured array (numbers as float64/int64, strings as unicode)."""
        if not self.rows:
            return np.zeros(0)
        names = list(self.rows[0])
        dtypes = []
        for n in names:
            col = [r.get(n) for r in self.rows]
            if all(isinstance(v, (bool, np.bool_)) for v in col):
                dtypes.append((n, bool))
            elif all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in col):
                dtypes.append((n, np.int64))
            elif all(v is None or isinstance(v, (int, float, np.number)) for v in col):
                dtypes.append((n, np.float64))
            else:
                dtypes.append((n, f"U{max(len(str(v)) for v in col)}"))
        out = np.zeros(len(self.rows), dtype=dtypes)
        for n, _ in dtypes:
            out[n] = [np.nan if r.get(n) is None else r.get(n) for r in self.rows]
        return out


def _read_done(path: Path) -> Dict[str, Dict[str, Any]]:
    done: Dict[str, Dict[str, Any]] = {}
    if not path.is_file():
        return done
    for i, line in enumerate(path.read_text().splitlines(), start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            # A line cut by an interruption: that task simply runs again.
            continue
        if row.get("status") == "ok" and "key" in row:
            done[row["key"]] = row
    return done


def _client(scheduler: Union[None, str, Any], workers: Optional[int]):
    """(client, owned): a distributed.Client for the scheduler argument."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - exercised only without the extra
        raise ImportError(INSTALL_HINT) from None
    if scheduler is None:
        return Client(processes=False, n_workers=1, threads_per_worker=int(workers or 2),
                      dashboard_address=None), True
    if isinstance(scheduler, str):
        return Client(scheduler), True
    return scheduler, False


def run_sweep(fn: Callable[..., Mapping[str, Any]], grid: Mapping[str, Sequence[Any]], *, runs: int = 1,
              base_seed: int = 0, out: Optional[Union[str, Path]] = None, scheduler: Union[None, str, Any] = None,
              workers: Optional[int] = None, shared: Optional[Mapping[str, Any]] = None,
              max_tasks: Optional[int] = None, progress: Optional[Callable[[], None]] = None) -> SweepResult:
    """Runs ``fn(params, seed, **shared)`` for every task of ``grid`` x ``runs``.

    Parameters
    ----------
    fn : callable
        A module-level (picklable) pure function returning a dict of JSON scalars.
    grid : mapping name -> sequence of JSON scalars
    runs : int
        Runs per grid point (Monte Carlo); run r of a point has its own seed.
    base_seed : int
        Every task seed is derived from it and the task's key (:func:`task_seed`).
    out : path, optional
        JSON-lines file: results are appended as tasks finish; tasks already there with status
        ``ok`` are not run again (resume).
    scheduler : None, "tcp://host:port" or a distributed.Client
        None: an in-process client with ``workers`` threads (default 2).
    shared : mapping, optional
        Large read-only inputs passed to every task as keyword arguments, sent once.
    max_tasks : int, optional
        Run at most this many new tasks, then return (a partial sweep; the next call resumes).
    progress : callable, optional
        Called once per finished task.

    Returns
    -------
    SweepResult
        Rows of the finished ``ok`` tasks in task order (whether run now or read from ``out``).
    """
    tic = time.perf_counter()
    tasks = make_tasks(grid, runs, base_seed)
    path = Path(out) if out is not None else None
    done = _read_done(path) if path is not None else {}
    todo = [t for t in tasks if t.key not in done]
    if max_tasks is not None:
        todo = todo[: max(0, int(max_tasks))]
    fresh: Dict[str, Dict[str, Any]] = {}
    failed: List[Dict[str, Any]] = []
    if todo:
        from distributed import as_completed

        client, owned = _client(scheduler, workers)
        try:
            # hash=False: a key of its own per call. With the default content hash, a second sweep on the
            # same client re-used the first one's key while its release was pending ("lost dependencies").
            shared_futures = {k: client.scatter(v, broadcast=True, hash=False) for k, v in (shared or {}).items()}
            futures = [client.submit(_run_task, fn, t, shared_futures, key=f"indoorloc-sweep-{t.seed:x}", pure=False)
                       for t in todo]
            sink = path.open("a") if path is not None else None
            try:
                for fut in as_completed(futures):
                    row = fut.result()
                    if sink is not None:
                        sink.write(json.dumps(row) + "\n")
                        sink.flush()
                    if row["status"] == "ok":
                        fresh[row["key"]] = row
                    else:
                        failed.append({"params": row["params"], "run": row["run"], "seed": row["seed"],
                                       "error": row["error"]})
                    if progress:
                        progress()
            finally:
                if sink is not None:
                    sink.close()
        finally:
            if owned:
                client.close()
    rows = []
    for t in tasks:
        row = fresh.get(t.key) or done.get(t.key)
        if row is None:
            continue
        rows.append({**row["params"], "run": row["run"], "seed": row["seed"], **row["result"]})
    failed.sort(key=lambda f: json.dumps({"params": f["params"], "run": f["run"]}, sort_keys=True))
    return SweepResult(rows, failed, n_run=len(fresh) + len(failed), n_cached=sum(t.key in done for t in tasks),
                       seconds=time.perf_counter() - tic)


__all__ = ["INSTALL_HINT", "SweepResult", "Task", "make_tasks", "run_sweep", "task_seed"]
