"""Pedestrian dead reckoning with a foot-mounted IMU (paper 002, Jiménez et al., WISP 2009).

- step / stance detection: the paper's acceleration-variance and gyroscope step detectors
  (:func:`steps_acceleration`, :func:`steps_gyro`), the SHOE zero-velocity detector
  (:func:`shoe_detector`, :func:`shoe_statistic`);
- stride length: Weinberg's rule (eq. 4; :func:`weinberg_stride_lengths`,
  :func:`weinberg_features`) with its 4th-order 3 Hz Butterworth low-pass
  (:func:`butterworth_sos`, :func:`sos_filter`, equal to scipy.signal's) and K calibrated on a walk
  of known length (:func:`calibrate_weinberg_k`, :func:`calibrate_weinberg_k_from_distance`);
- the zero-velocity-aided strapdown INS, a 9-state error-state EKF with an optional RTS smoother
  (:func:`zupt_ekf`).

Loaders for the recordings in ../shared/data/pdr are in :mod:`indoorloc.io`.
"""

from __future__ import annotations

from indoorloc._core.pdr import (
    butterworth_sos,
    calibrate_weinberg_k,
    calibrate_weinberg_k_from_distance,
    shoe_detector,
    shoe_statistic,
    sos_filter,
    steps_acceleration,
    steps_gyro,
    weinberg_features,
    weinberg_stride_lengths,
    zupt_ekf,
)

__all__ = [
    "butterworth_sos",
    "calibrate_weinberg_k",
    "calibrate_weinberg_k_from_distance",
    "shoe_detector",
    "shoe_statistic",
    "sos_filter",
    "steps_acceleration",
    "steps_gyro",
    "weinberg_features",
    "weinberg_stride_lengths",
    "zupt_ekf",
]
