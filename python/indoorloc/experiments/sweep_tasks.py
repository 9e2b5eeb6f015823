"""Task functions for ``indoorloc.sweep`` (module level, so that Dask can send them to workers).

Each takes ``(params, seed, **shared)`` and returns a dict (JSON scalars, or arrays when no
JSON-lines file is written); the result depends only on its arguments (the seed comes from the
sweep: ``sweep.task_seed``). The tasks of ``fusion evaluate`` and ``pdr evaluate`` live in their
experiment modules (``fusion_real.fold_task``, ``pdr_evaluate.dataset_task``), which dispatch
them themselves.
"""

from __future__ import annotations

import hashlib
from typing import Any, Dict, Mapping, Optional, Sequence

import numpy as np

_NETWORKS: Dict[str, Any] = {}  # per worker process: road networks built from shared segments


def _network(segments_m: Optional[np.ndarray]):
    """The road network of ``segments_m`` (E, 4) [m], built once per worker process (the C++
    object does not pickle; its segments do and are sent once as a shared input); None: the
    paper's warehouse."""
    from indoorloc import mapmatch

    if segments_m is None:
        key = "warehouse"
    else:
        seg = np.ascontiguousarray(segments_m, dtype=float)
        key = hashlib.sha1(seg.tobytes() + str(seg.shape).encode()).hexdigest()
    if key not in _NETWORKS:
        _NETWORKS[key] = mapmatch.warehouse_network() if segments_m is None else mapmatch.RoadNetwork(seg)
    return _NETWORKS[key]


def mapmatch_run(params: Mapping[str, Any], seed: int, segments_m: Optional[np.ndarray] = None) -> Dict[str, Any]:
    """One Monte Carlo run of paper 000's experiment (mapmatch_reproduce settings).

    params: ``kappa`` (von Mises concentration), optional ``num_particles`` (default 2000),
    ``duration_s`` (default 200 s), ``variant`` (default "bias"). ``segments_m``: the road
    network's segments (E, 4) [m] (default: the paper's warehouse; pass them as a shared input
    so that they are sent once). Returns the run's mean position error [m] and the fraction of
    epochs on the right segment."""
    from indoorloc import mapmatch
    from indoorloc.experiments import mapmatch_reproduce as mr

    net = _network(segments_m)
    f = mr.filter_options(float(params["kappa"]), str(params.get("variant", "bias")),
                          int(params.get("num_particles", 2000)))
    r = mapmatch.monte_carlo(net, mr.trajectory_options(float(params.get("duration_s", 200.0))), f, n_runs=1,
                             seed=int(seed), n_threads=1)
    return {"mean_error_m": float(np.mean(r["error_m"])), "p_correct": float(np.mean(r["correct_segment"]))}


def mapmatch_kappa(params: Mapping[str, Any], seed: int, segments_m: Optional[np.ndarray] = None) -> Dict[str, Any]:
    """``mapmatch reproduce`` for one κ on a worker: ``n_runs`` runs of ``variant`` with
    ``num_particles`` from the experiment's own ``seed`` parameter (not the sweep's derived seed,
    so that the results equal the in-process command's), ``threads`` C++ threads, optional
    ``duration_s`` (default 200 s). Returns the
    per-run curves (R, T) of the experiment's KappaResult and its time [s]."""
    from indoorloc.experiments import mapmatch_reproduce as mr

    r = mr.run_kappas(str(params["variant"]), kappas=(float(params["kappa"]),), n_runs=int(params["n_runs"]),
                      num_particles=int(params["num_particles"]), seed=int(params["seed"]),
                      n_threads=int(params.get("threads", 1)), network=_network(segments_m),
                      duration_s=float(params.get("duration_s", 200.0)))[float(params["kappa"])]
    return {"error_m": r.error_m, "correct": r.correct, "smoothed_error_m": r.smoothed_error_m, "seconds": r.seconds}


def analog_table1_realisation(params: Mapping[str, Any], seed: int, table1_kwargs: Mapping[str, Any]) -> Dict[str, Any]:
    """``analog lorenz63`` for realisation ``params["r"]`` on a worker: ``run_table1(**table1_kwargs,
    realisations=[r])`` (the experiment's own seeds: identical to the in-process run)."""
    from indoorloc.experiments import analog_lorenz63 as al

    return {"part": al.run_table1(**dict(table1_kwargs), realisations=[int(params["r"])])}


def wifi_case(params: Mapping[str, Any], seed: int, root: str, cv_points: int, cv_seed: int,
              threads: int = 0, methods: Optional[Sequence[str]] = None) -> Dict[str, Any]:
    """One ``wifi evaluate`` case ``params["case"]`` = "dataset/k=K" on a worker: its markdown and
    JSON entry (``wifi_evaluate.evaluate_case``; the experiment's own CV seed)."""
    from indoorloc.experiments import wifi_evaluate

    name, k = str(params["case"]).split("/k=")
    text, entry = wifi_evaluate.evaluate_case(root, name, int(k), cv_points, cv_seed, threads, methods=methods)
    return {"markdown": text, "entry": entry}


def analog_run(params: Mapping[str, Any], seed: int) -> Dict[str, Any]:
    """One realisation of the analog (paper 001) Lorenz-63 experiment: a catalog of ``m`` pairs
    and a test sequence of ``T`` steps (default 300) from the seed, exact forward-backward with
    ``k`` successors. Returns the RMSE of the smoothed state [model units]."""
    from indoorloc.experiments import analog_lorenz63 as al
    from indoorloc.simulate import lorenz63

    catalog = lorenz63.catalog_trajectory(int(params["m"]), seed=int(seed) % (2 ** 31))
    truth, obs = lorenz63.test_problem(int(seed) % (2 ** 31) + 1, T=int(params.get("T", 300)))
    hmm, _ = al.build_anfb(catalog, int(params["k"]), 2.0)
    out = al.run_anfb(hmm, obs, None)
    return {"rmse": al.rmse(out["mean"], truth)}


__all__ = ["analog_run", "analog_table1_realisation", "mapmatch_kappa", "mapmatch_run", "wifi_case"]
