"""Pedestrian dead reckoning with a hand-held phone (held flat in front, portrait).

The foot-mounted methods of :mod:`indoorloc.pdr` (paper 002) rely on the foot's stance; a phone in
the hand sees the body's vertical bounce instead, one oscillation per step. This module adapts them:

1. **Steps** (:func:`detect_steps_handheld`): the specific-force magnitude |a| (or its vertical
   component a_up, rotated into the east-north-up frame by the rotation vector), band-passed by a
   Butterworth low-pass and high-pass (:func:`indoorloc.pdr.butterworth_sos`,
   :func:`indoorloc.pdr.sos_filter`, run forward and backward for zero phase). A step is a local
   maximum above ``max(threshold_fraction x running RMS, min_peak_mps2)`` (the running RMS over
   ``rms_window_s`` makes the threshold follow the walker; the absolute floor keeps a phone held
   still from producing steps) and at least ``min_step_interval_s`` after the previous one
   (``scipy.signal.find_peaks``, largest peaks first).
2. **Length**: Weinberg's rule L_k = K (max ã - min ã)^(1/4) (paper 002 eq. 4) on the 3 Hz
   low-pass of |a| over the step's own interval (half-way to the neighbouring steps), through
   :func:`indoorloc.pdr.weinberg_features`; K from training walks by least squares of the waypoint
   distances on the feature sums between waypoints (:func:`calibrate_handheld`, which calls
   :func:`indoorloc.pdr.calibrate_weinberg_k`).
3. **Heading** of the phone's +y axis in the east-north frame (east = 0, north = pi/2), either from
   the rotation vector (Android TYPE_ROTATION_VECTOR: unit quaternion device -> ENU,
   :func:`rotation_vector_heading`) or from the gyroscope's rate about the vertical, integrated
   from the first rotation-vector heading (:func:`gyro_heading`), or the complementary blend of
   the two (:func:`complementary_heading`: gyro below 1 / (2 pi tau), rotation vector above).
   Per step, the mean heading over
   the step's interval. The floor frame differs from this frame by a yaw offset (map orientation,
   magnetic declination, how the phone is held) that a fusion filter estimates; its mean over the
   training walks is :attr:`HandheldOptions.yaw_offset_rad`.
4. **Uncertainty** per step, from cross-validation residuals on the training walks
   (:func:`calibrate_handheld`): with independent per-step length errors of sd ``f L_k``, the
   residual r_j of the path length between waypoints j, j+1 has variance ``f^2 sum L_k^2``, so
   ``f^2 = mean_j r_j^2 / sum_{k in j} L_k^2``; with independent per-step heading errors of sd
   s, the direction error d_j of an interval of n_j steps (after the walk's best yaw offset) has
   variance s^2 / n_j, so ``s^2 = mean_j n_j d_j^2``. Both assume independence; the real errors
   are partly systematic (per-walk scale, slowly varying magnetic disturbance), see
   docs/pdr_handheld.md.

Everything takes a walk of :mod:`indoorloc.io` (``IlcWalk``: ``accelerometer``, ``gyroscope``,
``rotation_quaternion_xyzw()``) or :class:`HandheldArrays`.

The parts live by concept beside this module, which re-exports them all (import paths unchanged):
:mod:`indoorloc.pdr.handheld_types` (arrays, options, steps), :mod:`indoorloc.pdr.handheld_detection`
(steps, lengths, headings), :mod:`indoorloc.pdr.handheld_track` (displacements and tracks),
:mod:`indoorloc.pdr.handheld_calibration` (waypoint intervals and the fit on training walks) and
:mod:`indoorloc.pdr.orientation` (the headings of the phone).
"""

from __future__ import annotations

# Re-exported, private helpers included: callers of the one-module version keep working.
from indoorloc.pdr.handheld_calibration import (  # noqa: F401
    HandheldCalibration,
    WaypointIntervals,
    best_yaw_offset,
    calibrate_from_intervals,
    calibrate_handheld,
    rescale,
    waypoint_intervals,
)
from indoorloc.pdr.handheld_detection import (  # noqa: F401
    _interval_mean,
    _zero_phase,
    detect_steps_handheld,
    handheld_steps,
    step_headings,
    step_signal,
)
from indoorloc.pdr.handheld_track import (  # noqa: F401
    _check_finite_steps,
    _heading_of,
    cumulative_at,
    pdr_track,
    step_displacements,
)
from indoorloc.pdr.handheld_types import (  # noqa: F401
    HEADING_SOURCES,
    MAX_ACC_MPS2,
    MAX_GYRO_RADPS,
    MAX_WINDOW_S,
    HandheldArrays,
    HandheldOptions,
    HandheldSteps,
    _real_array,
    as_arrays,
)
from indoorloc.pdr.orientation import (  # noqa: F401
    GRAVITY_MPS2,
    _check_time_base,
    _finite_array,
    _quaternions,
    _up_row,
    complementary_heading,
    gyro_heading,
    rotation_vector_heading,
    vertical_acceleration,
    wrap_angle,
)

__all__ = [
    "HandheldArrays",
    "HandheldCalibration",
    "HandheldOptions",
    "HandheldSteps",
    "WaypointIntervals",
    "as_arrays",
    "best_yaw_offset",
    "calibrate_from_intervals",
    "calibrate_handheld",
    "complementary_heading",
    "cumulative_at",
    "detect_steps_handheld",
    "gyro_heading",
    "handheld_steps",
    "pdr_track",
    "rescale",
    "rotation_vector_heading",
    "step_displacements",
    "step_headings",
    "step_signal",
    "vertical_acceleration",
    "waypoint_intervals",
    "wrap_angle",
]
