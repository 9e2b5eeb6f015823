"""Pedestrian dead reckoning with a foot-mounted IMU (paper 002, Jiménez et al., WISP 2009).

Implemented so far (issue 6 is in progress): the paper's acceleration-variance and gyroscope
step detectors (:func:`steps_acceleration`, :func:`steps_gyro`), the SHOE zero-velocity detector
(:func:`shoe_detector`, :func:`shoe_statistic`) and the zero-velocity-aided strapdown INS, a
9-state error-state EKF (:func:`zupt_ekf`). Loaders for the recordings in ../shared/data/pdr are in
:mod:`indoorloc.io`.
"""

from __future__ import annotations

from indoorloc._core.pdr import shoe_detector, shoe_statistic, steps_acceleration, steps_gyro, zupt_ekf

__all__ = ["shoe_detector", "shoe_statistic", "steps_acceleration", "steps_gyro", "zupt_ekf"]
