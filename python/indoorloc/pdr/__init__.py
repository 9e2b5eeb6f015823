"""Pedestrian dead reckoning with a foot-mounted IMU (paper 002, Jiménez et al., WISP 2009).

- step / stance detection: the paper's acceleration-variance and gyroscope step detectors
  (:func:`steps_acceleration`, :func:`steps_gyro`), the SHOE zero-velocity detector
  (:func:`shoe_detector`, :func:`shoe_statistic`) and its threshold adapted to the recording
  with a stance guard (:func:`zero_velocity`, chosen by cross-validation: docs/pdr.md);
- stride counting from stance flags, robust to slow walks and runs (:func:`count_strides`);
- stride length: Weinberg's rule (eq. 4; :func:`weinberg_stride_lengths`,
  :func:`weinberg_features`) with its 4th-order 3 Hz Butterworth low-pass
  (:func:`butterworth_sos`, :func:`sos_filter`, equal to scipy.signal's) and K calibrated on a walk
  of known length (:func:`calibrate_weinberg_k`, :func:`calibrate_weinberg_k_from_distance`);
- the zero-velocity-aided strapdown INS, a 9-state error-state EKF with an optional RTS smoother
  (:func:`zupt_ekf`), whose ``health`` dict reports divergence (stance fraction, swing
  durations, speed at stance, longest stride, ``implausible`` with reasons);
- the magnetometer step detector (:func:`steps_magnetometer`) and the Mahony attitude filter
  (:func:`attitude_mahony`) for recordings without the sensor orientation;
- step-wise positioning (paper eq. 5-9): INS-ZUPT increments (:func:`ins_zupt_increments`),
  headings at stance (:func:`stance_headings`), stride length + heading
  (:func:`positions_from_strides`) and increments (:func:`positions_from_increments`), each step
  with a 3 x 3 covariance of (x, y, heading error) for fusion with maps and WiFi.

Each function takes its settings as one ``options=`` argument, the Options class of its concept
(``zupt_ekf(t, acc, gyro, stance, options=ZuptEkfOptions(smooth=True))``; None: the defaults of
the C++ struct, the one place they are written). The fields as separate keywords still work for
one release, with a DeprecationWarning (docs/api_changes.md).

Beside the compiled functions, the package holds the Python side of the subsystem:

- :mod:`indoorloc.pdr.recommended`: the recommended foot-mounted pipeline
  (:func:`run_recommended`, :func:`detect_stance`, :data:`ZUPT_DETECTOR`) and its health check
  (:func:`gait_plausibility`);
- :mod:`indoorloc.pdr.metrics`: :func:`align_2d`, :func:`armse`, :func:`path_length`;
- :mod:`indoorloc.pdr.handheld`: step-and-heading PDR for a hand-held phone
  (:mod:`indoorloc.pdr.orientation`: its rotation-vector and gyroscope headings).

Loaders for the recordings in ../shared/data/pdr are in :mod:`indoorloc.io`. Moves from earlier
paths are listed in docs/api_changes.md.
"""

from __future__ import annotations

from indoorloc._core.pdr import (
    AccelerationStepOptions,
    GyroStepOptions,
    InsZuptOptions,
    MagneticStepOptions,
    MahonyOptions,
    ShoeOptions,
    StepCovarianceOptions,
    StrideCountOptions,
    WeinbergOptions,
    ZeroVelocityOptions,
    ZuptEkfOptions,
    attitude_mahony,
    butterworth_sos,
    calibrate_weinberg_k,
    calibrate_weinberg_k_from_distance,
    count_strides,
    ins_zupt_increments,
    positions_from_increments,
    positions_from_strides,
    shoe_detector,
    shoe_statistic,
    sos_filter,
    stance_headings,
    steps_acceleration,
    steps_gyro,
    steps_magnetometer,
    weinberg_features,
    weinberg_stride_lengths,
    zero_velocity,
    zupt_ekf,
)
from indoorloc.pdr import handheld, metrics, recommended
from indoorloc.pdr.metrics import align_2d, armse, path_length
from indoorloc.pdr.recommended import ZUPT_DETECTOR, detect_stance, gait_plausibility, run_recommended

__all__ = [
    "AccelerationStepOptions",
    "GyroStepOptions",
    "InsZuptOptions",
    "MagneticStepOptions",
    "MahonyOptions",
    "ShoeOptions",
    "StepCovarianceOptions",
    "StrideCountOptions",
    "WeinbergOptions",
    "ZeroVelocityOptions",
    "ZuptEkfOptions",
    "ZUPT_DETECTOR",
    "align_2d",
    "armse",
    "attitude_mahony",
    "butterworth_sos",
    "calibrate_weinberg_k",
    "calibrate_weinberg_k_from_distance",
    "count_strides",
    "detect_stance",
    "gait_plausibility",
    "handheld",
    "ins_zupt_increments",
    "metrics",
    "path_length",
    "positions_from_increments",
    "positions_from_strides",
    "recommended",
    "run_recommended",
    "shoe_detector",
    "shoe_statistic",
    "sos_filter",
    "stance_headings",
    "steps_acceleration",
    "steps_gyro",
    "steps_magnetometer",
    "weinberg_features",
    "weinberg_stride_lengths",
    "zero_velocity",
    "zupt_ekf",
]
