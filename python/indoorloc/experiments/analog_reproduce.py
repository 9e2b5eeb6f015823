"""Paper 001 (analog HMM) in ``indoorloc reproduce``: Table 1, Fig. 2, the AnDA-style sequence and
the IMU missing-data experiment, each cell with one value per seeded realisation.

Table 1 (Lorenz-63, x observed every 40 steps with noise variance 2, T = 1000): realisation r is
the test problem ``lorenz63.test_problem(seed + r)`` (r = 0 .. runs - 1, 50 at full size); the
catalogs are ``catalog_trajectory(M, seed)`` for M = 10^4 and 10^5 (the 10^4 one is the start of
the 10^5 one); EnKS and AnEnKS are seeded with seed + r. The AnFB rows:

- "N = 1000 fixed, uniform prior": the paper's §2.3 truncation as written (keep the N most
  likely filtering states at every step), with a uniform P(X_1) (the paper gives none);
- "N = 1000 fixed, AnDA prior": the same truncation with P(X_1) ∝ N(s_j; x_1, 0.1 I) around the
  true first state, the start AnDA's published smoothers use (``xb = xt[0]``, ``B = 0.1 I``);
- "N = 1000 / 3000, mass-adaptive": our default, uniform prior, the beam widened where the cut
  would drop more than 10^-3 of the filtering mass (docs/analog.md).

Every AnFB constant was chosen on validation problems ``test_problem(10000 + r)``, never on the
scored seeds: the kernels ``VALIDATED_KERNELS`` (K, width) and the tolerance 10^-3. The AnDA
prior variance 0.1 is AnDA's own B, not tuned.

:func:`reproduce_tables` is what ``indoorloc reproduce`` calls; ``quick=True`` shrinks every size
for tests (the default is the full size). With ``ctx.scheduler`` the realisations run as
``indoorloc.sweep`` tasks (:func:`table1_task`), each seeded by its realisation index only, so
the tables are identical to the in-process run.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field
from typing import Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from indoorloc.experiments import analog_baselines
from indoorloc.experiments import analog_lorenz63 as al
from indoorloc.experiments.reproduce_cells import Cell, ReproduceContext, Table
from indoorloc.simulate import lorenz63, lorenz63_anda

PAPER = "001"
#: Realisations per Table 1 cell at full size (at least 50, so that a cell's spread is itself stable).
FULL_RUNS = 50
#: IMU erasure seeds at full size (each seed draws new masks and noise on the same walk).
FULL_IMU_RUNS = 10
PAPER_BEAM = al.PAPER_BEAM
LORENZ63 = al.PAPER_SETTING  #: the paper's test problem (T, dt_obs, R) and ensemble sizes, written once
#: The paper's execution times τ of Table 1, in seconds (their machine, their code).
PAPER_SECONDS = {("EnKS", None): 7200.0, ("AnEnKS", 10**4): 780.0, ("AnEnKS", 10**5): 4680.0,
                 ("AnFB", 10**4): 480.0, ("AnFB", 10**5): 840.0}


@dataclass(frozen=True)
class AnfbVariant:
    """One AnFB row of Table 1: N, mass-adaptive tolerance (1 = fixed N), prior at t = 1."""

    label: str
    beam: int
    max_dropped_mass: float
    prior: str  # "uniform" or "anda"


ANFB_VARIANTS = (
    AnfbVariant("AnFB, N = 1000 fixed (paper §2.3), uniform prior", 1000, 1.0, "uniform"),
    AnfbVariant("AnFB, N = 1000 fixed (paper §2.3), AnDA prior N(x_1, 0.1 I)", 1000, 1.0, "anda"),
    AnfbVariant("AnFB, N = 1000, mass-adaptive 1e-3", 1000, al.DEFAULT_MAX_DROPPED_MASS, "uniform"),
    AnfbVariant("AnFB, N = 3000, mass-adaptive 1e-3 (our default)", 3000, al.DEFAULT_MAX_DROPPED_MASS, "uniform"),
)
DEFAULT_VARIANT = ANFB_VARIANTS[3]
PAPER_VARIANT = ANFB_VARIANTS[0]


@dataclass
class Scale:
    """Sizes of the section: the paper's (``full``) or small ones for tests (``quick``)."""

    catalog_sizes: Tuple[int, int] = (10**4, 10**5)
    T: int = LORENZ63.T
    n_members: int = LORENZ63.n_members
    anda_nb_loop_train: Tuple[int, int] = (100, 1000)  # AnDA catalog runs [time units] for 10^4, 10^5
    imu_samples: int = 1000
    imu_catalog_trials: Optional[int] = None  # None: every walk but the test walk
    full_runs: int = FULL_RUNS
    full_imu_runs: int = FULL_IMU_RUNS
    kernels: Dict[int, Tuple[int, float]] = field(default_factory=lambda: dict(al.VALIDATED_KERNELS))

    @staticmethod
    def quick() -> "Scale":
        return Scale(catalog_sizes=(2000, 5000), T=200, n_members=20, anda_nb_loop_train=(20, 50), imu_samples=200,
                     imu_catalog_trials=2, full_runs=2, full_imu_runs=2,
                     kernels={2000: (10, 0.5), 5000: (10, 0.5)})


def _size_label(M: Optional[int]) -> str:
    return "-" if M is None else f"M = {al._format_size(M)}"


# ---------------------------------------------------------------------------------------------
# Table 1: one realisation, all rows
# ---------------------------------------------------------------------------------------------

_MODELS: Dict[tuple, object] = {}  # per process: (M, K, width, catalog seed) -> (catalog, hmm, forecaster)


def _models(M: int, kernel: Tuple[int, float], seed: int):
    """Catalog states, analog HMM and AnEnKS forecaster of catalog size M (built once per process)."""
    key = (int(M), int(kernel[0]), float(kernel[1]), int(seed))
    if key not in _MODELS:
        analog = al.analog_bindings()
        traj = lorenz63.catalog_trajectory(int(M), seed=int(seed))
        catalog = analog.Catalog([np.ascontiguousarray(traj)], lag=1, stride=1)
        hmm = analog.AnalogHMM(catalog, k=int(kernel[0]), observed=[0], R=np.array([[LORENZ63.R]]),
                               sigma_scale=float(kernel[1]))
        forecaster = analog_baselines.AnalogForecaster(traj[:-1], traj[1:], k=LORENZ63.anenks_k)
        _MODELS[key] = (np.asarray(catalog.states), hmm, forecaster)
    return _MODELS[key]


def _smooth(hmm, states: np.ndarray, truth: np.ndarray, observations: np.ndarray, v: AnfbVariant) -> np.ndarray:
    """Posterior mean (T, 3) of one AnFB variant."""
    kwargs = dict(beam=int(v.beam), max_dropped_mass=float(v.max_dropped_mass))
    if v.prior == "anda":
        kwargs["initial"] = lorenz63_anda.anda_prior_weights(states, truth[0])
    return np.asarray(hmm.smooth(observations, **kwargs)["mean"])[:, :3]


def table1_realisation(r: int, settings: Mapping[str, object]) -> Dict[str, object]:
    """Every Table 1 row on realisation r: RMSE, per-variable RMSE (3,) and seconds per row key.

    settings: "seed", "catalog_sizes", "kernels" {M: (K, width)}, "T", "n_members" (see
    :func:`_settings`). Returns {"r", "seed", "rows": {key: {"rmse", "rmse_xyz", "seconds"}}}.
    """
    seed = int(settings["seed"])
    truth, obs = lorenz63.test_problem(seed + int(r), T=int(settings["T"]), dt_obs=LORENZ63.dt_obs, R=LORENZ63.R)
    rows: Dict[str, Dict[str, object]] = {}

    def record(key: str, estimate: np.ndarray, seconds: float) -> None:
        err = estimate - truth
        rows[key] = {"rmse": al.rmse(estimate, truth), "rmse_xyz": np.sqrt((err**2).mean(axis=0)).tolist(),
                     "seconds": seconds}

    start = time.perf_counter()
    est = analog_baselines.enks_lorenz63(obs, n_members=int(settings["n_members"]), seed=seed + int(r), R=LORENZ63.R)
    record("EnKS|-", est, time.perf_counter() - start)
    for M in settings["catalog_sizes"]:
        states, hmm, forecaster = _models(int(M), tuple(settings["kernels"][str(M)]), seed)
        start = time.perf_counter()
        est = analog_baselines.anenks(obs, None, None, observed=[0], R=LORENZ63.R, n_members=int(settings["n_members"]),
                                      seed=seed + int(r), forecaster=forecaster)
        record(f"AnEnKS|{M}", est, time.perf_counter() - start)
        for v in ANFB_VARIANTS:
            start = time.perf_counter()
            est = _smooth(hmm, states, truth, obs, v)
            record(f"{v.label}|{M}", est, time.perf_counter() - start)
    return {"r": int(r), "seed": seed + int(r), "rows": rows}


def table1_task(params: Mapping[str, object], seed: int, settings: Mapping[str, object]) -> Dict[str, object]:
    """``indoorloc.sweep`` task: :func:`table1_realisation` for ``params["r"]`` (the sweep's own
    seed is not used, so the result equals the in-process run's)."""
    return table1_realisation(int(params["r"]), settings)


def _settings(scale: Scale, seed: int) -> Dict[str, object]:
    return {"seed": int(seed), "catalog_sizes": [int(m) for m in scale.catalog_sizes], "T": int(scale.T),
            "n_members": int(scale.n_members),
            "kernels": {str(m): list(scale.kernels.get(m, (al.DEFAULT_K, al.DEFAULT_SIGMA_SCALE)))
                        for m in scale.catalog_sizes}}


def run_realisations(ctx: ReproduceContext, runs: int, settings: Mapping[str, object]) -> List[Dict[str, object]]:
    """Realisations 0 .. runs - 1, in process or through ``indoorloc.sweep`` (``ctx.scheduler``)."""
    if ctx.scheduler is not None:
        from indoorloc import sweep

        res = sweep.run_sweep(table1_task, {"r": list(range(int(runs)))}, scheduler=ctx.scheduler,
                              shared={"settings": dict(settings)})
        if res.failed:
            raise RuntimeError(f"indoorloc: analog realisation {res.failed[0]['params']['r']} failed: "
                               f"{res.failed[0]['error']}")
        return sorted(({"r": row["r"], "seed": row["seed"], "rows": row["rows"]} for row in res.rows),
                      key=lambda p: p["r"])
    out = []
    start = time.perf_counter()
    for r in range(int(runs)):
        out.append(table1_realisation(r, settings))
        if (r + 1) % 10 == 0 and r + 1 < runs:
            ctx.log(f"analog Table 1: {r + 1}/{runs} realisations ({time.perf_counter() - start:.0f} s)")
    return out


def _paper_value(method: str, M: Optional[int], variant: Optional[AnfbVariant] = None) -> Optional[float]:
    if method == "AnFB":
        return al.PAPER_RMSE.get(("AnFB", M))
    return al.PAPER_RMSE.get((method, M))


def table1_tables(parts: Sequence[Dict[str, object]], scale: Scale, seed: int) -> List[Table]:
    """Table 1 (RMSE), its execution times, and the Fig. 2 per-variable cells from the realisations."""
    seeds = [int(p["seed"]) for p in parts]

    def values(key: str, field_name: str = "rmse", index: Optional[int] = None) -> List[float]:
        vals = [p["rows"][key][field_name] for p in parts]
        return [float(v[index]) if index is not None else float(v) for v in vals]

    rmse_cells, time_cells, fig_cells = [], [], []
    rmse_cells.append(Cell("EnKS (Lorenz-63 equations, 100 members)", "-", values("EnKS|-"), seeds,
                           paper=al.PAPER_RMSE[("EnKS", None)]))
    time_cells.append(Cell("EnKS", "-", values("EnKS|-", "seconds"), seeds, paper=PAPER_SECONDS[("EnKS", None)],
                           unit="s"))
    for M in scale.catalog_sizes:
        col = _size_label(M)
        paper_m = M if M in (10**4, 10**5) else None
        rmse_cells.append(Cell("AnEnKS (100 members)", col, values(f"AnEnKS|{M}"), seeds,
                               paper=al.PAPER_RMSE.get(("AnEnKS", paper_m))))
        time_cells.append(Cell("AnEnKS", col, values(f"AnEnKS|{M}", "seconds"), seeds,
                               paper=PAPER_SECONDS.get(("AnEnKS", paper_m)), unit="s"))
        for v in ANFB_VARIANTS:
            note = "" if v.beam == PAPER_BEAM else "paper's figure is for N = 1000"
            rmse_cells.append(Cell(v.label, col, values(f"{v.label}|{M}"), seeds,
                                   paper=al.PAPER_RMSE.get(("AnFB", paper_m)), note=note))
            time_cells.append(Cell(v.label, col, values(f"{v.label}|{M}", "seconds"), seeds,
                                   paper=PAPER_SECONDS.get(("AnFB", paper_m)) if v is PAPER_VARIANT else None,
                                   unit="s", note="smoothing only (the HMM is built once per catalog)"))
    M = scale.catalog_sizes[-1]
    for key, label in ((f"{DEFAULT_VARIANT.label}|{M}", DEFAULT_VARIANT.label),
                       (f"{PAPER_VARIANT.label}|{M}", PAPER_VARIANT.label), (f"AnEnKS|{M}", "AnEnKS")):
        for i, name in enumerate("xyz"):
            fig_cells.append(Cell(f"{label}, {_size_label(M)}", f"RMSE of {name}", values(key, "rmse_xyz", i), seeds))
    kernels = ", ".join(f"M = {al._format_size(m)}: K = {scale.kernels.get(m, (al.DEFAULT_K,))[0]}, width x"
                        f"{scale.kernels.get(m, (0, al.DEFAULT_SIGMA_SCALE))[1]}" for m in scale.catalog_sizes)
    setup = (
        f"Lorenz-63 (RK4, dt = 0.01), x observed every 40 steps with noise variance R = 2, T = {scale.T}; "
        f"{len(parts)} realisations: test problem seeds {seeds[0]}..{seeds[-1]} (lorenz63.test_problem(seed), "
        f"independent streams), EnKS/AnEnKS seeded alike; catalogs catalog_trajectory(M, seed={seed}) of "
        f"M = {', '.join(al._format_size(m) for m in scale.catalog_sizes)} consecutive states. EnKS/AnEnKS: "
        f"{scale.n_members} members, climatological start; AnEnKS local linear regression on 50 analogs. "
        f"AnFB kernel (eq. 4, width = factor x the paper's adaptive σ): {kernels}; chosen by "
        "`indoorloc analog lorenz63-tune` on validation problems seeds 10000-10005 (disjoint from the test "
        "seeds); mass-adaptive tolerance 10^-3 chosen on validation seeds 10000-10003. 'Fixed' rows are the "
        "paper's truncation (keep the N most likely filtering states at every step); 'AnDA prior' starts "
        "from P(X_1) ∝ N(s_j; x_1, 0.1 I) around the true first state as AnDA's published smoothers do "
        "(B = 0.1 I, not tuned). RMSE over the 3 variables and all T steps. Paper: one realisation, N = 1000."
    )
    tables = [
        Table(PAPER, "Table 1", "Lorenz-63 from noisy x every 40 steps: RMSE", rmse_cells, setup),
        Table(PAPER, "Table 1 (time)", "Lorenz-63: execution time per realisation", time_cells,
              setup + " Times: seconds per realisation on this machine (single thread, smoothing only for the "
              "AnFB; HMM build once per catalog); the paper's τ are its totals on its machine."),
        Table(PAPER, "Fig. 2", "Lorenz-63 reconstruction: per-variable RMSE (the figure shows one realisation)",
              fig_cells, setup + " Per-variable RMSE over the T steps at the largest catalog."),
    ]
    return tables


def start_study(M: int, n_problems: int = 20, seed: int = 0, beam: int = PAPER_BEAM) -> Dict[str, object]:
    """Why a fixed N loses the truth at the start, on validation problems only (seeds 10000 + r).

    For each problem: the RMSE of every AnFB variant of :data:`ANFB_VARIANTS`, and the first
    step's cut of the fixed-N filter under a uniform prior: with one scalar observation y_1 of x,
    the N kept states are the N with x nearest y_1 (a slab of half-width ``slab_half_width``);
    ``kept_distance`` is the distance from the true x_1 to the nearest kept state, against
    ``catalog_distance`` to the nearest catalog state and ``obs_error`` = |y_1 - x_1|.

    Returns
    -------
    dict: "seeds", "rmse" {variant label: [per problem]}, "slab_half_width", "kept_distance",
    "catalog_distance", "obs_error" (lists per problem).
    """
    kernel = al.VALIDATED_KERNELS.get(int(M), (al.DEFAULT_K, al.DEFAULT_SIGMA_SCALE))
    states, hmm, _ = _models(int(M), kernel, seed)
    out: Dict[str, object] = {"seeds": [], "rmse": {v.label: [] for v in ANFB_VARIANTS}, "slab_half_width": [],
                              "kept_distance": [], "catalog_distance": [], "obs_error": []}
    for r in range(int(n_problems)):
        truth, obs = lorenz63.test_problem(al.VALIDATION_SEED + r, T=LORENZ63.T, dt_obs=LORENZ63.dt_obs, R=LORENZ63.R)
        out["seeds"].append(al.VALIDATION_SEED + r)
        for v in ANFB_VARIANTS:
            out["rmse"][v.label].append(al.rmse(_smooth(hmm, states, truth, obs, v), truth))
        d = np.abs(states[:, 0] - obs[0, 0])
        kept = np.argsort(d, kind="stable")[: int(beam)]
        out["slab_half_width"].append(float(d[kept].max()))
        out["kept_distance"].append(float(np.sqrt(((states[kept] - truth[0]) ** 2).sum(axis=1)).min()))
        out["catalog_distance"].append(float(np.sqrt(((states - truth[0]) ** 2).sum(axis=1)).min()))
        out["obs_error"].append(float(abs(obs[0, 0] - truth[0, 0])))
    return out


# ---------------------------------------------------------------------------------------------
# The AnDA-style sequence (named case) and the figure
# ---------------------------------------------------------------------------------------------

def anda_case(scale: Scale, seed: int) -> Tuple[Table, Dict[str, object]]:
    """AnFB, AnEnKS and EnKS on the single sequence AnDA's script generates (seed 1, dt_obs = 40),
    with AnDA's own catalog (the continuation of the test run) and with ours. Returns the table and
    the data of the largest catalog for the figure."""
    analog = al.analog_bindings()
    cells = []
    example: Dict[str, object] = {}
    for M, loops in zip(scale.catalog_sizes, scale.anda_nb_loop_train):
        problem = lorenz63_anda.anda_problem(nb_loop_test=scale.T // 100, nb_loop_train=int(loops), dt_obs=40)
        truth, obs = problem.truth, problem.observations
        # The ensemble smoothers from the climatology (as in Table 1) and from AnDA's start N(x_1, 0.1 I).
        starts = {"climatological start": {},
                  "AnDA start": {"initial_mean": truth[0],
                                 "initial_cov": lorenz63_anda.ANDA_PRIOR_VARIANCE * np.eye(3)}}
        kernel = scale.kernels.get(M, (al.DEFAULT_K, al.DEFAULT_SIGMA_SCALE))
        catalogs = {"AnDA catalog": problem.catalog, "our catalog": lorenz63.catalog_trajectory(int(M), seed=seed)}
        for cat_name, traj in catalogs.items():
            col = f"{_size_label(M)}, {cat_name} ({traj.shape[0] - 1} pairs)"
            paper_m = M if M in (10**4, 10**5) else None
            catalog = analog.Catalog([np.ascontiguousarray(traj)], lag=1, stride=1)
            hmm = analog.AnalogHMM(catalog, k=int(kernel[0]), observed=[0], R=np.array([[LORENZ63.R]]),
                                   sigma_scale=float(kernel[1]))
            states = np.asarray(catalog.states)
            for v in ANFB_VARIANTS:
                est = _smooth(hmm, states, truth, obs, v)
                cells.append(Cell(v.label, col, [al.rmse(est, truth)], [lorenz63_anda.ANDA_SEED],
                                  paper=al.PAPER_RMSE.get(("AnFB", paper_m))))
                if cat_name == "AnDA catalog" and v is ANFB_VARIANTS[1]:
                    example["AnFB (N = 1000 fixed, AnDA prior)"] = est
            forecaster = analog_baselines.AnalogForecaster(traj[:-1], traj[1:], k=LORENZ63.anenks_k)
            for start_name, start in starts.items():
                est = analog_baselines.anenks(obs, None, None, observed=[0], R=LORENZ63.R, n_members=scale.n_members,
                                              seed=lorenz63_anda.ANDA_SEED, forecaster=forecaster, **start)
                cells.append(Cell(f"AnEnKS (100 members), {start_name}", col, [al.rmse(est, truth)],
                                  [lorenz63_anda.ANDA_SEED], paper=al.PAPER_RMSE.get(("AnEnKS", paper_m))))
                if cat_name == "AnDA catalog" and start_name == "AnDA start":
                    example["AnEnKS"] = est
        example.update(truth=truth, observations=obs)
    # The test sequence does not depend on the catalog length (it is drawn first).
    for start_name, start in starts.items():
        est = analog_baselines.enks_lorenz63(obs, n_members=scale.n_members, seed=lorenz63_anda.ANDA_SEED, R=LORENZ63.R,
                                             **start)
        cells.append(Cell(f"EnKS (Lorenz-63 equations, 100 members), {start_name}", "-", [al.rmse(est, truth)],
                          [lorenz63_anda.ANDA_SEED], paper=al.PAPER_RMSE[("EnKS", None)]))
    setup = (
        "The single Lorenz-63 data set of AnDA's published generator (ptandeo/AnDA, AnDA_generate_data), "
        "rewritten in indoorloc.simulate.lorenz63_anda: legacy numpy RandomState(1) (the same stream as "
        "their np.random.seed(1)), x0 = (8, 0, 30), 5 time units of spin-up, scipy odeint (LSODA, default "
        f"tolerances) on a 0.01 grid, T = {scale.T}, observation noise drawn for all 3 components and x "
        "kept every dt_obs = 40 steps; AnDA's catalog continues the test run for nb_loop_train = "
        f"{', '.join(str(n) for n in scale.anda_nb_loop_train)} time units (M - 1 pairs). 'our catalog' is "
        f"catalog_trajectory(M, seed={seed}) of Table 1. Kernels and tolerance as in Table 1. EnKS and AnEnKS "
        "from the climatology (as in Table 1) and from AnDA's start N(x_1, 0.1 I). One realisation per cell "
        "(seed 1), like the paper's. Fig. 2: the AnFB (N = 1000 fixed, AnDA prior) and the AnEnKS (AnDA "
        "start) on this sequence with AnDA's catalog at the largest M."
    )
    # The figure uses the first dict entry order: AnFB first.
    example["estimates"] = {k: example.pop(k) for k in list(example) if k not in ("truth", "observations")}
    return Table(PAPER, "AnDA-style sequence", "Lorenz-63 on AnDA's published test sequence (seed 1, dt_obs = 40)",
                 cells, setup), example


# ---------------------------------------------------------------------------------------------
# IMU missing data
# ---------------------------------------------------------------------------------------------

def imu_table(ctx: ReproduceContext, scale: Scale, runs: int) -> Table:
    """Experiments A and B on the walking IMU data, one value per erasure seed."""
    from indoorloc.experiments import analog_imu
    from indoorloc.registry import default_pdr_root

    root = default_pdr_root()
    if not root.is_dir():
        raise FileNotFoundError(f"indoorloc: the IMU experiment needs the PyShoe recordings, not found at {root} "
                                "(it is looked up beside $INDOORLOC_WIFI_DATA or shared/data/wifi)")
    options = {"n_samples": int(scale.imu_samples)}
    if scale.imu_catalog_trials is not None:
        trials = [t for t in analog_imu.PYSHOE_WALKING_TRIALS if t != analog_imu.DEFAULT_TEST_TRIAL]
        options["catalog_trials"] = tuple(trials[: int(scale.imu_catalog_trials)])
    split = analog_imu.prepare_split(root, **options)
    seeds = [int(ctx.seed) + r for r in range(int(runs))]
    per: Dict[Tuple[str, str], List[float]] = {}
    for s in seeds:
        n = int(scale.imu_samples)  # experiment B's blocks at the default's fractions (100-300, 600-700 of 1000)
        result = analog_imu.run_imu_experiments(split=split, seed=s,
                                                blocks=((n // 10, 3 * n // 10), (6 * n // 10, 7 * n // 10)))
        for row in result["rows"]:
            per.setdefault((row["experiment"], row["method"]), []).append(float(row["rmse"]))
    cells = []
    for (experiment, method), vals in per.items():
        paper = analog_imu.PAPER_RMSE.get((method, experiment))
        note = f"paper (CMU mocap, other data and units): {paper}" if paper is not None else ""
        cells.append(Cell(method, f"experiment {experiment}", vals, seeds, note=note))
    for experiment in analog_imu.EXPERIMENTS:
        a, b = per.get((experiment, "AnFB")), per.get((experiment, "AnEnKS"))
        pa, pb = analog_imu.PAPER_RMSE.get(("AnFB", experiment)), analog_imu.PAPER_RMSE.get(("AnEnKS", experiment))
        if a and b:
            cells.append(Cell("AnFB / AnEnKS RMSE ratio", f"experiment {experiment}",
                              [x / y for x, y in zip(a, b)], seeds, paper=None if pa is None else pa / pb,
                              note="unit-free, so comparable with the paper's ratio on mocap data"))
    setup = (
        f"Paper §3.2 (CMU mocap, 7 joint angles) is replaced by walking foot-IMU recordings (PyShoe, 6 channels, "
        f"standardised, 50 Hz): test {scale.imu_samples} samples of walk {split.test_trial}, catalog "
        f"{len(split.catalog_trials)} other walks. A: 50 % of the values erased, noise variance 0.5; B: blocks "
        "erased, noise 0.1. RMSE on the erased values. AnFB K = 6 and N = 500 (the paper's), lag 3 chosen "
        "on a validation walk (2018-02-09-11-29-43, never the test walk). Erasure/noise seeds "
        f"{seeds[0]}..{seeds[-1]}. The RMSE cells have no paper figure (other data, other units); the "
        "AnFB/AnEnKS ratio is compared with the paper's."
    )
    return Table(PAPER, "IMU missing data (Table 2 analog)", "Missing values of a walk: RMSE on the erased values",
                 cells, setup)


# ---------------------------------------------------------------------------------------------
# Entry points
# ---------------------------------------------------------------------------------------------

#: Wall-clock seconds per Table 1 realisation (all rows, both catalogs) and per IMU erasure seed,
#: and the one-off AnDA-style case, measured in the full run of 2026-11-25 on the 2-core machine
#: shared with other jobs (load average 6-11): Table 1 1209 s for 50 realisations, the AnDA case
#: and Fig. 2 53 s; the IMU part is dominated by the AnEnKS kd-tree queries in 18-D (lag 3).
SECONDS_PER_REALISATION = 24.0
SECONDS_PER_IMU_SEED = 180.0
SECONDS_ONE_OFF = 60.0


def expected_seconds(runs: Optional[int]) -> float:
    """Honest wall-clock estimate [s] of the full-size section on 2 cores for ``runs`` realisations
    (None: the full size, 50)."""
    n = FULL_RUNS if runs is None else int(runs)
    n_imu = FULL_IMU_RUNS if runs is None else min(int(runs), FULL_IMU_RUNS)
    return SECONDS_ONE_OFF + SECONDS_PER_REALISATION * n + SECONDS_PER_IMU_SEED * n_imu


def reproduce_tables(ctx: ReproduceContext, quick: bool = False) -> List[Table]:
    """Paper 001's tables with the spread of our runs.

    Parameters
    ----------
    ctx : ReproduceContext
        ``runs`` realisations per cell (None: 50 for Table 1, 10 IMU erasure seeds), ``seed`` the
        base seed, ``scheduler`` (None: in process), ``log`` for the progress lines; the figure is
        written to ``ctx.figure_path("analog_fig2")``.
    quick : bool
        (or ``ctx.quick``) Small sizes for tests (catalogs 2000 / 5000, T = 200, 20 members, short IMU split); the
        default False is the paper's size.

    Returns
    -------
    list of Table: "Table 1", "Table 1 (time)", "Fig. 2", "AnDA-style sequence",
    "IMU missing data (Table 2 analog)".
    """
    from indoorloc import plots

    # ctx.quick (added to ReproduceContext on main) and the argument both select the small sizes.
    quick = bool(quick or getattr(ctx, "quick", False))
    scale = Scale.quick() if quick else Scale()
    runs = ctx.runs_or(scale.full_runs)
    if runs < 1:
        raise ValueError(f"indoorloc: argument 'runs': expected >= 1, got {runs}")
    al.analog_bindings()
    start = time.perf_counter()
    settings = _settings(scale, ctx.seed)
    parts = run_realisations(ctx, runs, settings)
    tables = table1_tables(parts, scale, ctx.seed)
    ctx.log(f"analog Table 1: {runs} realisations, M = {settings['catalog_sizes']} ({time.perf_counter() - start:.0f} s)")

    start = time.perf_counter()
    anda, example = anda_case(scale, ctx.seed)
    path = plots.analog_lorenz(example, ctx.figure_path("analog_fig2"))
    tables[2].figures.append(str(path))
    anda.figures.append(str(path))
    tables.append(anda)
    ctx.log(f"analog AnDA-style sequence and Fig. 2 ({time.perf_counter() - start:.0f} s)")

    start = time.perf_counter()
    imu_runs = min(runs, scale.full_imu_runs) if ctx.runs is not None else scale.full_imu_runs
    from indoorloc.registry import default_pdr_root

    if default_pdr_root().is_dir():
        tables.append(imu_table(ctx, scale, imu_runs))
        ctx.log(f"analog IMU missing data: {imu_runs} erasure seeds ({time.perf_counter() - start:.0f} s)")
    else:  # the other tables need no data; say what is missing instead of failing the section
        ctx.log(f"paper 001: no PyShoe recordings at {default_pdr_root()}: the IMU missing-data table is left out")
    return tables


__all__ = ["ANFB_VARIANTS", "FULL_RUNS", "Scale", "anda_case", "expected_seconds", "imu_table", "reproduce_tables",
           "table1_realisation", "table1_task", "table1_tables"]
