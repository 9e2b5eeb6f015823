"""Table 1 of the analog HMM paper (Lguensat et al., EUSIPCO 2016, §3.1): Lorenz-63 from x alone.

The experiment: a catalog of M (analog, successor) pairs from one long Lorenz-63 simulation
(dt = 0.01), and independent test sequences of T = 1000 steps whose x component is observed
every dt_obs = 40 steps with noise variance R = 2 (:mod:`indoorloc.simulate.lorenz63`). Every
method reconstructs (x, y, z) at all T steps; the score is the RMSE over the 3 variables and the
T steps, averaged over seeded realisations:

- EnKS: 100 members, the true Lorenz-63 equations (:func:`analog_baselines.enks_lorenz63`);
- AnEnKS: 100 members, analog forecasting on the catalog (:func:`analog_baselines.anenks`);
- AnFB: posterior mean of the analog HMM, truncated forward-backward keeping N states
  (``indoorloc.analog``, the C++ implementation; N = 1000 in the paper, K = 10 here).

:func:`run_table1` returns the numbers and :func:`markdown_table` lays them out next to the
paper's; :func:`reconstruction_example` returns one realisation for the paper's Fig. 2 (3-D
attractor and time series). Everything is seeded: the catalog of size M is
``catalog_trajectory(M, seed=seed)`` (so the 10^4 catalog is the start of the 10^5 one), test
problem r is ``test_problem(seed + r)`` (independent streams, see the simulator), and every
stochastic method of realisation r is seeded with ``seed + r``.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc.experiments import analog_baselines
from indoorloc.progress import progress
from indoorloc.simulate import lorenz63

#: Table 1 of the paper: RMSE and execution time (their Matlab/Python, their machine).
PAPER_RMSE = {
    ("EnKS", None): 3.7799,
    ("AnEnKS", 10**4): 4.3279,
    ("AnEnKS", 10**5): 3.2788,
    ("AnFB", 10**4): 1.3183,
    ("AnFB", 10**5): 0.5774,
}
PAPER_TIME = {
    ("EnKS", None): "2 h",
    ("AnEnKS", 10**4): "13 min",
    ("AnEnKS", 10**5): "1.3 h",
    ("AnFB", 10**4): "8 min",
    ("AnFB", 10**5): "14 min",
}
PAPER_BEAM = 1000
METHODS = ("enks", "anenks", "anfb")


def analog_bindings():
    """The ``indoorloc.analog`` module, or ImportError with the reason when it is not built."""
    try:
        from indoorloc import analog
    except ImportError as exc:
        raise ImportError(
            "indoorloc: the AnFB needs the analog HMM bindings (indoorloc.analog over "
            f"indoorloc._core.analog), which this installation does not have ({exc}). Rebuild and "
            "reinstall indoorloc, or leave 'anfb' out of 'methods'."
        ) from exc
    if not hasattr(analog, "AnalogHMM"):
        raise ImportError(
            "indoorloc: indoorloc.analog exists but has no AnalogHMM: the analog bindings are not "
            "built in this installation. Rebuild and reinstall indoorloc, or leave 'anfb' out of 'methods'."
        )
    return analog


def analog_available() -> bool:
    """True when ``indoorloc.analog`` provides the AnalogHMM bindings."""
    try:
        analog_bindings()
    except ImportError:
        return False
    return True


def rmse(estimate: np.ndarray, truth: np.ndarray) -> float:
    """Root mean square error over every time step and every variable."""
    estimate = np.asarray(estimate, dtype=float)
    truth = np.asarray(truth, dtype=float)
    if estimate.shape != truth.shape:
        raise ValueError(f"indoorloc: estimate {estimate.shape} and truth {truth.shape} differ in shape")
    return float(np.sqrt(np.mean((estimate - truth) ** 2)))


def _check_methods(methods: Sequence[str]) -> List[str]:
    methods = [m.lower() for m in methods]
    unknown = [m for m in methods if m not in METHODS]
    if unknown or not methods:
        raise ValueError(f"indoorloc: argument 'methods': unknown {unknown}; choose among {list(METHODS)}")
    return methods


def _beam_label(beam: Optional[int]) -> str:
    return "exact" if beam is None else str(int(beam))


#: Kernel width multiplier and mass-adaptive beam tolerance of the AnFB, chosen by
#: :func:`run_kernel_selection` on validation problems (seeds 10000+) disjoint from the test
#: problems (seeds 0 .. 9): see docs/analog.md. The paper's own σ is sigma_scale = 1.
DEFAULT_SIGMA_SCALE = 0.5
DEFAULT_MAX_DROPPED_MASS = 1e-3
DEFAULT_K = 10
#: (K, sigma_scale) per catalog size, chosen by `indoorloc analog lorenz63-tune` on the
#: validation problems (docs/analog.md): a small catalog needs more and wider neighbours to let
#: the chain jump between passes of the attractor, a large one a narrow kernel that keeps it on
#: a pass. Sizes not listed use (k, sigma_scale) as given.
VALIDATED_KERNELS: Dict[int, Tuple[int, float]] = {10**4: (50, 0.35), 10**5: (10, 0.5)}


@dataclasses.dataclass(frozen=True)
class Lorenz63Setting:
    """The paper's test problem and ensemble sizes (§3.1), written once: every runner of this
    module takes ``setting=`` (default :data:`PAPER_SETTING`); a smaller case is
    ``Lorenz63Setting(T=200, dt_obs=8)``."""

    T: int = 1000  #: steps of a test sequence (dt = 0.01 each)
    dt_obs: int = 40  #: steps between two observations of x
    R: float = 2.0  #: observation noise variance of x [model units²]
    n_members: int = 100  #: ensemble size of EnKS and AnEnKS
    anenks_k: int = 50  #: analogs of the AnEnKS local linear regression


#: The setting of the paper's Table 1 and Fig. 2.
PAPER_SETTING = Lorenz63Setting()


def _setting_with(setting: Lorenz63Setting, legacy: Dict[str, Any], caller: str) -> Lorenz63Setting:
    """``setting`` with the fields given by the former keyword arguments (T, dt_obs, R, n_members,
    anenks_k), which still work for one release with a DeprecationWarning."""
    names = {f.name for f in dataclasses.fields(Lorenz63Setting)}
    unknown = sorted(set(legacy) - names)
    if unknown:
        raise TypeError(f"{caller}() got an unexpected keyword argument {unknown[0]!r}")
    if not legacy:
        return setting
    warnings.warn(f"indoorloc: {caller}({', '.join(f'{k}=...' for k in sorted(legacy))}) is deprecated; pass "
                  f"setting=Lorenz63Setting({', '.join(f'{k}=...' for k in sorted(legacy))})",
                  DeprecationWarning, stacklevel=3)
    return dataclasses.replace(setting, **legacy)
#: First seed of the validation problems used to choose the kernel (never used for the test).
VALIDATION_SEED = 10_000


#: Successor rules of the AnFB transitions (``AnalogHMM(successor_rule=...)``): "catalog" is the
#: paper's eq. 4, "incremental" the locally incremental analog operator (docs/analog.md).
SUCCESSOR_RULES = ("catalog", "incremental")
DEFAULT_SUCCESSOR_RULE = "catalog"


def build_anfb(
    catalog: np.ndarray, k: int, R: float, sigma_scale: float = DEFAULT_SIGMA_SCALE,
    successor_rule: str = DEFAULT_SUCCESSOR_RULE,
):
    """Analog HMM of a Lorenz-63 catalog trajectory (x observed); returns (hmm, seconds).

    R is the observation variance the HMM assumes (it may be inflated over the data's).
    """
    analog = analog_bindings()
    start = time.perf_counter()
    cat = analog.Catalog([np.ascontiguousarray(catalog)], lag=1, stride=1)
    hmm = analog.AnalogHMM(
        cat, k=int(k), observed=[0], R=np.array([[float(R)]]), sigma_scale=float(sigma_scale),
        successor_rule=str(successor_rule),
    )
    return hmm, time.perf_counter() - start


def run_anfb(
    hmm, observations: np.ndarray, beam: Optional[int], max_dropped_mass: float = DEFAULT_MAX_DROPPED_MASS
) -> Dict[str, object]:
    """Posterior mean (T, 3) and diagnostics of one smoothing run.

    beam None is the exact forward-backward; otherwise N of the truncated one, widened where it
    would drop more than ``max_dropped_mass`` of the filtering mass (1 = the paper's fixed N).
    """
    start = time.perf_counter()
    if beam is None:
        out = hmm.smooth(observations, beam=None)
    else:
        out = hmm.smooth(observations, beam=int(beam), max_dropped_mass=float(max_dropped_mass))
    seconds = time.perf_counter() - start
    mean = np.asarray(out["mean"])[:, :3]
    std = np.asarray(out["std"])[:, :3] if "std" in out else None
    dropped = np.asarray(out["dropped_mass"]) if "dropped_mass" in out else np.zeros(0)
    return {
        "mean": mean,
        "std": std,
        "seconds": seconds,
        "log_likelihood": float(out["log_likelihood"]),
        "max_dropped_mass": float(np.max(dropped)) if dropped.size else 0.0,
        "mean_support": float(np.mean(out["support_size"])),
    }


def run_table1(
    n_realisations: int = 3,
    catalog_sizes: Sequence[int] = (10**4, 10**5),
    beams: Sequence[Optional[int]] = (1000, 3000, 10000),
    k: int = DEFAULT_K,
    methods: Sequence[str] = METHODS,
    setting: Lorenz63Setting = PAPER_SETTING,
    enks_Q: float = analog_baselines.DEFAULT_LORENZ_Q,
    seed: int = 0,
    sigma_scale: float = DEFAULT_SIGMA_SCALE,
    max_dropped_mass: float = DEFAULT_MAX_DROPPED_MASS,
    kernels: Optional[Dict[int, Tuple[int, float]]] = None,
    successor_rule: str = DEFAULT_SUCCESSOR_RULE,
    r_hmm_scale: float = 1.0,
    realisations: Optional[Sequence[int]] = None,
    **deprecated_setting_fields: Any,
) -> Dict[str, object]:
    """Run Table 1: RMSE and time of EnKS, AnEnKS and AnFB over seeded realisations.

    Parameters
    ----------
    n_realisations : int
        Test problems ``test_problem(seed + r)``, r = 0 .. n_realisations - 1.
    catalog_sizes : ints
        Catalog sizes M (number of pairs).
    beams : ints or None
        N of the truncated AnFB (None: exact forward-backward).
    k : int
        Successors per state of the analog HMM (K of eq. 4).
    methods : subset of ("enks", "anenks", "anfb")
    setting : Lorenz63Setting
        Test problem (T, dt_obs, R) and ensemble sizes (n_members, anenks_k); the paper's by
        default. The former keywords T, dt_obs, R, n_members, anenks_k still work (deprecated).
    enks_Q : float
        Model noise variance per step of the EnKS.
    seed : int
    sigma_scale : float
        Kernel width multiplier of the AnFB transitions (1 = the paper's σ).
    max_dropped_mass : float
        Mass-adaptive beam of the truncated AnFB (1 = the paper's fixed N).
    kernels : {M: (K, sigma_scale)} or None
        Per-catalog-size kernel overriding (k, sigma_scale) (e.g. :data:`VALIDATED_KERNELS`).
    successor_rule : "catalog" or "incremental"
        Target of the AnFB transitions (see :data:`SUCCESSOR_RULES`).
    r_hmm_scale : float
        The AnFB's observation variance is r_hmm_scale · R (1: the data's own).
    realisations : ints or None
        Run only these realisation indices r (default all of 0 .. n_realisations - 1): one
        Dask task per realisation, merged by :func:`merge_table1`.

    Returns
    -------
    dict with "settings", "rows" (one per method / M / N: per-realisation "rmse" and
    "seconds", their mean and std, the paper's RMSE and time) and "build_seconds" per M.
    Raises ImportError (with the reason) if "anfb" is requested and the bindings are missing.
    """
    methods = _check_methods(methods)
    setting = _setting_with(setting, deprecated_setting_fields, "run_table1")
    T, dt_obs, R, n_members, anenks_k = setting.T, setting.dt_obs, setting.R, setting.n_members, setting.anenks_k
    if int(n_realisations) != n_realisations or n_realisations < 1:
        raise ValueError(f"indoorloc: argument 'n_realisations': expected an integer >= 1, got {n_realisations}")
    if "anfb" in methods:
        analog_bindings()
        if not beams:
            raise ValueError("indoorloc: argument 'beams': give at least one N (or None for exact)")
    sizes = [int(m) for m in catalog_sizes] if ("anenks" in methods or "anfb" in methods) else []

    build: Dict[int, Dict[str, float]] = {}
    forecasters, hmms = {}, {}
    for M in sizes:
        start = time.perf_counter()
        catalog = lorenz63.catalog_trajectory(M, seed=seed)
        build[M] = {"simulate_catalog": time.perf_counter() - start}
        if "anenks" in methods:
            start = time.perf_counter()
            forecasters[M] = analog_baselines.AnalogForecaster(catalog[:-1], catalog[1:], k=anenks_k)
            build[M]["anenks_kdtree"] = time.perf_counter() - start
        if "anfb" in methods:
            k_m, scale_m = (kernels or {}).get(M, (k, sigma_scale))
            hmms[M], build[M]["anfb_hmm"] = build_anfb(catalog, k_m, r_hmm_scale * R, scale_m, successor_rule)
            build[M]["anfb_kernel"] = (int(k_m), float(scale_m))

    rows: Dict[tuple, Dict[str, object]] = {}

    def record(method: str, M: Optional[int], beam: Optional[int], value: float, seconds: float, extra=None):
        key = (method, M, _beam_label(beam) if method == "AnFB" else None)
        row = rows.setdefault(
            key,
            {
                "method": method,
                "M": M,
                "beam": key[2],
                "rmse": [],
                "seconds": [],
                "paper_rmse": PAPER_RMSE.get((method, M)) if method != "AnFB" or beam == PAPER_BEAM else None,
                "paper_time": PAPER_TIME.get((method, M)) if method != "AnFB" or beam == PAPER_BEAM else None,
            },
        )
        row["rmse"].append(value)
        row["seconds"].append(seconds)
        for name, v in (extra or {}).items():
            row.setdefault(name, []).append(v)

    todo = list(range(int(n_realisations))) if realisations is None else [int(r) for r in realisations]
    for r in progress(todo, total=len(todo), desc="Lorenz-63 realisations"):
        truth, observations = lorenz63.test_problem(seed + r, T=T, dt_obs=dt_obs, R=R)
        if "enks" in methods:
            start = time.perf_counter()
            est = analog_baselines.enks_lorenz63(observations, n_members=n_members, seed=seed + r, R=R, Q=enks_Q)
            record("EnKS", None, None, rmse(est, truth), time.perf_counter() - start)
        for M in sizes:
            if "anenks" in methods:
                start = time.perf_counter()
                est = analog_baselines.anenks(
                    observations, None, None, observed=[0], R=R, n_members=n_members, seed=seed + r,
                    forecaster=forecasters[M],
                )
                record("AnEnKS", M, None, rmse(est, truth), time.perf_counter() - start)
            if "anfb" in methods:
                for beam in beams:
                    out = run_anfb(hmms[M], observations, beam, max_dropped_mass)
                    record(
                        "AnFB", M, beam, rmse(out["mean"], truth), out["seconds"],
                        {"max_dropped_mass": out["max_dropped_mass"], "mean_support": out["mean_support"]},
                    )

    out_rows = [_row_stats(row) for row in rows.values()]
    return {
        "title": "Lorenz-63 reconstruction from noisy x every dt_obs steps (paper 001, Table 1)",
        "settings": {
            "n_realisations": int(n_realisations), "catalog_sizes": sizes, "beams": [_beam_label(b) for b in beams],
            "k": int(k), "methods": methods, "T": int(T), "dt_obs": int(dt_obs), "R": float(R),
            "n_members": int(n_members), "anenks_k": int(anenks_k), "enks_Q": float(enks_Q), "seed": int(seed),
            "sigma_scale": float(sigma_scale), "max_dropped_mass": float(max_dropped_mass),
            "kernels": {str(M): list(v) for M, v in (kernels or {}).items()},
            "successor_rule": str(successor_rule), "r_hmm_scale": float(r_hmm_scale),
        },
        "rows": out_rows,
        "build_seconds": {str(M): v for M, v in build.items()},
        "realisations": todo,
    }


def _row_stats(row: Dict[str, object]) -> Dict[str, object]:
    values = np.asarray(row["rmse"])
    row["rmse_mean"] = float(values.mean())
    row["rmse_median"] = float(np.median(values))
    row["rmse_std"] = float(values.std(ddof=1)) if values.size > 1 else 0.0
    row["seconds_mean"] = float(np.mean(row["seconds"]))
    return row


def merge_table1(parts: Sequence[Dict[str, object]]) -> Dict[str, object]:
    """One :func:`run_table1` result from results over disjoint ``realisations`` (e.g. one Dask
    task each): per row the per-realisation lists concatenated in realisation order and the
    statistics recomputed; the build times are the first part's."""
    if not parts:
        raise ValueError("indoorloc: argument 'parts': no result to merge")
    parts = sorted(parts, key=lambda p: min(p["realisations"]) if p["realisations"] else -1)
    merged = {k: v for k, v in parts[0].items() if k not in ("rows", "realisations")}
    rows: Dict[tuple, Dict[str, object]] = {}
    for part in parts:
        for row in part["rows"]:
            key = (row["method"], row["M"], row["beam"])
            if key not in rows:
                rows[key] = {k: ([] if isinstance(v, list) else v) for k, v in row.items()}
            for name, value in row.items():
                if isinstance(value, list):
                    rows[key][name].extend(value)
    merged["rows"] = [_row_stats(r) for r in rows.values()]
    merged["realisations"] = [r for p in parts for r in p["realisations"]]
    return merged


def markdown_table(result: Dict[str, object]) -> str:
    """The rows of :func:`run_table1` as a markdown table next to the paper's Table 1."""
    n = result["settings"]["n_realisations"]
    lines = [
        f"| method | M | N (beam) | RMSE (mean ± std, {n} runs) | median | worst run | paper RMSE | time per run [s] | "
        "mean support | paper time |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in result["rows"]:
        M = _format_size(row["M"])
        beam = row["beam"] or "-"
        paper = "-" if row["paper_rmse"] is None else f"{row['paper_rmse']:.4g}"
        paper_time = row["paper_time"] or "-"
        support = f"{np.mean(row['mean_support']):.0f}" if "mean_support" in row else "-"
        lines.append(
            f"| {row['method']} | {M} | {beam} | {row['rmse_mean']:.3f} ± {row['rmse_std']:.3f} | "
            f"{np.median(row['rmse']):.3f} | {np.max(row['rmse']):.2f} | {paper} | {row['seconds_mean']:.2f} | {support} | {paper_time} |"
        )
    return "\n".join(lines)


def _format_size(m: Optional[int]) -> str:
    if m is None:
        return "-"
    exponent = int(round(np.log10(m)))
    return f"10^{exponent}" if 10**exponent == m else str(m)


def reconstruction_example(
    seed: int = 0,
    M: int = 10**5,
    beam: Optional[int] = 1000,
    k: Optional[int] = None,
    methods: Sequence[str] = METHODS,
    setting: Lorenz63Setting = PAPER_SETTING,
    sigma_scale: Optional[float] = None,
    max_dropped_mass: float = DEFAULT_MAX_DROPPED_MASS,
    **deprecated_setting_fields: Any,
) -> Dict[str, object]:
    """One realisation for the paper's Fig. 2: truth, observations and each reconstruction.

    k and sigma_scale default to :data:`VALIDATED_KERNELS` for M (else DEFAULT_K / DEFAULT_SIGMA_SCALE);
    ``setting`` (the paper's by default) gives the test problem and the ensemble sizes.

    Returns
    -------
    dict with "truth" (T, 3), "observations" (T, 1) (NaN = not observed), "t_obs" (indices of
    the observed steps), "estimates" {method: (T, 3)}, "rmse" {method: float}, "seconds".
    """
    methods = _check_methods(methods)
    setting = _setting_with(setting, deprecated_setting_fields, "reconstruction_example")
    T, dt_obs, R, n_members, anenks_k = setting.T, setting.dt_obs, setting.R, setting.n_members, setting.anenks_k
    if "anfb" in methods:
        analog_bindings()
    k_default, scale_default = VALIDATED_KERNELS.get(int(M), (DEFAULT_K, DEFAULT_SIGMA_SCALE))
    k = k_default if k is None else int(k)
    sigma_scale = scale_default if sigma_scale is None else float(sigma_scale)
    truth, observations = lorenz63.test_problem(seed, T=T, dt_obs=dt_obs, R=R)
    estimates, seconds = {}, {}
    catalog = lorenz63.catalog_trajectory(int(M), seed=seed) if ("anfb" in methods or "anenks" in methods) else None
    if "anfb" in methods:
        hmm, build = build_anfb(catalog, k, R, sigma_scale)
        out = run_anfb(hmm, observations, beam, max_dropped_mass)
        estimates["AnFB"], seconds["AnFB"] = out["mean"], build + out["seconds"]
    if "anenks" in methods:
        start = time.perf_counter()
        estimates["AnEnKS"] = analog_baselines.anenks(
            observations, catalog[:-1], catalog[1:], observed=[0], R=R, n_members=n_members, k=anenks_k, seed=seed
        )
        seconds["AnEnKS"] = time.perf_counter() - start
    if "enks" in methods:
        start = time.perf_counter()
        estimates["EnKS"] = analog_baselines.enks_lorenz63(observations, n_members=n_members, seed=seed, R=R)
        seconds["EnKS"] = time.perf_counter() - start
    return {
        "truth": truth,
        "observations": observations,
        "t_obs": np.flatnonzero(np.isfinite(observations[:, 0])),
        "estimates": estimates,
        "rmse": {name: rmse(est, truth) for name, est in estimates.items()},
        "seconds": seconds,
        "settings": {
            "seed": seed, "M": int(M), "beam": _beam_label(beam), "k": int(k), "T": T, "dt_obs": dt_obs, "R": R,
            "sigma_scale": sigma_scale, "max_dropped_mass": max_dropped_mass,
        },
    }


def run_kernel_selection(
    M: int,
    ks: Sequence[int] = (5, 10, 15),
    sigma_scales: Sequence[float] = (0.35, 0.5, 0.7, 1.0),
    beam: Optional[int] = 1000,
    max_dropped_mass: float = DEFAULT_MAX_DROPPED_MASS,
    n_problems: int = 6,
    setting: Lorenz63Setting = PAPER_SETTING,
    seed: int = 0,
    successor_rule: str = DEFAULT_SUCCESSOR_RULE,
    r_hmm_scales: Sequence[float] = (1.0,),
    **deprecated_setting_fields: Any,
) -> List[Dict[str, object]]:
    """Choose K and the kernel width on validation problems, never on the test problems.

    The paper leaves σ to cross-validation ("σ can be thought as a scale parameter"). The
    validation problems are ``test_problem(VALIDATION_SEED + r)``, r < n_problems: streams
    disjoint from the Table 1 test problems (seeds ``seed + r``, r < 10). The catalog is the one
    of Table 1 (``catalog_trajectory(M, seed)``).

    successor_rule selects the transition rule; r_hmm_scales the inflations of the HMM's
    observation variance (r_hmm_scale · R) tried for every kernel; ``setting`` gives the problems'
    T, dt_obs and R (the paper's by default).

    Returns
    -------
    list of dicts (one per (K, sigma_scale, r_hmm_scale)): "k", "sigma_scale",
    "successor_rule", "r_hmm_scale", "rmse" (per problem), "rmse_mean", "rmse_median",
    "seconds_mean"; sorted by rmse_mean, best first.
    """
    setting = _setting_with(setting, deprecated_setting_fields, "run_kernel_selection")
    T, dt_obs, R = setting.T, setting.dt_obs, setting.R
    analog_bindings()
    catalog = lorenz63.catalog_trajectory(int(M), seed=seed)
    problems = [lorenz63.test_problem(VALIDATION_SEED + r, T=T, dt_obs=dt_obs, R=R) for r in range(int(n_problems))]
    rows = []
    for k in ks:
        for scale in sigma_scales:
            for r_scale in r_hmm_scales:
                hmm, _ = build_anfb(catalog, int(k), float(r_scale) * R, float(scale), successor_rule)
                errors, seconds = [], []
                for truth, observations in problems:
                    out = run_anfb(hmm, observations, beam, max_dropped_mass)
                    errors.append(rmse(out["mean"], truth))
                    seconds.append(out["seconds"])
                rows.append({
                    "k": int(k), "sigma_scale": float(scale), "successor_rule": str(successor_rule),
                    "r_hmm_scale": float(r_scale), "rmse": errors, "rmse_mean": float(np.mean(errors)),
                    "rmse_median": float(np.median(errors)), "seconds_mean": float(np.mean(seconds)),
                })
    return sorted(rows, key=lambda r: r["rmse_mean"])


def error_anatomy(
    truth: np.ndarray, observations: np.ndarray, mean: np.ndarray, std: Optional[np.ndarray] = None,
    burst_threshold: float = 5.0,
) -> Dict[str, object]:
    """Where the squared error of one reconstruction comes from.

    Parameters
    ----------
    truth, mean : (T, 3) true and estimated states; std : (T, 3) posterior standard deviation.
    observations : (T, 1), NaN where x is not observed.
    burst_threshold : float
        A step is in a burst when its error norm ||mean_t - truth_t|| exceeds this (state units).

    Returns
    -------
    dict: "rmse"; "mse_per_variable" (3,) (their mean is rmse²); "rmse_by_phase" {label: RMSE
    over the steps at that distance from the nearest observation (0, 1-10, 11-20)};
    "burst_fraction_steps", "burst_fraction_se" (share of the steps in bursts and of the
    squared error they carry); "se_share_worst_10pct" (squared error share of the worst 10 %
    of the steps); with std: "spread_per_variable" (3,) sqrt(mean posterior variance),
    "rmse_per_variable" (3,), "coverage_2sd" (share of components within 2 posterior sd).
    """
    truth = np.asarray(truth, dtype=float)
    mean = np.asarray(mean, dtype=float)
    err = mean - truth
    se_t = (err**2).sum(axis=1)
    t_obs = np.flatnonzero(np.isfinite(np.asarray(observations)[:, 0]))
    steps = np.arange(truth.shape[0])
    distance = np.min(np.abs(steps[:, None] - t_obs[None, :]), axis=1) if t_obs.size else np.full(steps.size, -1)
    phases = {"0": distance == 0, "1-10": (distance >= 1) & (distance <= 10), "11-20": distance >= 11}
    burst = np.sqrt(se_t) > burst_threshold
    worst = np.sort(se_t)[::-1][: max(1, se_t.size // 10)]
    out: Dict[str, object] = {
        "rmse": rmse(mean, truth),
        "mse_per_variable": (err**2).mean(axis=0),
        "rmse_by_phase": {k: float(np.sqrt(se_t[m].mean() / 3.0)) if m.any() else float("nan") for k, m in phases.items()},
        "burst_fraction_steps": float(burst.mean()),
        "burst_fraction_se": float(se_t[burst].sum() / max(se_t.sum(), 1e-300)),
        "se_share_worst_10pct": float(worst.sum() / max(se_t.sum(), 1e-300)),
    }
    if std is not None:
        std = np.asarray(std, dtype=float)
        out["spread_per_variable"] = np.sqrt((std**2).mean(axis=0))
        out["rmse_per_variable"] = np.sqrt((err**2).mean(axis=0))
        out["coverage_2sd"] = float((np.abs(err) <= 2.0 * std).mean())
    return out


def run_error_anatomy(
    M: int = 10**5,
    k: Optional[int] = None,
    sigma_scale: Optional[float] = None,
    beam: Optional[int] = 3000,
    n_problems: int = 4,
    successor_rule: str = DEFAULT_SUCCESSOR_RULE,
    max_dropped_mass: float = DEFAULT_MAX_DROPPED_MASS,
    setting: Lorenz63Setting = PAPER_SETTING,
    seed: int = 0,
    **deprecated_setting_fields: Any,
) -> List[Dict[str, object]]:
    """:func:`error_anatomy` of the AnFB on the first n_problems validation problems (seeds 10000+).

    k and sigma_scale default to :data:`VALIDATED_KERNELS` for M; ``setting`` gives the problems'
    T, dt_obs and R (the paper's by default).
    """
    setting = _setting_with(setting, deprecated_setting_fields, "run_error_anatomy")
    T, dt_obs, R = setting.T, setting.dt_obs, setting.R
    k_default, scale_default = VALIDATED_KERNELS.get(int(M), (DEFAULT_K, DEFAULT_SIGMA_SCALE))
    k = k_default if k is None else int(k)
    sigma_scale = scale_default if sigma_scale is None else float(sigma_scale)
    catalog = lorenz63.catalog_trajectory(int(M), seed=seed)
    hmm, _ = build_anfb(catalog, k, R, sigma_scale, successor_rule)
    rows = []
    for r in range(int(n_problems)):
        truth, observations = lorenz63.test_problem(VALIDATION_SEED + r, T=T, dt_obs=dt_obs, R=R)
        out = run_anfb(hmm, observations, beam, max_dropped_mass)
        row = error_anatomy(truth, observations, out["mean"], out["std"])
        row["seed"] = VALIDATION_SEED + r
        rows.append(row)
    return rows
