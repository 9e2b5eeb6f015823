# Stubs of indoorloc._core.mapmatch: road networks, trajectories, circular particle filter.
from typing import Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

_ArrayLike = npt.ArrayLike
_F64 = npt.NDArray[np.float64]
_I64 = npt.NDArray[np.int64]

class RoadNetwork:
    def __init__(
        self,
        segments_m: _ArrayLike,
        ids: Optional[_ArrayLike] = None,
        snap_tolerance_m: float = 1e-6,
        split_at_intersections: bool = False,
    ) -> None: ...
    @property
    def num_segments(self) -> int: ...
    @property
    def segments_m(self) -> _F64: ...
    @property
    def ids(self) -> npt.NDArray[np.int32]: ...
    @property
    def headings_rad(self) -> _F64: ...
    @property
    def lengths_m(self) -> _F64: ...
    @property
    def total_length_m(self) -> float: ...
    @property
    def components(self) -> npt.NDArray[np.int32]: ...
    @property
    def num_components(self) -> int: ...
    @property
    def dangling_ends(self) -> _I64: ...
    def continuations(self, segment: int, end: int) -> List[Tuple[int, int]]: ...
    def nearest(self, points_m: _ArrayLike) -> Tuple[_I64, _F64, _F64, _F64]: ...
    def point_at(self, segment: int, along_m: float) -> _F64: ...
    def report(self) -> str: ...

class TrajectoryOptions:
    duration_s: float
    dt_s: float
    speed_mps: float
    speed_noise_sd_mps: float
    speed_bias_halfwidth_mps: float
    heading_kappa: float
    allow_straight: bool
    def __init__(
        self,
        duration_s: float = 200.0,
        dt_s: float = 0.5,
        speed_mps: float = 2.0,
        speed_noise_sd_mps: float = 0.6,
        speed_bias_halfwidth_mps: float = 0.5,
        heading_kappa: float = 2.0,
        allow_straight: bool = False,
    ) -> None: ...

def simulate_trajectory(
    network: RoadNetwork, options: TrajectoryOptions = ..., seed: int = 0, stream: int = 0
) -> Dict[str, object]: ...

class FilterOptions:
    num_particles: int
    kappa: float
    noise_halfwidth_m: float
    estimate_speed_bias: bool
    smoothing_lag_steps: int
    recovery_disagreement: float
    seed: int
    junction_policy: str
    def __init__(
        self,
        num_particles: int = 10000,
        kappa: float = 1.0,
        noise_halfwidth_m: float = 0.6,
        resampling: str = "systematic",
        ess_threshold: float = 0.5,
        junction_policy: str = "uniform",
        junction_kappa: float = 2.0,
        estimate_speed_bias: bool = False,
        bias_halfwidth_mps: float = 0.5,
        bias_jitter_mps: float = 0.02,
        tracking_spread_m: float = 2.0,
        recovery_disagreement: float = 0.9,
        recovery_window_s: float = 20.0,
        recovery_fraction: float = 0.5,
        smoothing_lag_steps: int = 0,
        seed: int = 0,
    ) -> None: ...
    def validate(self) -> None: ...

class ParticleMapMatcher:
    def __init__(self, network: RoadNetwork, options: FilterOptions = ...) -> None: ...
    def reset(self) -> None: ...
    def step(self, speed_mps: float, heading_rad: float, dt_s: float) -> Dict[str, np.ndarray]: ...
    def run(self, speed_mps: _ArrayLike, heading_rad: _ArrayLike, dt_s: float) -> Dict[str, np.ndarray]: ...
    def set_particles(self, segments: _ArrayLike, directions: _ArrayLike, along_m: _ArrayLike) -> None: ...
    def segment_posterior(self) -> _F64: ...
    def particle_positions(self) -> _F64: ...
    def particle_weights(self) -> _F64: ...
    def particle_states(self) -> Tuple[_I64, _I64, _F64]: ...
    @property
    def summary_report(self) -> str: ...
    @property
    def recoveries(self) -> int: ...

def monte_carlo(
    network: RoadNetwork,
    trajectory: TrajectoryOptions,
    filter: FilterOptions,
    n_runs: int = 100,
    seed: int = 0,
    n_threads: int = 0,
) -> Dict[str, np.ndarray]: ...
