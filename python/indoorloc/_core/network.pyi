# Stubs of indoorloc._core.network: INS/GPS network adjustment, the Kalman smoother baseline,
# the cross-over finder and normal gravity (paper 003); and the scale path (linearised INS/GPS
# network, block-tridiagonal solver, cross-over PCG).
from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

from .pdr import _Result

# The scale path's results: typed read-only objects (fields as annotations); reading them as the
# former dicts (result["key"], keys(), items(), ...) is deprecated (DeprecationWarning), to_dict() is not.

class _NetworkSize(_Result):
    """The network solved (bindings: SizeFields)."""
    imu_epochs: int
    gps_epochs: int
    unknowns: int

class _SolverSummary(_Result):
    """The block-tridiagonal solver's timings [s], memory and smallest pivot (bindings: SolverFields)."""
    factor_seconds: float
    backward_seconds: float
    total_seconds: float
    stored_factor_bytes: float
    min_relative_pivot: float

class _TruthError(_Result):
    """The error against the noise-free truth (bindings: TruthFields)."""
    max_abs_error: float
    gravity_rmse: float

class _GravityDisturbance(_Result):
    """δg with its sigma per epoch, (E, 3) [m/s²] (bindings: GravityFields)."""
    gravity_sigma: npt.NDArray[np.float64]
    gravity_estimate: npt.NDArray[np.float64]

class LinearInsNetworkResult(_NetworkSize, _SolverSummary, _TruthError, _GravityDisturbance):
    equations: int
    block_size: int
    num_blocks: int
    assembler_calls: int
    min_relative_pivot_block: int
    min_relative_pivot_unknown: int
    max_abs_error_by_unknown: npt.NDArray[np.float64]
    max_abs_error_epoch: int
    report: str

class FoldedNetworkResult(_NetworkSize, _SolverSummary, _TruthError, _GravityDisturbance):
    ties: int
    gupts: int
    equations: int
    folded_blocks: int
    folded_block_size: int
    report: str

class CrossoverNetworkResult(_NetworkSize, _TruthError):
    equations: int
    crossings: int
    ties: int
    factor_seconds: float
    factor_bytes: float
    pcg_iterations: int
    pcg_seconds: float
    pcg_relative_residual: float
    pcg_converged: bool
    total_seconds: float
    report: str

class LinearInsCeresResult(_Result):
    imu_epochs: int
    unknowns: int
    x: npt.NDArray[np.float64]
    build_seconds: float
    solve_seconds: float
    iterations: int
    converged: bool
    max_abs_error: float
    linear_solver: str
    report: str

class LinearInsEquations(_Result):
    offsets: List[int]
    J: List[npt.NDArray[np.float64]]
    row_sigma: npt.NDArray[np.float64]
    centres: List[int]
    dynamic_l: npt.NDArray[np.float64]
    gps_epochs: List[int]
    gps_l: npt.NDArray[np.float64]
    prior_l: npt.NDArray[np.float64]
    gupt_epochs: List[int]
    gupt_l: npt.NDArray[np.float64]
    sigma_gps: float
    sigma_prior: float
    sigma_gupt: float
    imu_epochs: int

class LinearInsNetworkOptions:
    """Fields and defaults: read them from the compiled struct (``LinearInsNetworkOptions().to_dict()``);
    they are not restated here."""
    accel_bias_density: float
    accel_density: float
    duration_s: float
    gps_rate_hz: float
    gravity_density: float
    gupt_end_epochs: int
    gyro_bias_density: float
    gyro_density: float
    imu_rate_hz: float
    prior_epochs: int
    rule: str
    sigma_gps_m: float
    sigma_gupt_mps2: float
    sigma_prior: float
    specific_force_mps2: List[float]
    velocity_density: float
    def __init__(self, *args: Any, **fields: Any) -> None: ...
    def replace(self, **fields: Any) -> "LinearInsNetworkOptions": ...
    def to_dict(self) -> Dict[str, Any]: ...
    def validate(self) -> None: ...

# The former calls with the network's fields (imu_rate_hz, duration_s, gps_rate_hz, rule,
# prior_epochs, sigma_gupt_mps2) as arguments still run (DeprecationWarning); not listed here.
def solve_linear_ins_network(
    network: LinearInsNetworkOptions = ...,
    gravity_covariance: bool = ...,
    checkpoint_interval: int = ...,
    keep_gravity_estimate: bool = ...,
    num_threads: int = ...,
    pivot_tolerance: Optional[float] = ...,
    method: str = ...,
) -> LinearInsNetworkResult: ...
def solve_folded_linear_ins_network(
    network: LinearInsNetworkOptions = ...,
    num_ties: int = ...,
    num_gupts: int = ...,
    sigma_xover_mps2: float = ...,
    checkpoint_interval: int = ...,
    gravity_covariance: bool = ...,
    keep_gravity_estimate: bool = ...,
    num_threads: int = ...,
) -> FoldedNetworkResult: ...
def solve_linear_ins_network_with_crossovers(
    network: LinearInsNetworkOptions = ...,
    lines: int = ...,
    cross_lines: int = ...,
    sigma_xover_mps2: float = ...,
    max_iterations: int = ...,
    relative_tolerance: float = ...,
) -> CrossoverNetworkResult: ...
def solve_linear_ins_network_ceres(
    network: LinearInsNetworkOptions = ..., one_gauss_newton_step: bool = ...
) -> LinearInsCeresResult: ...
def linear_ins_equations(network: LinearInsNetworkOptions = ...) -> LinearInsEquations: ...
def linear_ins_normal_blocks(
    network: LinearInsNetworkOptions = ...,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
_ArrayLike = npt.ArrayLike
_F64 = npt.NDArray[np.float64]
_State = Dict[str, _F64]

class NetworkOptions:
    """Fields and defaults: read them from the compiled struct (``NetworkOptions().to_dict()``);
    they are not restated here."""
    acc_bias_correlation_time_s: float
    acc_bias_walk_mps2_rts: float
    acc_noise_mps2_rthz: float
    check_datum: bool
    datum_pivot_tolerance: float
    discretization: str
    earth_rate_radps: float
    function_tolerance: float
    gps_huber_threshold: float
    gradient_tolerance: float
    gravity_covariance: str
    gravity_walk_mps2_rts: float
    gyro_bias_correlation_time_s: float
    gyro_bias_walk_radps_rts: float
    gyro_noise_radps_rthz: float
    initial_trust_region_radius: float
    latitude_rad: float
    max_iterations: int
    num_threads: int
    origin_height_m: float
    parameter_tolerance: float
    sigma_gps_m: float
    sigma_gupt_mps2: float
    sigma_sgupt_mps2: float
    sigma_vel_mps: float
    sigma_vupt_mps: float
    sigma_xover_mps2: float
    sigma_zupt_mps: float
    slow_parameter_stride: int
    variance_components: bool
    def __init__(self, *args: Any, **fields: Any) -> None: ...
    def replace(self, **fields: Any) -> "NetworkOptions": ...
    def to_dict(self) -> Dict[str, Any]: ...
    def validate(self) -> None: ...
    def is_valid(self) -> str: ...

class KalmanSmootherOptions:
    """Fields and defaults: read them from the compiled struct (``KalmanSmootherOptions().to_dict()``);
    they are not restated here."""
    init_sigma_acc_bias_mps2: float
    init_sigma_gravity_mps2: float
    init_sigma_gyro_bias_radps: float
    init_sigma_heading_rad: float
    init_sigma_level_rad: float
    init_sigma_position_m: float
    init_sigma_velocity_mps: float
    smooth: bool
    def __init__(self, *args: Any, **fields: Any) -> None: ...
    def replace(self, **fields: Any) -> "KalmanSmootherOptions": ...
    def to_dict(self) -> Dict[str, Any]: ...
    def validate(self) -> None: ...

class NetworkObservations:
    """The observations of a flight for solve_network and kalman_smoother, checked once."""
    def __init__(
        self,
        imu_time_s: _ArrayLike,
        acc_body_mps2: _ArrayLike,
        gyro_body_radps: _ArrayLike,
        gps_time_s: _ArrayLike,
        gps_position_m: _ArrayLike,
        zupt_epochs: Optional[_ArrayLike] = None,
        gupt_epochs: Optional[_ArrayLike] = None,
        gupt_gravity_mps2: Optional[_ArrayLike] = None,
        xover_epochs: Optional[_ArrayLike] = None,
        vupt_epochs: Optional[_ArrayLike] = None,
        vupt_velocity_mps: Optional[_ArrayLike] = None,
        vupt_sd_mps: Optional[_ArrayLike] = None,
        sgupt_epochs: Optional[_ArrayLike] = None,
    ) -> None: ...
    @property
    def num_imu_epochs(self) -> int: ...
    @property
    def num_gps_epochs(self) -> int: ...

# The former calls with the observation arrays as arguments still run (DeprecationWarning); they
# are not listed here.
def solve_network(
    observations: NetworkObservations, initial: Dict[str, _ArrayLike], options: NetworkOptions = ...
) -> Tuple[_State, Dict[str, Any]]: ...
def kalman_smoother(
    observations: NetworkObservations,
    initial: Dict[str, _ArrayLike],
    model: NetworkOptions = ...,
    options: KalmanSmootherOptions = ...,
) -> Tuple[_State, _State, Dict[str, Any]]: ...
def find_crossovers(
    time_s: _ArrayLike,
    position_m: _ArrayLike,
    radius_m: float = 5.0,
    max_height_difference_m: float = 50.0,
    min_separation_s: float = 30.0,
) -> npt.NDArray[np.int32]: ...
def normal_gravity(latitude_rad: float, height_m: _ArrayLike) -> _F64: ...
def earth_rate_enu(latitude_rad: float) -> _F64: ...
