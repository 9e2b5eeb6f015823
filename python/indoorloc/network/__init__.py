"""INS/GPS network adjustment for strapdown inertial kinematic gravimetry (paper 003, Térmens &
Colomina): the network approach (NA, :func:`solve_network`: one sparse least-squares problem over
all epochs, with cross-overs) and the state-space approach (SSA, :func:`kalman_smoother`: an
error-state EKF + RTS smoother with the same model, without cross-overs). Both take the same
:class:`NetworkObservations` (IMU, GPS and the update epochs, checked once).

Model (docs/network.md): local Earth-fixed ENU frame with Earth rotation and GRS80 normal gravity
γ(h); per epoch position, velocity, attitude quaternion, accelerometer and gyro biases (random
walks) and the vertical gravity disturbance δg (random walk along time). Dynamic equations by the
leap-frog rule (paper §3.3) or the trapezoidal rule; CUPT, VUPT, ZUPT, GUPT, SGUPT and XOVER
observations. ``NetworkOptions.slow_parameter_stride`` carries the biases and δg at a lower rate
(paper §4: one block per that many IMU epochs, e.g. the IMU/GPS rate ratio; about half the
unknowns).

The helpers :func:`flight_options`, :func:`start_state`, :func:`solve_flight` and
:func:`smooth_flight` run both approaches on a simulated flight
(:mod:`indoorloc.simulate.flight`).

Examples
--------
>>> from indoorloc import network
>>> float(network.normal_gravity(0.0, [0.0])[0])  # doctest: +ELLIPSIS
9.780326...
"""

from __future__ import annotations

import math
from typing import Dict, Optional, Tuple

import numpy as np

from indoorloc.validate import integer, real_scalar

from indoorloc._core.network import (
    KalmanSmootherOptions,
    LinearInsNetworkOptions,
    NetworkObservations,
    NetworkOptions,
    earth_rate_enu,
    find_crossovers,
    kalman_smoother,
    normal_gravity,
    solve_folded_linear_ins_network,
    solve_network,
)

__all__ = [
    "KalmanSmootherOptions",
    "LinearInsNetworkOptions",
    "NetworkObservations",
    "NetworkOptions",
    "flight_observations",
    "earth_rate_enu",
    "find_crossovers",
    "flight_options",
    "kalman_smoother",
    "normal_gravity",
    "smooth_flight",
    "solve_repeated_pass_network",
    "solve_flight",
    "solve_network",
    "start_state",
]

MGAL = 1e-5  #: 1 mGal in m/s^2

#: Paper Table 2 case 4 (Rockies'95): 50 Hz IMU, 2 Hz GPS, 565,050 epochs, 332,150 XOVER, 1,907 GUPT.
CASE4 = dict(imu_rate_hz=50.0, duration_s=565049.0 / 50.0, gps_rate_hz=2.0, num_ties=332150, num_gupts=1907)


def solve_repeated_pass_network(
    imu_rate_hz: float = 50.0,
    duration_s: float = 60.0,
    gps_rate_hz: float = 2.0,
    num_ties: int = 1000,
    num_gupts: int = 10,
    sigma_xover_mps2: float = MGAL,
    sigma_gupt_mps2: float = MGAL,
    rule: str = "leapfrog",
    checkpoint_interval: int = 2048,
    keep_gravity_estimate: bool = False,
    num_threads: int = 1,
) -> Dict[str, object]:
    """Linearised INS/GPS network of a survey re-flown in reverse over its own track, with
    cross-over ties between the passes, solved exactly in the folded band order
    (docs/network_scale.md, "Case 4: repeated passes folded into the band").

    The flight is folded at its midpoint, so a tie between epoch t and its mirror E-1-t (or the
    mirror's neighbour E-2-t) stays inside one block of 72 unknowns (leap-frog) and the tied
    network is solved by the block-tridiagonal Cholesky with the variance of every δg. The C++
    work runs with the GIL released. ``solve_repeated_pass_network(**CASE4)`` is Table 2 case 4.

    Parameters
    ----------
    imu_rate_hz, duration_s, gps_rate_hz : float
        Network size [Hz], [s], [Hz]; E = round(duration_s * imu_rate_hz) + 1 epochs.
    num_ties : int
        Scalar XOVER ties on the vertical δg (every mirror pair, then mirror neighbours).
    num_gupts : int
        Scalar GUPTs on the vertical δg, evenly spread over the flight.
    sigma_xover_mps2, sigma_gupt_mps2 : float
        Standard deviations [m/s^2] (default 1 mGal).
    rule : "leapfrog" or "trapezoidal"
    checkpoint_interval : int
        0 keeps the whole factor; k > 0 keeps one checkpoint every k blocks.
    keep_gravity_estimate : bool
        Also return the δg estimate.
    num_threads : int
        1 or 2 threads for the two chains of the twisted elimination (<= 0: all cores); the
        results are bit-identical on any count.

    Returns
    -------
    FoldedNetworkResult
        Read-only attributes (reading it as the former dict is deprecated; ``to_dict()``): sizes
        (``imu_epochs``, ``unknowns``, ``ties``, ``gupts``, ``equations``), timings [s],
        ``max_abs_error`` (every unknown, against the noise-free truth), ``gravity_rmse``
        [m/s^2], ``gravity_sigma`` (E, 3) [m/s^2] (numpy), ``gravity_estimate`` (E, 3) [m/s^2]
        or empty, ``report``.
    """
    network = LinearInsNetworkOptions(imu_rate_hz=imu_rate_hz, duration_s=duration_s, gps_rate_hz=gps_rate_hz,
                                      rule=rule, sigma_gupt_mps2=sigma_gupt_mps2)
    return solve_folded_linear_ins_network(
        network, integer(num_ties, "num_ties", lo=0, hi=2**62), integer(num_gupts, "num_gupts", lo=0, hi=2**62),
        sigma_xover_mps2, checkpoint_interval, True, keep_gravity_estimate,
        integer(num_threads, "num_threads", lo=-1024, hi=1024))


def flight_options(config, discretization: str = "trapezoidal", **overrides) -> NetworkOptions:
    """NetworkOptions whose noise densities and sigmas are those the simulator used."""
    o = NetworkOptions()
    o.discretization = discretization
    o.latitude_rad = config.latitude_rad
    o.origin_height_m = config.origin_height_m
    o.acc_noise_mps2_rthz = config.acc_noise_mps2_rthz
    o.gyro_noise_radps_rthz = config.gyro_noise_radps_rthz
    o.acc_bias_walk_mps2_rts = config.acc_bias_walk_mps2_rts
    o.gyro_bias_walk_radps_rts = config.gyro_bias_walk_radps_rts
    o.sigma_gps_m = config.sigma_gps_m
    o.sigma_gupt_mps2 = config.sigma_gupt_mps2
    for k, v in overrides.items():
        if not hasattr(o, k):
            raise ValueError(f"indoorloc: argument '{k}': not a NetworkOptions field")
        setattr(o, k, v)
    return o


def start_state(flight, seed: int = 0, level_sd_rad: float = 1e-3, heading_sd_rad: float = 1e-2) -> Dict[str, np.ndarray]:
    """Initial state (one row) for the filter: first GPS fix, zero velocity (hover), true
    attitude with N(0, level_sd) roll/pitch and N(0, heading_sd) heading errors, zero biases and δg.
    Stream ``default_rng([seed, 2])``."""
    from scipy.spatial.transform import Rotation

    _check_flight(flight)
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)
    level_sd_rad = real_scalar(level_sd_rad, "level_sd_rad", lo=0.0, hi=math.pi)
    heading_sd_rad = real_scalar(heading_sd_rad, "heading_sd_rad", lo=0.0, hi=math.pi)
    rng = np.random.default_rng([seed, 2])
    q = flight.truth["attitude_wxyz"][0]
    err = rng.normal(0.0, [level_sd_rad, level_sd_rad, heading_sd_rad])
    r = Rotation.from_rotvec(err) * Rotation.from_quat([q[1], q[2], q[3], q[0]])
    xyzw = r.as_quat()
    return {
        "position_m": flight.gps_position_m[:1].copy(),
        "velocity_mps": np.zeros((1, 3)),
        "attitude_wxyz": np.array([[xyzw[3], xyzw[0], xyzw[1], xyzw[2]]]),
        "acc_bias_mps2": np.zeros((1, 3)),
        "gyro_bias_radps": np.zeros((1, 3)),
        "gravity_disturbance_mps2": np.zeros(1),
    }


def _check_flight(flight) -> None:
    """A simulated flight (indoorloc.simulate.flight.simulate_flight), named when it is not one."""
    needed = ("config", "truth", "imu_time_s", "acc_body_mps2", "gyro_body_radps", "gps_time_s", "gps_position_m")
    if not all(hasattr(flight, a) for a in needed):
        raise TypeError(f"indoorloc: argument 'flight': expected a simulated flight "
                        f"(indoorloc.simulate.flight.simulate_flight), got {type(flight).__name__}")


def flight_observations(flight, xover_epochs: Optional[np.ndarray] = None,
                        sgupt_epochs: Optional[np.ndarray] = None) -> NetworkObservations:
    """The :class:`NetworkObservations` of a simulated flight: its IMU and GPS samples, ZUPT (hover)
    and GUPT epochs; ``xover_epochs`` (K, 2) cross-over pairs and ``sgupt_epochs`` static epochs
    when given (None or empty: none)."""
    _check_flight(flight)
    return NetworkObservations(
        flight.imu_time_s, flight.acc_body_mps2, flight.gyro_body_radps, flight.gps_time_s, flight.gps_position_m,
        zupt_epochs=flight.zupt_epochs, gupt_epochs=flight.gupt_epochs, gupt_gravity_mps2=flight.gupt_gravity_mps2,
        xover_epochs=xover_epochs if xover_epochs is not None and np.size(xover_epochs) else None,
        sgupt_epochs=sgupt_epochs)


def smooth_flight(flight, options: Optional[NetworkOptions] = None, seed: int = 0, smooth: bool = True,
                  kalman_options: Optional[KalmanSmootherOptions] = None) -> Tuple[dict, dict, dict]:
    """SSA on a simulated flight: (smoothed state, filtered state, summary)."""
    _check_flight(flight)
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)
    options = options or flight_options(flight.config)
    ko = kalman_options or KalmanSmootherOptions()
    ko.smooth = smooth
    return kalman_smoother(flight_observations(flight), start_state(flight, seed), model=options, options=ko)


def solve_flight(flight, options: Optional[NetworkOptions] = None, xover: bool = True, seed: int = 0,
                 initial: Optional[dict] = None, crossover_radius_m: float = 5.0,
                 min_separation_s: float = 30.0, sgupt: bool = False) -> Tuple[dict, dict, np.ndarray]:
    """NA on a simulated flight: (state, summary, cross-over pairs used).

    Initial values: the forward EKF's states (``initial`` overrides). Cross-overs are found on the
    initial trajectory with :func:`find_crossovers` when ``xover``. ``sgupt``: constant gravity
    (SGUPT) over the flight's ZUPT (hover) epochs. Slow parameters: ``options.slow_parameter_stride``.
    """
    _check_flight(flight)
    seed = integer(seed, "seed", lo=0, hi=2**64 - 1)
    if initial is not None and not isinstance(initial, dict):
        raise TypeError(f"indoorloc: argument 'initial': expected None or a state dict, got {type(initial).__name__}")
    crossover_radius_m = real_scalar(crossover_radius_m, "crossover_radius_m", lo=1e-12, hi=1e12)
    min_separation_s = real_scalar(min_separation_s, "min_separation_s", lo=0.0)
    options = options or flight_options(flight.config)
    if initial is None:
        _, initial, _ = smooth_flight(flight, options, seed=seed, smooth=False)
    pairs = np.zeros((0, 2), dtype=np.int32)
    if xover:
        pairs = find_crossovers(flight.imu_time_s, initial["position_m"], radius_m=crossover_radius_m,
                                min_separation_s=min_separation_s)
    observations = flight_observations(flight, xover_epochs=pairs, sgupt_epochs=flight.zupt_epochs if sgupt else None)
    state, summary = solve_network(observations, initial, options=options)
    return state, summary, pairs
