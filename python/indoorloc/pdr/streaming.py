"""Causal hand-held step detection, one sensor sample at a time (for live tracking).

Why beside :func:`indoorloc.pdr.handheld.handheld_steps`: that detector looks at the whole walk
(zero-phase band-pass, a centred running RMS, ``find_peaks`` taking the largest peaks first, the
walk's median step interval, the walk's mean sample rate), so the steps it finds at time t depend
on samples after t. A live tracker needs steps from the past only. :class:`StreamingStepDetector`
is the same method made causal; :func:`causal_handheld_steps` runs it over a recorded walk, so a
walk replayed sample by sample gives exactly (bit for bit) the steps of the batch call. Both are
the C++ detector (``cpp/include/indoorloc/pdr/streaming_step_detector.h``, bound as
``indoorloc._core.pdr.StreamingStepDetector``), which the C++ live session
(``fusion/live_session.h``) also runs: one implementation of the model.

The method, per accelerometer sample (gyroscope and rotation vector held at their latest sample at
or before it; send them first at equal times):

1. **Rate**: the nominal rate is 1 / median of the first ``RATE_SAMPLES`` accelerometer intervals
   (the filters need one; the samples until then are kept and filtered once it is known).
2. **Signal**: |a| - g through the Butterworth low-pass (``lowpass_hz``) then high-pass
   (``highpass_hz``) of ``HandheldOptions``, run forward only (transposed direct form II, started in
   the steady state of the first sample).
3. **Threshold**: ``max(threshold_fraction x RMS over the trailing rms_window_s, min_peak_mps2)``.
4. **Peaks**: a local maximum above the threshold at least ``min_step_interval_s`` after the
   previous step becomes the candidate unless a larger candidate is pending; a candidate that no
   larger maximum displaced for ``min_step_interval_s`` is a step (so a step is known that long
   after its peak: the detector's latency).
5. **Length**: Weinberg's feature (max - min of the low-passed |a|)^(1/4) over
   ``[t - h, t + h]``, h = min(``max_step_half_window_s``, half the interval to the previous step).
6. **Heading**: per step the mean over [previous step, this step] (the first step: the
   ``2 max_step_half_window_s`` before it) of the unwrapped rotation-vector heading, the gyro
   heading (rate about the vertical integrated from the first rotation-vector heading) and the
   complementary blend (a causal first-order low-pass of their difference, ``complementary_tau_s``).

The output is a :class:`indoorloc.pdr.handheld.HandheldSteps`, so ``calibrate_handheld`` (K, yaw
offset, sds fitted on training walks' causal steps) and ``rescale`` apply unchanged. Calibrate K on
causal steps for a causal tracker: the forward-only filter changes the feature's amplitude.
"""

from __future__ import annotations

import math
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core import pdr as _pdr
from indoorloc.pdr.handheld import HandheldOptions, HandheldSteps, as_arrays

#: Accelerometer intervals whose median gives the nominal sample rate (the C++ default).
RATE_SAMPLES = _pdr.StreamingStepOptions().rate_samples

#: HandheldOptions fields the detector reads (the rest are the whole-walk detector's or the
#: calibration's).
_DETECTOR_FIELDS = ("lowpass_hz", "highpass_hz", "filter_order", "rms_window_s", "threshold_fraction",
                    "min_peak_mps2", "min_step_interval_s", "max_step_half_window_s", "complementary_tau_s")


def detector_options(options: HandheldOptions) -> Any:
    """The C++ detector's options (``_core.pdr.StreamingStepOptions``) of hand-held options.
    ValueError unless ``options.method`` is "peaks" and ``options.signal`` "magnitude"."""
    options.validate()
    if options.method != "peaks" or options.signal != "magnitude":
        raise ValueError("indoorloc: StreamingStepDetector: options.method must be 'peaks' and options.signal "
                         f"'magnitude' (got {options.method!r}, {options.signal!r})")
    return _pdr.StreamingStepOptions(**{f: getattr(options, f) for f in _DETECTOR_FIELDS})


class StreamingStepDetector:
    """Causal hand-held step detector fed one IMU sample at a time (module docstring).

    ``add_sample(t_s, acc_mps2, gyro_radps, quat_xyzw)`` returns the steps confirmed by this sample
    (usually none, at most a few): tuples ``(t_s, index, feature, heading_rv_rad, heading_gyro_rad,
    heading_complementary_rad, start_t_s, confirmed_t_s)`` (the last: this sample's time); :meth:`steps` assembles everything confirmed so far
    into a :class:`HandheldSteps`. Samples must come with increasing times (ValueError otherwise).
    """

    def __init__(self, options: Optional[HandheldOptions] = None):
        self.options = options or HandheldOptions()
        self._detector = _pdr.StreamingStepDetector(detector_options(self.options))
        self._out: List[Tuple] = []

    def add_sample(self, t_s: float, acc_mps2: Sequence[float], gyro_radps: Sequence[float],
                   quat_xyzw: Sequence[float]) -> List[Tuple]:
        """One IMU sample: time [s], specific force (3,) [m/s²] and angular rate (3,) [rad/s] in the
        device frame, unit quaternion (x, y, z, w) device -> east-north-up. Returns the steps it
        confirmed (see the class docstring)."""
        got = self._detector.add_sample(t_s, acc_mps2, gyro_radps, quat_xyzw)
        self._out += got
        return got

    def steps(self) -> HandheldSteps:
        """Every step confirmed so far as :class:`HandheldSteps` (lengths with ``options.k``)."""
        first = self._detector.first_time_s
        return _assemble(self._out, self.options, first if math.isfinite(first) else 0.0)

    @property
    def rate_hz(self) -> Optional[float]:
        """The filters' sample rate [Hz], None until ``RATE_SAMPLES + 1`` samples have come."""
        r = self._detector.rate_hz
        return r if math.isfinite(r) else None

    @property
    def latency_s(self) -> float:
        """How long after its peak a step is confirmed [s] (plus the band-pass's group delay)."""
        return self.options.min_step_interval_s


def _assemble(rows: Sequence[Tuple], options: HandheldOptions, first_t: float) -> HandheldSteps:
    """HandheldSteps from the detector's step tuples."""
    m = len(rows)
    if m == 0:
        e = np.zeros(0)
        return HandheldSteps(e, np.zeros(0, np.int64), e, e, e, e, e, e, e, e, float(first_t), options,
                             confirmed_t_s=np.zeros(0))
    a = np.array([r[:6] for r in rows], dtype=np.float64)
    feature = a[:, 2]
    length = options.k * feature
    hr, hg, hc = a[:, 3], a[:, 4], a[:, 5]
    heading = {"rotation_vector": hr, "gyro": hg, "complementary": hc}[options.heading_source]
    return HandheldSteps(
        t_s=a[:, 0].copy(), index=a[:, 1].astype(np.int64), length_m=length, heading_rad=heading.copy(),
        length_sd_m=options.length_sd_fraction * length, heading_sd_rad=np.full(m, options.heading_sd_rad),
        feature=feature.copy(), heading_rotation_vector_rad=hr.copy(), heading_gyro_rad=hg.copy(),
        heading_complementary_rad=hc.copy(), start_t_s=float(rows[0][6]), options=options,
        confirmed_t_s=np.array([r[7] for r in rows], dtype=np.float64))


def imu_samples(walk: Any) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The detector's input from a recorded walk: per accelerometer sample its time (N,) [s], force
    (N, 3), and the gyroscope (N, 3) and rotation quaternion (N, 4) held at their latest sample at
    or before it (the first sample where none is yet: the live tracker waits for all three)."""
    acc = walk.accelerometer
    gyro = walk.gyroscope
    quat = walk.rotation_quaternion_xyzw()
    t = np.asarray(acc.t_s, float)
    gi = np.searchsorted(np.asarray(gyro.t_s, float), t, side="right") - 1
    qi = np.searchsorted(np.asarray(walk.rotation_vector.t_s, float), t, side="right") - 1
    ok = (gi >= 0) & (qi >= 0)
    return t[ok], np.asarray(acc.values, float)[ok, :3], np.asarray(gyro.values, float)[gi[ok], :3], \
        np.asarray(quat, float)[qi[ok]]


def causal_handheld_steps(walk_or_arrays: Any, options: Optional[HandheldOptions] = None) -> HandheldSteps:
    """The causal steps of a recorded walk (an ``IlcWalk``, or ``HandheldArrays`` already on one
    time base): :class:`StreamingStepDetector` fed every sample, so the result equals a live replay
    of the walk bit for bit (the C++ detector, a few µs per sample)."""
    options = options or HandheldOptions()
    if hasattr(walk_or_arrays, "accelerometer"):
        t, acc, gyro, quat = imu_samples(walk_or_arrays)
    else:
        arr = as_arrays(walk_or_arrays)
        t, acc, gyro, quat = arr.t_s, arr.acc_mps2, arr.gyro_radps, arr.quat_xyzw
    rows = _pdr.causal_steps(t, acc, gyro, quat, detector_options(options))
    steps = [(r[0], int(r[1]), r[2], r[3], r[4], r[5], r[6], r[7]) for r in rows]
    return _assemble(steps, options, float(t[0]) if t.shape[0] > _pdr.StreamingStepOptions().rate_samples else 0.0)


__all__ = ["RATE_SAMPLES", "StreamingStepDetector", "causal_handheld_steps", "detector_options", "imu_samples"]
