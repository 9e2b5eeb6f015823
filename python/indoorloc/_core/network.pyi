# Stubs of indoorloc._core.network: the scale path (linearised INS/GPS network, block-tridiagonal solver).
from typing import Dict, Tuple

import numpy as np
import numpy.typing as npt

def solve_linear_ins_network(
    imu_rate_hz: float = 200.0,
    duration_s: float = 60.0,
    gps_rate_hz: float = 1.0,
    rule: str = "leapfrog",
    gravity_covariance: bool = True,
    checkpoint_interval: int = 0,
    prior_epochs: int = 2,
    keep_gravity_estimate: bool = False,
) -> Dict[str, object]: ...
def linear_ins_normal_blocks(
    imu_rate_hz: float = 200.0,
    duration_s: float = 60.0,
    gps_rate_hz: float = 1.0,
    rule: str = "leapfrog",
    prior_epochs: int = 2,
) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
def linear_ins_equations(
    imu_rate_hz: float = 200.0,
    duration_s: float = 60.0,
    gps_rate_hz: float = 1.0,
    rule: str = "leapfrog",
    prior_epochs: int = 2,
) -> Dict[str, object]: ...
def solve_linear_ins_network_with_crossovers(
    imu_rate_hz: float = 50.0,
    duration_s: float = 600.0,
    gps_rate_hz: float = 2.0,
    rule: str = "leapfrog",
    lines: int = 10,
    cross_lines: int = 10,
    sigma_xover_mps2: float = 1e-5,
    max_iterations: int = 1000,
    relative_tolerance: float = 1e-10,
) -> Dict[str, object]: ...
