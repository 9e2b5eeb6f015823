"""Missing-data interpolation on real walking IMU data: the analog HMM paper's §3.2 and Table 2.

The paper (Lguensat et al., EUSIPCO 2016) fills gaps in 7 joint angles of CMU motion capture
walks; this experiment asks the same of a foot-mounted IMU, the signal the rest of indoorloc
works with. Data: the PyShoe / University of Toronto foot-mounted trials (``pyshoe_vicon/`` of
the project's shared PDR data, LORD MicroStrain 3DM-GX3-25 on the foot, 200 Hz, MATLAB files
with ``imu_data`` N x 6 = accelerometer [m/s^2] and gyroscope [rad/s], ``timestamps_all`` [s]).
Only the walking trials are used (median stride period above 1 s; the others are runs).

Pre-processing: each recording is low-passed by a moving average one output period long and
linearly interpolated to a common rate (50 Hz by default), then every channel is standardised
with the catalog's mean and standard deviation (so the noise variances and RMSEs below are in
standardised units, as in the paper).

- Catalog: every walking trial but the test one (the paper used 22 walks for the catalog and
  the 23rd for the test). Each trial is a separate trajectory: no pair straddles two trials.
- Test: a segment of ``n_samples`` (1000) of the test trial.
- Experiment A: 50 % of the test values erased at random, white noise of variance 0.5 on the
  rest. Experiment B: all channels erased over samples 100-300 and 600-700, noise 0.1.
- Methods: AnFB (``indoorloc.analog``: analog HMM with all 6 channels observed, NaN for erased
  values, observation covariance = the noise variance), AnEnKS and NNN
  (:mod:`indoorloc.experiments.analog_baselines`), and linear interpolation in time as a
  reference the paper does not have. Score: RMSE over the erased values only.

The package does not depend on the shared data folder: functions take the data root and raise
``ValueError`` when the recordings are not there.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from indoorloc.experiments import analog_baselines

#: Walking trials of pyshoe_vicon (median stride period 1.03-1.70 s); the seven others are runs
#: (0.72-0.80 s).
PYSHOE_WALKING_TRIALS = (
    "2017-11-22-11-22-03",
    "2017-11-22-11-23-25",
    "2017-11-22-11-26-05",
    "2017-11-22-11-27-30",
    "2017-11-22-11-30-14",
    "2017-11-22-11-36-45",
    "2017-11-22-11-39-47",
    "2017-11-22-11-44-47",
    "2017-11-22-11-49-03",
    "2017-11-22-11-50-42",
    "2017-11-22-11-52-02",
    "2017-12-15-17-59-19",
    "2017-12-15-18-00-13",
    "2018-02-09-11-29-43",
)
#: Test trial: a typical walk (0.9 m/s, 1.17 s stride) recorded on another day than most of
#: the catalog.
DEFAULT_TEST_TRIAL = "2017-12-15-17-59-19"
CHANNELS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z")
EXPERIMENTS = ("A", "B")
METHODS = ("anfb", "anenks", "nnn", "linear")
METHOD_NAMES = {"anfb": "AnFB", "anenks": "AnEnKS", "nnn": "NNN", "linear": "linear interpolation"}
#: Table 2 of the paper (CMU mocap, left leg, 7 joint angles): not the same data or units.
PAPER_RMSE = {
    ("NNN", "A"): 15.5247,
    ("AnEnKS", "A"): 1.7696,
    ("AnEnKS", "B"): 2.8151,
    ("AnFB", "A"): 1.7499,
    ("AnFB", "B"): 2.2576,
}


def pyshoe_folder(data_root: Union[str, Path]) -> Path:
    """The folder holding the PyShoe ``*_LLIO.mat`` files: ``data_root`` itself or its
    ``pyshoe_vicon`` subfolder. Raises ValueError when neither holds them."""
    root = Path(data_root)
    for folder in (root, root / "pyshoe_vicon", root / "pdr" / "pyshoe_vicon"):
        if folder.is_dir() and any(folder.glob("*_LLIO.mat")):
            return folder
    raise ValueError(
        f"indoorloc: argument 'data_root': no PyShoe recordings (*_LLIO.mat) in {root} or "
        f"{root / 'pyshoe_vicon'}; pass the folder of the pedestrian IMU data (e.g. .../data/pdr)"
    )


def load_pyshoe_trial(data_root: Union[str, Path], trial: str, rate_hz: float = 50.0) -> np.ndarray:
    """One PyShoe trial resampled to ``rate_hz``: (n, 6) accelerometer [m/s^2], gyroscope [rad/s].

    A centred moving average one output period long (anti-aliasing), then linear interpolation
    at t0 + i / rate_hz, i = 0 .. while inside the recording.
    """
    from scipy.io import loadmat

    if not rate_hz > 0:
        raise ValueError(f"indoorloc: argument 'rate_hz': expected > 0, got {rate_hz}")
    path = pyshoe_folder(data_root) / f"{trial}_LLIO.mat"
    if not path.is_file():
        raise ValueError(f"indoorloc: argument 'trial': no recording {path.name} in {path.parent}")
    mat = loadmat(str(path), variable_names=["imu_data", "timestamps_all"])
    imu = np.asarray(mat["imu_data"], dtype=float)
    t = np.asarray(mat["timestamps_all"], dtype=float).ravel()
    if imu.ndim != 2 or imu.shape[1] != 6 or t.size != imu.shape[0]:
        raise ValueError(f"indoorloc: {path.name}: expected imu_data (N, 6) and N timestamps")
    keep = np.concatenate([[True], np.diff(t) > 0])  # strictly increasing time for np.interp
    t, imu = t[keep], imu[keep]
    native_hz = 1.0 / np.median(np.diff(t))
    width = int(round(native_hz / rate_hz))
    if width > 1:
        kernel = np.ones(width) / width
        padded = np.pad(imu, ((width // 2, width - 1 - width // 2), (0, 0)), mode="edge")
        imu = np.stack([np.convolve(padded[:, c], kernel, mode="valid") for c in range(6)], axis=1)
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) * rate_hz)) + 1) / rate_hz
    return np.stack([np.interp(grid, t, imu[:, c]) for c in range(6)], axis=1)


@dataclass
class ImuSplit:
    """Standardised catalog trajectories and test segment, and how they were made."""

    catalog: List[np.ndarray]  # one (n_i, 6) standardised trajectory per catalog trial
    test: np.ndarray  # (n_samples, 6) standardised truth
    mean: np.ndarray  # (6,) catalog mean, physical units
    std: np.ndarray  # (6,) catalog standard deviation, physical units
    rate_hz: float
    catalog_trials: List[str]
    test_trial: str
    start_s: float
    channels: Tuple[str, ...] = CHANNELS

    @property
    def catalog_states(self) -> np.ndarray:
        """All catalog samples stacked, (M, 6)."""
        return np.concatenate(self.catalog, axis=0)


def prepare_split(
    data_root: Union[str, Path],
    test_trial: str = DEFAULT_TEST_TRIAL,
    catalog_trials: Optional[Sequence[str]] = None,
    rate_hz: float = 50.0,
    start_s: float = 3.0,
    n_samples: int = 1000,
) -> ImuSplit:
    """Catalog (every walking trial but ``test_trial`` by default) and the test segment
    [start_s, start_s + n_samples / rate_hz) of ``test_trial``, standardised with the catalog."""
    if catalog_trials is None:
        catalog_trials = [t for t in PYSHOE_WALKING_TRIALS if t != test_trial]
    catalog_trials = list(catalog_trials)
    if test_trial in catalog_trials:
        raise ValueError(f"indoorloc: the test trial {test_trial} is also in 'catalog_trials'")
    if not catalog_trials:
        raise ValueError("indoorloc: argument 'catalog_trials': at least one trial is needed")
    if int(n_samples) != n_samples or n_samples < 2:
        raise ValueError(f"indoorloc: argument 'n_samples': expected an integer >= 2, got {n_samples}")
    raw = [load_pyshoe_trial(data_root, trial, rate_hz) for trial in catalog_trials]
    stacked = np.concatenate(raw, axis=0)
    mean, std = stacked.mean(axis=0), stacked.std(axis=0)
    test_raw = load_pyshoe_trial(data_root, test_trial, rate_hz)
    first = int(round(start_s * rate_hz))
    if first < 0 or first + n_samples > test_raw.shape[0]:
        raise ValueError(
            f"indoorloc: trial {test_trial} has {test_raw.shape[0]} samples at {rate_hz} Hz: no segment of "
            f"{n_samples} samples from {start_s} s"
        )
    test = (test_raw[first : first + int(n_samples)] - mean) / std
    return ImuSplit(
        catalog=[(r - mean) / std for r in raw],
        test=test,
        mean=mean,
        std=std,
        rate_hz=float(rate_hz),
        catalog_trials=catalog_trials,
        test_trial=test_trial,
        start_s=float(start_s),
    )


def make_observations(
    truth: np.ndarray,
    experiment: str,
    seed: int = 0,
    fraction: float = 0.5,
    blocks: Sequence[Tuple[int, int]] = ((100, 300), (600, 700)),
    noise_var: Optional[float] = None,
) -> Tuple[np.ndarray, np.ndarray, float]:
    """Erase and perturb ``truth`` (T, d) as in experiment "A" or "B".

    A: ``fraction`` of the T d values erased, drawn without replacement; noise variance 0.5.
    B: every channel erased on the sample ranges ``blocks`` ([start, stop)); noise variance 0.1.
    The noise N(0, noise_var) is added to the values left, from ``default_rng([seed, 7])``.

    Returns
    -------
    observations : (T, d) array, NaN where erased.
    erased : (T, d) bool array.
    noise_var : float, the variance used.
    """
    truth = np.asarray(truth, dtype=float)
    T, d = truth.shape
    rng = np.random.default_rng([int(seed), 7])
    erased = np.zeros((T, d), dtype=bool)
    if experiment == "A":
        if not 0.0 <= fraction < 1.0:
            raise ValueError(f"indoorloc: argument 'fraction': expected in [0, 1), got {fraction}")
        erased.ravel()[rng.choice(T * d, size=int(round(fraction * T * d)), replace=False)] = True
        var = 0.5 if noise_var is None else float(noise_var)
    elif experiment == "B":
        for start, stop in blocks:
            if not 0 <= start < stop <= T:
                raise ValueError(f"indoorloc: argument 'blocks': [{start}, {stop}) is not inside [0, {T})")
            erased[start:stop] = True
        var = 0.1 if noise_var is None else float(noise_var)
    else:
        raise ValueError(f"indoorloc: argument 'experiment': expected 'A' or 'B', got {experiment!r}")
    if not var > 0:
        raise ValueError(f"indoorloc: argument 'noise_var': expected > 0, got {var}")
    observations = truth + np.sqrt(var) * rng.standard_normal((T, d))
    observations[erased] = np.nan
    return observations, erased, var


def linear_fill(observations: np.ndarray) -> np.ndarray:
    """Linear interpolation in time of each channel's missing values (held constant at the ends)."""
    obs = np.asarray(observations, dtype=float)
    out = obs.copy()
    t = np.arange(obs.shape[0])
    for c in range(obs.shape[1]):
        seen = np.isfinite(obs[:, c])
        out[:, c] = np.interp(t, t[seen], obs[seen, c]) if seen.any() else 0.0
    return out


def lagged_pairs(trajectories: Sequence[np.ndarray], lag: int = 1) -> Tuple[np.ndarray, np.ndarray]:
    """(analogs, successors) of lag-embedded states (x_t, x_{t-1}, ..., x_{t-lag+1}), the
    layout of ``indoorloc.analog.Catalog``; no pair straddles two trajectories."""
    if int(lag) != lag or lag < 1:
        raise ValueError(f"indoorloc: argument 'lag': expected an integer >= 1, got {lag}")
    analogs, successors = [], []
    for x in trajectories:
        if x.shape[0] < lag + 1:
            continue
        states = np.concatenate([x[lag - 1 - j : x.shape[0] - j] for j in range(lag)], axis=1)
        analogs.append(states[:-1])
        successors.append(states[1:])
    if not analogs:
        raise ValueError(f"indoorloc: no trajectory is longer than lag + 1 = {lag + 1} samples")
    return np.concatenate(analogs), np.concatenate(successors)


def erased_rmse(estimate: np.ndarray, truth: np.ndarray, erased: np.ndarray) -> float:
    """RMSE over the erased values only."""
    diff = (np.asarray(estimate) - np.asarray(truth))[erased]
    return float(np.sqrt(np.mean(diff**2))) if diff.size else float("nan")


@dataclass
class _Models:
    catalog: object = None
    forecaster: Optional[analog_baselines.AnalogForecaster] = None
    build_seconds: Dict[str, float] = field(default_factory=dict)


def run_imu_experiments(
    data_root: Union[str, Path, None] = None,
    experiments: Sequence[str] = EXPERIMENTS,
    methods: Sequence[str] = METHODS,
    split: Optional[ImuSplit] = None,
    k_anfb: int = 6,
    beam: Optional[int] = 500,
    lag: int = 3,
    n_members: int = 100,
    anenks_k: int = 50,
    seed: int = 0,
    blocks: Sequence[Tuple[int, int]] = ((100, 300), (600, 700)),
    **split_options,
) -> Dict[str, object]:
    """Experiments A and B: RMSE on the erased values for each method.

    Parameters
    ----------
    data_root : path
        Folder of the pedestrian IMU data (``.../data/pdr``) or its ``pyshoe_vicon`` subfolder;
        not needed when ``split`` is given.
    experiments : subset of ("A", "B")
    methods : subset of ("anfb", "anenks", "nnn", "linear")
    split : ImuSplit, optional
        A prepared split (else ``prepare_split(data_root, **split_options)``).
    k_anfb : int
        Successors per state of the analog HMM (the paper's cross-validated K = 6).
    beam : int or None
        N of the truncated AnFB (the paper's 500); None: exact.
    lag : int
        Time-lag embedding of both analog methods (eq. 6): states (x_t, ..., x_{t-lag+1}).
        3 by default: chosen by :func:`run_lag_selection` on the validation walk (mean AnFB RMSE
        over A, B and erasure seeds 0-2: lag 1 0.96, lag 2 0.82, lag 3 0.80), never on the test walk.
    n_members, anenks_k : AnEnKS ensemble size and number of analogs.
    seed : int
        Erasure masks and noise (``make_observations(..., seed)``) and the AnEnKS stream.
    blocks : [start, stop) sample ranges erased in experiment B.
    split_options : passed to :func:`prepare_split` (test_trial, catalog_trials, rate_hz,
        start_s, n_samples).

    Returns
    -------
    dict with "settings", "rows" (experiment, method, rmse, seconds) and "build_seconds".
    """
    from indoorloc.experiments.analog_lorenz63 import analog_bindings

    methods = [m.lower() for m in methods]
    unknown = [m for m in methods if m not in METHODS]
    if unknown or not methods:
        raise ValueError(f"indoorloc: argument 'methods': unknown {unknown}; choose among {list(METHODS)}")
    bad = [e for e in experiments if e not in EXPERIMENTS]
    if bad or not experiments:
        raise ValueError(f"indoorloc: argument 'experiments': unknown {bad}; choose among {list(EXPERIMENTS)}")
    if split is None:
        if data_root is None:
            raise ValueError("indoorloc: argument 'data_root': give the IMU data folder (or a prepared 'split')")
        split = prepare_split(data_root, **split_options)
    d = split.test.shape[1]
    current = list(range(d))  # the layout (x_t, x_{t-1}, ...) puts the current sample first

    models = _Models()
    if "anfb" in methods:
        analog = analog_bindings()
        start = time.perf_counter()
        models.catalog = analog.Catalog([np.ascontiguousarray(x) for x in split.catalog], lag=int(lag), stride=1)
        models.build_seconds["anfb_catalog"] = time.perf_counter() - start
    if "anenks" in methods:
        start = time.perf_counter()
        analogs, successors = lagged_pairs(split.catalog, lag)
        models.forecaster = analog_baselines.AnalogForecaster(analogs, successors, k=anenks_k)
        models.build_seconds["anenks_kdtree"] = time.perf_counter() - start
    catalog_states = split.catalog_states

    rows = []
    for experiment in experiments:
        observations, erased, var = make_observations(split.test, experiment, seed=seed, blocks=blocks)
        hmm = None
        if "anfb" in methods:
            start = time.perf_counter()
            hmm = analog.AnalogHMM(models.catalog, k=int(k_anfb), observed=current, R=var * np.eye(d))
            models.build_seconds[f"anfb_hmm_{experiment}"] = time.perf_counter() - start
        for method in methods:
            start = time.perf_counter()
            extra = {}
            if method == "anfb":
                out = hmm.smooth(observations, beam=None if beam is None else int(beam))
                estimate = np.asarray(out["mean"])[:, :d]
                if "dropped_mass" in out:
                    extra["max_dropped_mass"] = float(np.max(out["dropped_mass"]))
            elif method == "anenks":
                estimate = analog_baselines.anenks(
                    observations, None, None, observed=current, R=var, n_members=n_members, seed=seed,
                    forecaster=models.forecaster,
                )[:, :d]
            elif method == "nnn":
                estimate = analog_baselines.nearest_neighbour_fill(observations, catalog_states)
            else:
                estimate = linear_fill(observations)
            seconds = time.perf_counter() - start
            name = METHOD_NAMES[method]
            rows.append(
                {
                    "experiment": experiment,
                    "method": name,
                    "rmse": erased_rmse(estimate, split.test, erased),
                    "rmse_per_channel": [
                        erased_rmse(estimate[:, c], split.test[:, c], erased[:, c]) for c in range(d)
                    ],
                    "seconds": seconds,
                    "noise_var": var,
                    "erased_fraction": float(erased.mean()),
                    "paper_rmse": PAPER_RMSE.get((name, experiment)),
                    **extra,
                }
            )
    return {
        "title": "Missing IMU values of a walk (paper 001 §3.2 on a foot IMU instead of mocap)",
        "settings": {
            "test_trial": split.test_trial, "catalog_trials": split.catalog_trials, "rate_hz": split.rate_hz,
            "start_s": split.start_s, "n_samples": int(split.test.shape[0]),
            "catalog_states": int(catalog_states.shape[0]), "k_anfb": int(k_anfb),
            "beam": "exact" if beam is None else int(beam), "lag": int(lag), "n_members": int(n_members),
            "anenks_k": int(anenks_k), "seed": int(seed), "blocks": [list(b) for b in blocks],
            "experiments": list(experiments), "methods": methods,
        },
        "rows": rows,
        "build_seconds": models.build_seconds,
    }


def markdown_table(result: Dict[str, object]) -> str:
    """The rows of :func:`run_imu_experiments` as a markdown table (standardised units)."""
    s = result["settings"]
    lines = [
        f"Test: {s['n_samples']} samples of {s['test_trial']} at {s['rate_hz']:g} Hz; catalog "
        f"{len(s['catalog_trials'])} walks, {s['catalog_states']} samples; lag {s['lag']}, AnFB K = "
        f"{s['k_anfb']}, N = {s['beam']}.",
        "",
        "| experiment | method | RMSE on erased values (standardised) | time [s] | paper (mocap, other units) |",
        "|---|---|---|---|---|",
    ]
    for row in result["rows"]:
        paper = "-" if row["paper_rmse"] is None else f"{row['paper_rmse']:.4g}"
        lines.append(f"| {row['experiment']} | {row['method']} | {row['rmse']:.3f} | {row['seconds']:.2f} | {paper} |")
    return "\n".join(lines)


#: Validation walk for the choice of the lag (never the test walk; the longest other walk).
VALIDATION_TRIAL = "2018-02-09-11-29-43"


def run_lag_selection(
    data_root: Union[str, Path],
    lags: Sequence[int] = (1, 2, 3),
    validation_trial: str = VALIDATION_TRIAL,
    test_trial: str = DEFAULT_TEST_TRIAL,
    methods: Sequence[str] = ("anfb", "anenks"),
    seeds: Sequence[int] = (0, 1, 2),
    **options,
) -> Dict[str, object]:
    """Choose the lag embedding of the analog methods on a validation walk, not on the test walk.

    The validation split uses ``validation_trial`` as its test segment and every walking trial
    but it and ``test_trial`` as catalog (the test walk is never seen). For every lag and erasure
    seed, experiments A and B are run; the lag with the lowest mean AnFB RMSE (over A, B and the
    seeds) is returned with the whole table.

    Returns
    -------
    dict with "best_lag", "validation_trial", "rows" (lag, method, experiment, seed, rmse) and
    "mean_rmse" {lag: mean AnFB RMSE}.
    """
    if validation_trial == test_trial:
        raise ValueError("indoorloc: argument 'validation_trial': must differ from the test trial")
    catalog = [t for t in PYSHOE_WALKING_TRIALS if t not in (validation_trial, test_trial)]
    split = prepare_split(data_root, test_trial=validation_trial, catalog_trials=catalog)
    rows = []
    for lag in lags:
        for seed in seeds:
            result = run_imu_experiments(split=split, methods=methods, lag=int(lag), seed=int(seed), **options)
            for row in result["rows"]:
                rows.append({"lag": int(lag), "seed": int(seed), "method": row["method"],
                             "experiment": row["experiment"], "rmse": row["rmse"]})
    mean_rmse = {
        int(lag): float(np.mean([r["rmse"] for r in rows if r["lag"] == lag and r["method"] == "AnFB"]))
        for lag in lags
    }
    best = min(mean_rmse, key=mean_rmse.get)
    return {"best_lag": best, "validation_trial": validation_trial, "rows": rows, "mean_rmse": mean_rmse}
