"""Causal hand-held step detection, one sensor sample at a time (for live tracking).

Why beside :func:`indoorloc.pdr.handheld.handheld_steps`: that detector looks at the whole walk
(zero-phase band-pass, a centred running RMS, ``find_peaks`` taking the largest peaks first, the
walk's median step interval, the walk's mean sample rate), so the steps it finds at time t depend
on samples after t. A live tracker needs steps from the past only. :class:`StreamingStepDetector`
is the same method made causal; :func:`causal_handheld_steps` runs it over a recorded walk, so a
walk replayed sample by sample gives exactly (bit for bit) the steps of the batch call: both are
the same code.

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
from collections import deque
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from indoorloc._core.pdr import butterworth_sos
from indoorloc.pdr.handheld import GRAVITY_MPS2, HandheldOptions, HandheldSteps, as_arrays

#: Accelerometer intervals whose median gives the nominal sample rate.
RATE_SAMPLES = 25
_TWO_PI = 2.0 * math.pi


def _wrap(a: float) -> float:
    """Angle folded into [-pi, pi) (as ``pdr.handheld.wrap_angle``)."""
    return (a + math.pi) % _TWO_PI - math.pi


class _Sos:
    """Second-order sections (scipy's layout, rows b0 b1 b2 a0 a1 a2) run one sample at a time
    (transposed direct form II), started in the steady state of the first input."""

    def __init__(self, sos: np.ndarray):
        sos = np.asarray(sos, float)
        self.sections = [tuple(float(v) for v in (r[0], r[1], r[2], r[4], r[5])) for r in sos / sos[:, 3:4]]
        self.state: Optional[List[List[float]]] = None

    def __call__(self, x: float) -> float:
        if self.state is None:  # the steady state of a constant input x
            self.state = []
            v = x
            for b0, b1, b2, a1, a2 in self.sections:
                y0 = v * (b0 + b1 + b2) / (1.0 + a1 + a2)
                self.state.append([y0 - b0 * v, b2 * v - a2 * y0])
                v = y0
        for st, (b0, b1, b2, a1, a2) in zip(self.state, self.sections):
            y = b0 * x + st[0]
            st[0] = b1 * x - a1 * y + st[1]
            st[1] = b2 * x - a2 * y
            x = y
        return x


class StreamingStepDetector:
    """Causal hand-held step detector fed one IMU sample at a time (module docstring).

    ``add_sample(t_s, acc_mps2, gyro_radps, quat_xyzw)`` returns the steps confirmed by this sample
    (usually none, at most a few): tuples ``(t_s, index, feature, heading_rv_rad, heading_gyro_rad,
    heading_complementary_rad, start_t_s)``; :meth:`steps` assembles everything confirmed so far
    into a :class:`HandheldSteps`. Samples must come with increasing times (ValueError otherwise).
    """

    def __init__(self, options: Optional[HandheldOptions] = None):
        self.options = options or HandheldOptions()
        self.options.validate()
        if self.options.method != "peaks" or self.options.signal != "magnitude":
            raise ValueError("indoorloc: StreamingStepDetector: options.method must be 'peaks' and options.signal "
                             f"'magnitude' (got {self.options.method!r}, {self.options.signal!r})")
        self._buffer: List[Tuple[float, np.ndarray, np.ndarray, np.ndarray]] = []
        self.rate_hz: Optional[float] = None
        self._n = 0                   # samples processed (the index of the next one)
        self._last_t = -math.inf
        self._out: List[Tuple[float, int, float, float, float, float, float]] = []
        self._first_t: Optional[float] = None

    # ------------------------------------------------------------------ input
    def add_sample(self, t_s: float, acc_mps2: Sequence[float], gyro_radps: Sequence[float],
                   quat_xyzw: Sequence[float]) -> List[Tuple]:
        """One IMU sample: time [s], specific force (3,) [m/s²] and angular rate (3,) [rad/s] in the
        device frame, unit quaternion (x, y, z, w) device -> east-north-up. Returns the steps it
        confirmed (see the class docstring)."""
        t = float(t_s)
        if not math.isfinite(t):
            raise ValueError(f"indoorloc: StreamingStepDetector.add_sample: argument 't_s' must be finite, got {t_s!r}")
        if t <= self._last_t:
            raise ValueError(f"indoorloc: StreamingStepDetector.add_sample: sample at t = {t} s is not after the "
                             f"previous one (t = {self._last_t} s)")
        self._last_t = t
        sample = (t, tuple(float(v) for v in acc_mps2), tuple(float(v) for v in gyro_radps),
                  tuple(float(v) for v in quat_xyzw))
        if self.rate_hz is None:
            self._buffer.append(sample)
            if len(self._buffer) <= RATE_SAMPLES:
                return []
            dt = np.diff([s[0] for s in self._buffer])
            self.rate_hz = float(1.0 / np.median(dt))
            self._start_filters()
            out: List[Tuple] = []
            for s in self._buffer:
                out += self._process(*s)
            self._buffer = []
            return out
        return self._process(*sample)

    def steps(self) -> HandheldSteps:
        """Every step confirmed so far as :class:`HandheldSteps` (lengths with ``options.k``)."""
        return _assemble(self._out, self.options, self._first_t if self._first_t is not None else 0.0)

    @property
    def latency_s(self) -> float:
        """How long after its peak a step is confirmed [s] (plus the band-pass's group delay)."""
        return self.options.min_step_interval_s

    # ------------------------------------------------------------------ internals
    def _start_filters(self) -> None:
        o, rate = self.options, self.rate_hz
        order = int(o.filter_order)
        self._lp = _Sos(butterworth_sos(order, min(o.lowpass_hz, 0.45 * rate), rate))
        self._hp = _Sos(butterworth_sos(order, o.highpass_hz, rate, True))
        fc = 1.0 / (2.0 * math.pi * o.complementary_tau_s)
        self._comp = None if fc >= 0.45 * rate else _Sos(butterworth_sos(1, fc, rate))
        self._rms: deque = deque()        # (t, s²) over the trailing window
        self._rms_sum = 0.0
        self._recent: deque = deque()     # (t, index, lp, I_rv, I_gyro, I_comp) of the last seconds
        self._s_prev2 = self._s_prev = None   # band-passed signal at i - 2, i - 1
        self._thr_prev = math.inf
        self._t_prev = None
        self._candidate: Optional[Tuple[float, int, float]] = None  # (t, index, value)
        self._last_step: Optional[Tuple[float, float, float, float]] = None  # (t, I_rv, I_gyro, I_comp)
        self._h = None                    # (raw rv heading, unwrapped rv, gyro, complementary, w_up)
        self._integrals = (0.0, 0.0, 0.0)

    def _process(self, t: float, acc: Tuple, gyro: Tuple, q: Tuple) -> List[Tuple]:
        o = self.options
        i = self._n
        self._n += 1
        if self._first_t is None:
            self._first_t = t
        # Signal and its low-pass (the Weinberg feature's input).
        mag = math.sqrt(acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2]) - GRAVITY_MPS2
        lp = self._lp(mag)
        s = self._hp(lp)
        # Headings (module docstring, 6) and their running integrals (trapezoid).
        x, y, z, w = q
        raw = math.atan2(1.0 - 2.0 * (x * x + z * z), 2.0 * (x * y - w * z))
        w_up = (2.0 * (x * z - w * y)) * gyro[0] + (2.0 * (y * z + w * x)) * gyro[1] + \
            (1.0 - 2.0 * (x * x + y * y)) * gyro[2]
        if self._h is None:
            h_rv, h_gy = raw, raw
        else:
            raw_prev, rv_prev, gy_prev, _, w_prev = self._h
            dt = t - self._t_prev
            h_rv = rv_prev + _wrap(raw - raw_prev)
            h_gy = gy_prev + 0.5 * (w_prev + w_up) * dt
        if self._comp is None:
            h_c = h_rv
        else:
            h_c = h_gy + self._comp(h_rv - h_gy)
        if self._h is not None:
            _, rv_prev, gy_prev, c_prev, _ = self._h
            dt = t - self._t_prev
            i_rv, i_gy, i_c = self._integrals
            self._integrals = (i_rv + 0.5 * (rv_prev + h_rv) * dt, i_gy + 0.5 * (gy_prev + h_gy) * dt,
                               i_c + 0.5 * (c_prev + h_c) * dt)
        self._h = (raw, h_rv, h_gy, h_c, w_up)
        self._recent.append((t, i, lp) + self._integrals + (h_rv, h_gy, h_c))
        keep_s = 3.0 * o.max_step_half_window_s + 2.0 * o.min_step_interval_s + 1.0
        while self._recent and self._recent[0][0] < t - keep_s:
            self._recent.popleft()
        # Trailing RMS and threshold.
        self._rms.append((t, s * s))
        self._rms_sum += s * s
        while self._rms[0][0] < t - o.rms_window_s:
            self._rms_sum -= self._rms.popleft()[1]
        thr = max(o.threshold_fraction * math.sqrt(max(self._rms_sum, 0.0) / len(self._rms)), o.min_peak_mps2)
        out: List[Tuple] = []
        # Sample i - 1 a local maximum above its threshold: a candidate.
        if self._s_prev2 is not None and self._s_prev > self._s_prev2 and self._s_prev >= s \
                and self._s_prev >= self._thr_prev:
            tp = self._t_prev
            far = self._last_step is None or tp - self._last_step[0] >= o.min_step_interval_s
            if far and (self._candidate is None or self._s_prev > self._candidate[2]):
                self._candidate = (tp, i - 1, self._s_prev)
        if self._candidate is not None and t - self._candidate[0] >= o.min_step_interval_s:
            out.append(self._confirm(t))
            self._candidate = None
        self._s_prev2, self._s_prev, self._thr_prev, self._t_prev = self._s_prev, s, thr, t
        return out

    def _confirm(self, t_now: float) -> Tuple:
        o = self.options
        tc, ic, _ = self._candidate
        hw = o.max_step_half_window_s
        half = hw if self._last_step is None else min(hw, 0.5 * (tc - self._last_step[0]))
        lo_t, hi_t = tc - half, tc + half
        lps = [r[2] for r in self._recent if lo_t <= r[0] <= hi_t]
        feature = max(0.0, max(lps) - min(lps)) ** 0.25 if lps else 0.0
        at_c = next(r for r in self._recent if r[1] == ic)
        if self._last_step is None:  # the first step: the interval before it
            t_a = max(self._first_t, tc - 2.0 * hw)
            a = next((r for r in self._recent if r[0] >= t_a), at_c)
            start = (a[0], a[3], a[4], a[5])
        else:
            start = self._last_step
        width = tc - start[0]
        if width > 1e-9:
            heads = tuple((at_c[3 + j] - start[1 + j]) / width for j in range(3))
        else:
            heads = (at_c[6], at_c[7], at_c[8])
        step = (tc, ic, feature, _wrap(heads[0]), _wrap(heads[1]), _wrap(heads[2]), start[0])
        self._last_step = (tc, at_c[3], at_c[4], at_c[5])
        self._out.append(step)
        return step


def _assemble(rows: Sequence[Tuple], options: HandheldOptions, first_t: float) -> HandheldSteps:
    """HandheldSteps from the detector's step tuples."""
    m = len(rows)
    if m == 0:
        e = np.zeros(0)
        return HandheldSteps(e, np.zeros(0, np.int64), e, e, e, e, e, e, e, e, float(first_t), options)
    a = np.array([r[:6] for r in rows], dtype=np.float64)
    feature = a[:, 2]
    length = options.k * feature
    hr, hg, hc = a[:, 3], a[:, 4], a[:, 5]
    heading = {"rotation_vector": hr, "gyro": hg, "complementary": hc}[options.heading_source]
    return HandheldSteps(
        t_s=a[:, 0].copy(), index=a[:, 1].astype(np.int64), length_m=length, heading_rad=heading.copy(),
        length_sd_m=options.length_sd_fraction * length, heading_sd_rad=np.full(m, options.heading_sd_rad),
        feature=feature.copy(), heading_rotation_vector_rad=hr.copy(), heading_gyro_rad=hg.copy(),
        heading_complementary_rad=hc.copy(), start_t_s=float(rows[0][6]), options=options)


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
    of the walk bit for bit. About 20 µs per sample (pure Python)."""
    det = StreamingStepDetector(options)
    if hasattr(walk_or_arrays, "accelerometer"):
        t, acc, gyro, quat = imu_samples(walk_or_arrays)
    else:
        arr = as_arrays(walk_or_arrays)
        t, acc, gyro, quat = arr.t_s, arr.acc_mps2, arr.gyro_radps, arr.quat_xyzw
    for k in range(t.shape[0]):
        det.add_sample(t[k], acc[k], gyro[k], quat[k])
    return det.steps()


__all__ = ["RATE_SAMPLES", "StreamingStepDetector", "causal_handheld_steps", "imu_samples"]
