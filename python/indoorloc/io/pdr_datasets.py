"""Loaders for public foot-mounted IMU recordings (numpy + scipy.io only).

Three on-disk formats are read into one in-memory layout, :class:`ImuRecording`, always in SI
units (specific force in m/s^2, angular rate in rad/s, time in s), in the *sensor* frame as
recorded (no axis is flipped: the ZUPT filter estimates the initial attitude from the first still
samples, so any mounting works):

- x-io Gait-Tracking ``short_walk.csv`` / ``long_walk.csv`` (NGIMU on the shoe, ~400 Hz; file
  units deg/s and g, converted here), :func:`load_xio`;
- the OpenShoe figure-8 ``OpenShoeDataSet.txt`` (820 Hz, headerless, acc m/s^2, gyro rad/s, no
  time column), :func:`load_openshoe`;
- the PyShoe / University of Toronto Vicon trials as repackaged by LLIO-aided-iPyShoe
  (``*_LLIO.mat``: ``imu_data``, ``timestamps_all``, ``gt``, ``strideIndex``; 200 Hz),
  :func:`load_pyshoe_trial` and :func:`list_pyshoe_trials`.

Every loader checks the units it declares with :func:`check_imu_units` and raises
``ValueError("indoorloc: argument '<name>': ...")`` naming the argument and the unit the values
most likely are in (e.g. a gyro in deg/s declared as rad/s, an accelerometer in g declared as
m/s^2).

Oddities of the files (found when writing these loaders)
--------------------------------------------------------
- x-io: 205 (short) / 252 (long) rows repeat the timestamp of the previous row, and every one of
  them is an exact copy of the previous row (a re-sent packet; the step before it is usually two
  or three sample periods long, i.e. a packet was lost and the last one repeated). We **remove
  exact duplicate rows** (keep the first); nudging the time would invent a sample that was never
  measured. A repeated timestamp whose data differ is not in these files and raises
  ``ValueError``. After removal the time is strictly increasing with gaps of up to ~17 ms.
- x-io: at rest the sensor is tilted (acc about (-0.49, 0.24, 0.83) g), the gravity constant used
  for the conversion is the standard 9.80665 m/s^2.
- PyShoe: the sensor z axis points down (acc z about -9.4 m/s^2 at rest); ``strideIndex`` is
  0-based (``timestamps_all[strideIndex] == timestamps``) and its first entry is the rest before
  the first step (Vicon position about (0, 0)), so a trial with S indices has S - 1 strides;
  ``timestamps_all`` jitters (smallest step ~1.3 ms at a nominal 5 ms).
- OpenShoe: no time column; the time is built as ``k / rate_hz``.
- mobgap (Mobilise-D lower-back unit, 100 Hz): ``Acc`` in g, ``Gyr`` in deg/s, ``Mag`` in uT,
  ``Timestamp`` in Unix seconds; ``Standards.INDIP.MicroWB`` is a struct when a test has one
  walking bout and a struct array otherwise, and is empty for HA/002 Test5 (no reference).
  ``Stride_InitialContacts`` are sample numbers at 100 Hz that equal ``InitialContact_Event``
  [s] times 100 (505 <-> 5.05 s), used here as 0-based indices; strides with a NaN contact or
  length (the INDIP could not resolve them) are dropped.

Examples
--------
>>> from indoorloc.io import load_xio
>>> rec = load_xio("../shared/data/pdr/xio_gait_tracking/short_walk.csv")  # doctest: +SKIP
>>> rec.acc_mps2.shape, round(rec.rate_hz)  # doctest: +SKIP
((16334, 3), 398)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, List, Optional, Tuple, Union

import numpy as np

from indoorloc.io.errors import reads_file
from indoorloc.validate import real_array
PathLike = Union[str, Path]

#: Standard gravity [m/s^2] used to convert accelerations given in g.
STANDARD_GRAVITY_MPS2 = 9.80665

# Plausibility limits of the unit checks. A foot-mounted IMU peaks at ~17 rad/s (~1000 deg/s)
# in the recordings here and common MEMS gyros saturate at 2000 deg/s (34.9 rad/s); a walking
# foot's median rate is below 5 rad/s even when running. The median |specific force| of any
# recording is near g (9.8-17 m/s^2 here, running included).
_GYRO_P99_MAX_RADPS = 35.0
_GYRO_MEDIAN_MAX_RADPS = 10.0
_GYRO_P99_MIN_MOVING_RADPS = 0.2
_ACC_MOVING_STD_MPS2 = 1.0
_ACC_MEDIAN_RANGE_MPS2 = (4.0, 30.0)

# Nominal distances walked [m] given by the sources (approximate: "about").
_XIO_DISTANCE_M = {"short_walk": 25.0, "long_walk": 60.0}
_OPENSHOE_DISTANCE_M = 81.0


@dataclass
class ImuRecording:
    """One foot-mounted IMU recording in SI units, sensor frame.

    Attributes
    ----------
    name : str
        Recording name (file stem).
    time_s : (N,) float
        Sample times [s], strictly increasing.
    acc_mps2 : (N, 3) float
        Specific force [m/s^2] in the sensor frame (about +g along "up" at rest).
    gyro_radps : (N, 3) float
        Angular rate [rad/s] in the sensor frame.
    rate_hz : float
        Nominal sample rate [Hz] (1 / median time step, or as given).
    truth_xy_m : (N, 2) float or None
        Per-sample reference position [m] (Vicon for PyShoe), None when there is none.
    stride_indices : (S,) int or None
        0-based sample indices of annotated foot-rest points (stride ends), None when absent.
    closed_loop : bool
        True when the walk ends where it started (the final position error is the metric).
    distance_m : float or None
        Distance walked [m] (nominal from the source, or the truth's path length through the
        stride points), None when unknown.
    source_units : str
        The units the file stores, for the record (e.g. ``"gyro deg/s, acc g"``).
    sensor : str
        Sensor / dataset family (``"xio"``, ``"openshoe"``, ``"pyshoe"``, ``"mobgap"``): methods
        may keep one parameter set per sensor.
    mag_uT : (N, 3) float or None
        Magnetic field [uT] in the sensor frame when the recording has a magnetometer.
    """

    name: str
    time_s: np.ndarray
    acc_mps2: np.ndarray
    gyro_radps: np.ndarray
    rate_hz: float
    truth_xy_m: Optional[np.ndarray]
    stride_indices: Optional[np.ndarray]
    closed_loop: bool
    distance_m: Optional[float]
    source_units: str
    sensor: str = ""
    mag_uT: Optional[np.ndarray] = None

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.time_s.shape[0])

    @property
    def duration_s(self) -> float:
        """Time between the first and last samples [s]."""
        return float(self.time_s[-1] - self.time_s[0])


def _err(argument: str, message: str) -> ValueError:
    return ValueError(f"indoorloc: argument '{argument}': {message}")


def check_imu_units(acc_mps2: np.ndarray, gyro_radps: np.ndarray, *, acc_name: str = "acc_mps2",
                    gyro_name: str = "gyro_radps") -> None:
    """Check that IMU samples are plausibly in m/s^2 and rad/s; raise ValueError if not.

    Checks, on (N, 3) finite arrays:

    - median |acc| must lie in [4, 30] m/s^2 (gravity dominates any recording). About 1 means
      the values are in g; about 96 (9.8^2) means m/s^2 were multiplied by g again.
    - |gyro|: the 99th percentile must be below 35 rad/s (2000 deg/s, a MEMS gyro's full scale)
      and the median below 10 rad/s; larger values mean deg/s. When the accelerometer shows motion
      (sd of |acc| above 1 m/s^2) a 99th percentile below 0.2 rad/s means rad/s converted from
      deg/s twice (values ~57 times too small).

    The error message names the argument (``acc_name`` / ``gyro_name``) and the likely unit.
    """
    acc = real_array(acc_mps2, acc_name)  # refuses strings, complex, NaN and inf, naming it
    gyro = real_array(gyro_radps, gyro_name)
    for name, a in ((acc_name, acc), (gyro_name, gyro)):
        if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] == 0:
            raise _err(name, f"expected a non-empty (N, 3) array, got shape {a.shape}")
        if not np.all(np.isfinite(a)):
            raise _err(name, "contains NaN or inf")
    if acc.shape[0] != gyro.shape[0]:
        raise _err(gyro_name, f"has {gyro.shape[0]} rows but {acc_name} has {acc.shape[0]}")

    acc_norm = np.linalg.norm(acc, axis=1)
    acc_median = float(np.median(acc_norm))
    lo, hi = _ACC_MEDIAN_RANGE_MPS2
    if not lo <= acc_median <= hi:
        if lo <= acc_median * STANDARD_GRAVITY_MPS2 <= hi:
            likely = "g (multiply by 9.80665)"
        elif lo <= acc_median / STANDARD_GRAVITY_MPS2 <= hi:
            likely = "m/s^2 multiplied by g once too often"
        else:
            likely = "an unknown unit"
        raise _err(acc_name, f"declared m/s^2 but median |acc| = {acc_median:.3g}, expected about "
                             f"9.8 (between {lo} and {hi}): the values look like {likely}")

    gyro_norm = np.linalg.norm(gyro, axis=1)
    gyro_p99 = float(np.percentile(gyro_norm, 99))
    gyro_median = float(np.median(gyro_norm))
    if gyro_p99 > _GYRO_P99_MAX_RADPS or gyro_median > _GYRO_MEDIAN_MAX_RADPS:
        raise _err(gyro_name, f"declared rad/s but median |gyro| = {gyro_median:.3g} and 99th "
                              f"percentile = {gyro_p99:.3g} rad/s, beyond a foot's or a MEMS gyro's "
                              f"range: the values look like deg/s (multiply by pi/180)")
    if float(np.std(acc_norm)) > _ACC_MOVING_STD_MPS2 and gyro_p99 < _GYRO_P99_MIN_MOVING_RADPS:
        raise _err(gyro_name, f"declared rad/s but the 99th percentile of |gyro| is only "
                              f"{gyro_p99:.3g} rad/s while the accelerometer shows motion: the "
                              f"values look like deg/s converted to rad/s twice (or a wrong scale)")


class IrregularTimestampsWarning(UserWarning):
    """The time stamps of a recording are irregular (see :func:`fit_sample_rate`)."""


#: A step is irregular when it differs from the fitted period by more than this fraction of the
#: period, and a time base is irregular when more than IRREGULAR_STEP_SHARE of its steps are. A
#: PyShoe trial's stamps jitter by +-4 % (1st-99th percentile of dt 4.8-5.2 ms at 5 ms) and
#: are regular by this test; x-io's re-sent packets (a repeated stamp after a 2-3-period gap) and
#: a logger that stamps bursts of samples with one time are not.
IRREGULAR_STEP_TOLERANCE = 0.25
IRREGULAR_STEP_SHARE = 0.01


def fit_sample_rate(time_s: np.ndarray, *, argument: str = "time_s", warn: bool = True,
                    name: str = "") -> Tuple[float, dict]:
    """Sample rate [Hz] from a robust straight-line fit of the time stamps ``t_k = t_0 + k T``.

    The period T is the median over k of ``(t_{k+L} - t_k) / L`` with a long lag L = max(1,
    (N - 1) // 20): jitter averages out over L samples, and bursts of equal stamps, a few
    dropped or re-sent packets or a clock step affect a minority of the windows, which the
    median ignores (1 / median(dt) fails when a logger stamps samples in bursts: the median
    step is then 0 or a multiple of T). Returns ``(rate_hz, info)`` with ``info`` = ``{"period_s",
    "irregular" (bool), "irregular_share" (share of steps off T by more than
    :data:`IRREGULAR_STEP_TOLERANCE` x T, or not increasing), "max_step_s", "min_step_s",
    "fit_rms_s" (RMS residual of the stamps about the fitted line, offset by its median)}``.
    Issues an :class:`IrregularTimestampsWarning` (when ``warn``) if more than
    :data:`IRREGULAR_STEP_SHARE` of the steps are irregular. Raises ValueError (naming
    ``argument``) when there are fewer than two stamps, non-finite ones, or no increase.
    """
    t = np.asarray(time_s, dtype=float).ravel()
    if t.size < 2:
        raise _err(argument, "needs at least two samples")
    if not np.all(np.isfinite(t)):
        raise _err(argument, "time stamps contain NaN or inf")
    n = t.size
    lag = max(1, (n - 1) // 20)
    slopes = (t[lag:] - t[:-lag]) / lag
    period = float(np.median(slopes))
    if not period > 0:
        raise _err(argument, "the time stamps do not increase")
    dt = np.diff(t)
    bad = (dt <= 0) | (np.abs(dt - period) > IRREGULAR_STEP_TOLERANCE * period)
    share = float(np.mean(bad))
    resid = t - period * np.arange(n)
    resid -= np.median(resid)
    info = {"period_s": period, "irregular": share > IRREGULAR_STEP_SHARE, "irregular_share": share,
            "max_step_s": float(dt.max()), "min_step_s": float(dt.min()),
            "fit_rms_s": float(np.sqrt(np.mean(resid ** 2)))}
    if warn and info["irregular"]:
        warnings.warn(f"indoorloc: {name or argument}: irregular time stamps: {100 * share:.1f} % of the "
                      f"steps differ from the fitted period {1e3 * period:.3f} ms by more than "
                      f"{100 * IRREGULAR_STEP_TOLERANCE:.0f} % (steps {1e3 * dt.min():.3f} to "
                      f"{1e3 * dt.max():.3f} ms); the rate {1.0 / period:.3f} Hz comes from a robust fit",
                      IrregularTimestampsWarning, stacklevel=3)
    return 1.0 / period, info


def _rate_from_time(time_s: np.ndarray, argument: str, where: str = "") -> float:
    prefix = f"{where}: " if where else ""
    dt = np.diff(time_s)
    if dt.size == 0:
        raise _err(argument, f"{prefix}needs at least two samples")
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0))
        raise _err(argument, f"{prefix}time is not strictly increasing at row {k + 1} "
                             f"({float(time_s[k])!r} then {float(time_s[k + 1])!r})")
    return float(1.0 / np.median(dt))


def _require_file(path: PathLike, argument: str = "path") -> Path:
    p = Path(path)
    if not p.is_file():
        raise _err(argument, f"file not found: {p}")
    return p


@reads_file("path")
def load_xio(path: PathLike, *, gravity_mps2: float = STANDARD_GRAVITY_MPS2) -> ImuRecording:
    """Load an x-io Gait-Tracking csv (``short_walk.csv`` / ``long_walk.csv``).

    The file has a header row and columns ``Time (s)``, gyroscope X/Y/Z in deg/s, accelerometer
    X/Y/Z in g. Converted to rad/s and m/s^2 (``gravity_mps2`` per g). Rows that are exact copies
    of the previous row (same timestamp and data: re-sent packets) are removed; a repeated
    timestamp with different data raises ValueError. The walks are closed loops (start = end);
    ``distance_m`` is the source's approximate length (25 m short, 60 m long) or None for other
    file names.
    """
    p = _require_file(path)
    with p.open("r", encoding="utf-8") as f:
        header = f.readline().strip().split(",")
    if len(header) != 7 or "deg/s" not in header[1] or "(g)" not in header[4]:
        raise _err("path", f"{p}: expected the x-io header 'Time (s),Gyroscope X (deg/s),...,"
                           f"Accelerometer Z (g)', got {','.join(header)!r}")
    data = np.loadtxt(p, delimiter=",", skiprows=1, ndmin=2)
    if data.shape[1] != 7:
        raise _err("path", f"{p}: expected 7 columns, got {data.shape[1]}")
    keep = np.ones(data.shape[0], dtype=bool)
    keep[1:] = np.any(data[1:] != data[:-1], axis=1)  # drop exact repeats of the previous row
    data = data[keep]
    time_s = data[:, 0]
    rate_hz = _rate_from_time(time_s, "path", str(p))
    gyro = np.deg2rad(data[:, 1:4])
    acc = data[:, 4:7] * float(gravity_mps2)
    check_imu_units(acc, gyro, acc_name="path (accelerometer columns, converted from g)",
                    gyro_name="path (gyroscope columns, converted from deg/s)")
    return ImuRecording(name=p.stem, time_s=time_s, acc_mps2=acc, gyro_radps=gyro,
                        rate_hz=rate_hz, truth_xy_m=None, stride_indices=None, closed_loop=True,
                        distance_m=_XIO_DISTANCE_M.get(p.stem), source_units="gyro deg/s, acc g",
                        sensor="xio")


@reads_file("path")
def load_openshoe(path: PathLike, rate_hz: float = 820.0) -> ImuRecording:
    """Load the OpenShoe data set (``OpenShoeDataSet.txt``): headerless, 6 comma-separated
    floats per row, acc x, y, z in m/s^2 then gyro x, y, z in rad/s, sampled at ``rate_hz``.

    The time is ``k / rate_hz``. The recording is the closed figure-8 of about 81 m (the
    ``distance_m`` given when the file is named ``OpenShoeDataSet.txt``).
    """
    p = _require_file(path)
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise _err("rate_hz", f"must be a positive finite rate in Hz, got {rate_hz!r}")
    data = np.loadtxt(p, delimiter=",", ndmin=2)
    if data.shape[1] != 6:
        raise _err("path", f"{p}: expected 6 columns (acc m/s^2, gyro rad/s), got {data.shape[1]}")
    acc, gyro = data[:, 0:3], data[:, 3:6]
    check_imu_units(acc, gyro, acc_name="path (columns 1-3, acc declared m/s^2)",
                    gyro_name="path (columns 4-6, gyro declared rad/s)")
    time_s = np.arange(data.shape[0], dtype=float) / float(rate_hz)
    distance = _OPENSHOE_DISTANCE_M if p.name == "OpenShoeDataSet.txt" else None
    return ImuRecording(name=p.stem, time_s=time_s, acc_mps2=acc, gyro_radps=gyro,
                        rate_hz=float(rate_hz), truth_xy_m=None, stride_indices=None,
                        closed_loop=True, distance_m=distance,
                        source_units="acc m/s^2, gyro rad/s", sensor="openshoe")


@reads_file("path")
def load_pyshoe_trial(path: PathLike, *, rate_hz: float = 200.0, regular_time: Optional[bool] = None) -> ImuRecording:
    """Load one PyShoe Vicon trial (``*_LLIO.mat`` of LLIO-aided-iPyShoe), or a recording of the
    same layout without per-sample truth.

    Reads ``imu_data`` (N x 6: acc m/s^2, gyro rad/s; sensor z points down, so acc z is about
    -9.8 at rest) and, where present, ``timestamps_all`` (N, s), ``gt`` (N x 2, Vicon x, y in m),
    ``strideIndex`` (0-based sample indices of foot-rest points; the first is the rest before the
    first step) and ``timestamps`` (the times of the stride points). Only ``imu_data`` is
    required: a recording with IMU and stride annotations but no per-sample truth loads with
    ``truth_xy_m = None`` (then ``distance_m`` is None too).

    Time base: ``timestamps_all`` when present (checked by :func:`fit_sample_rate`, which warns
    when the stamps are irregular); otherwise, when ``strideIndex`` and ``timestamps`` are both
    there, the rate is the least-squares slope of ``timestamps`` against ``strideIndex`` (the
    stamps of the stride points are a sparse sample of the clock) and the time a regular grid
    at that rate; otherwise a regular grid at ``rate_hz`` (200 Hz, this sensor's nominal rate).
    ``regular_time``: True replaces the stamps by the fitted regular grid ``t_0 + k / rate``
    (what a logger with a jittery or bursty clock really sampled); None (default) does so only
    when the stamps are irregular or not strictly increasing; False keeps the stamps (and raises
    if they do not strictly increase). ``rate_hz`` of the recording is always the robust fit.
    """
    from scipy.io import loadmat

    p = _require_file(path)
    if not (np.isfinite(rate_hz) and rate_hz > 0):
        raise _err("rate_hz", f"must be a positive finite rate in Hz, got {rate_hz!r}")
    try:
        mat = loadmat(p)
    except Exception as exc:  # scipy raises several types for a bad file
        raise _err("path", f"{p}: not a readable MATLAB file ({exc})") from exc
    if "imu_data" not in mat:
        raise _err("path", f"{p}: variable 'imu_data' missing (the IMU samples are required)")
    imu = np.asarray(mat["imu_data"], dtype=float)
    if imu.ndim != 2 or imu.shape[1] != 6:
        raise _err("path", f"{p}: imu_data must be N x 6, got {imu.shape}")
    n = imu.shape[0]
    strides = (np.asarray(mat["strideIndex"]).ravel().astype(np.int64) if "strideIndex" in mat else None)
    if strides is not None:
        if strides.size and (strides.min() < 0 or strides.max() >= n):
            raise _err("path", f"{p}: strideIndex outside [0, {n})")
        if np.any(np.diff(strides) <= 0):
            raise _err("path", f"{p}: strideIndex is not strictly increasing")
    gt = None
    if "gt" in mat:
        gt = np.asarray(mat["gt"], dtype=float)
        if gt.shape != (n, 2):
            raise _err("path", f"{p}: gt {gt.shape} must have one row (x, y) per imu_data row ({n})")
    acc, gyro = imu[:, 0:3], imu[:, 3:6]
    check_imu_units(acc, gyro, acc_name="path (imu_data columns 1-3, acc declared m/s^2)",
                    gyro_name="path (imu_data columns 4-6, gyro declared rad/s)")
    name = p.stem[:-5] if p.stem.endswith("_LLIO") else p.stem
    if "timestamps_all" in mat:
        stamps = np.asarray(mat["timestamps_all"], dtype=float).ravel()
        if stamps.shape[0] != n:
            raise _err("path", f"{p}: timestamps_all ({stamps.shape[0]}) must have one entry per imu_data row ({n})")
        fitted_rate, info = fit_sample_rate(stamps, argument="path", name=f"{p.name} timestamps_all")
        increasing = bool(np.all(np.diff(stamps) > 0))
        use_grid = (not increasing or info["irregular"]) if regular_time is None else bool(regular_time)
        if not use_grid and not increasing:
            _rate_from_time(stamps, "path", str(p))  # raises, naming the first bad row
        offset = float(np.median(stamps - np.arange(n) / fitted_rate))
        time_s = offset + np.arange(n) / fitted_rate if use_grid else stamps
        units = "acc m/s^2, gyro rad/s" + (", time: regular grid fitted to timestamps_all" if use_grid else "")
    else:
        fitted_rate = float(rate_hz)
        units = f"acc m/s^2, gyro rad/s, time: regular grid at {rate_hz:g} Hz (no timestamps_all)"
        if strides is not None and strides.size >= 2 and "timestamps" in mat:
            st = np.asarray(mat["timestamps"], dtype=float).ravel()
            if st.shape[0] == strides.shape[0] and np.all(np.isfinite(st)):
                slope = float(np.polyfit(strides.astype(float), st, 1)[0])
                if slope > 0:
                    fitted_rate = 1.0 / slope
                    units = "acc m/s^2, gyro rad/s, time: regular grid at the rate fitted to the stride stamps"
        time_s = np.arange(n, dtype=float) / fitted_rate
    distance = (float(np.sum(np.linalg.norm(np.diff(gt[strides], axis=0), axis=1)))
                if gt is not None and strides is not None and strides.size >= 2 else None)
    return ImuRecording(name=name, time_s=time_s, acc_mps2=acc, gyro_radps=gyro,
                        rate_hz=float(fitted_rate), truth_xy_m=gt, stride_indices=strides, closed_loop=False,
                        distance_m=distance, source_units=units, sensor="pyshoe")


def _files_in(root: PathLike, pattern: str, none_found: str) -> List[Path]:
    """Sorted files matching ``pattern`` under the folder ``root``; ValueError naming 'root' when
    it is not a folder or nothing matches (``none_found`` + the folder)."""
    r = Path(root)
    if not r.is_dir():
        raise _err("root", f"folder not found: {r}")
    files = sorted(r.glob(pattern))
    if not files:
        raise _err("root", f"{none_found} {r}")
    return files


@reads_file("root")
def list_pyshoe_trials(root: PathLike) -> List[Path]:
    """Sorted paths of the PyShoe trials (``*.mat``) in the folder ``root``.

    Raises ValueError when ``root`` is not a folder or holds no ``.mat`` file.
    """
    return _files_in(root, "*.mat", "no PyShoe trial (*.mat) in")


@dataclass
class MobgapTrial:
    """One Mobilise-D lower-back trial with its INDIP reference strides.

    Attributes
    ----------
    recording : ImuRecording
        The lower-back IMU in SI units (acc m/s^2, gyro rad/s, ``mag_uT``), time from 0 s.
    subject : str
        ``"HA/001"``-style subject folder.
    test, trial : str
        ``"Test5"`` / ``"Test11"`` and ``"Trial1"``...
    stride_intervals : (S, 2) int
        0-based sample indices [start, end] of the reference strides (initial contact to the
        next initial contact of the same foot).
    stride_lengths_m : (S,) float
        INDIP stride lengths [m].
    bout_bounds_s : (B, 2) float
        Start and end [s] of the reference walking bouts (MicroWB).
    bout_initial_contacts : list of (C,) int
        Sample indices of every initial contact (both feet) per bout (NaN contacts dropped).
    """

    recording: ImuRecording
    subject: str
    test: str
    trial: str
    stride_intervals: np.ndarray
    stride_lengths_m: np.ndarray
    bout_bounds_s: np.ndarray
    bout_initial_contacts: List[np.ndarray]

    @property
    def name(self) -> str:
        """``"HA/001 Test5 Trial1"``."""
        return f"{self.subject} {self.test} {self.trial}"


def _as_bouts(micro_wb) -> list:
    if isinstance(micro_wb, dict):
        return [micro_wb]
    if isinstance(micro_wb, (list, tuple)):
        return [b for b in micro_wb if isinstance(b, dict)]
    arr = np.asarray(micro_wb, dtype=object)
    return [b for b in arr.ravel() if isinstance(b, dict)]


def _mat_numbers(value: Any, where: str) -> np.ndarray:
    """A finite real array from a MATLAB field (complex, text, structs and NaN refused, naming
    the file and the field)."""
    a = np.asarray(value)
    if a.dtype.kind not in "biuf":
        raise _err("path", f"{where}: expected real numbers, got {a.dtype} data")
    a = a.astype(float)
    if not np.all(np.isfinite(a)):
        raise _err("path", f"{where}: holds NaN or inf")
    return a


@reads_file("path")
def load_mobgap_trials(path: PathLike, *, gravity_mps2: float = STANDARD_GRAVITY_MPS2) -> List[MobgapTrial]:
    """Load every trial of one mobgap ``data.mat`` (Mobilise-D lower-back example data).

    ``path`` is a subject's ``data.mat`` (e.g. ``.../mobgap_lowerback/HA/001/data.mat``); the
    subject name is the two folders above it. Reads
    ``data.TimeMeasure1.<Test>.<Trial>.SU.LowerBack.{Acc [g], Gyr [deg/s], Mag [uT],
    Timestamp [s]}`` and the INDIP ``MicroWB`` reference; converts to m/s^2 (``gravity_mps2``
    per g) and rad/s and checks the units with :func:`check_imu_units`. Trials without a
    reference walking bout are returned with empty stride arrays.
    """
    from scipy.io import loadmat

    p = _require_file(path)
    try:
        mat = loadmat(p, simplify_cells=True)
    except Exception as exc:
        raise _err("path", f"{p}: not a readable MATLAB file ({exc})") from exc
    try:
        measure = mat["data"]["TimeMeasure1"]
    except (KeyError, TypeError) as exc:
        raise _err("path", f"{p}: no data.TimeMeasure1 struct") from exc
    subject = f"{p.parent.parent.name}/{p.parent.name}"
    out: List[MobgapTrial] = []
    for test in sorted(measure, key=lambda t: int(t[4:]) if t[4:].isdigit() else 0):
        for trial in sorted(measure[test]):
            node = measure[test][trial]
            try:
                lb = node["SU"]["LowerBack"]
                name = f"{p}: {test}.{trial}.SU.LowerBack"
                acc = _mat_numbers(lb["Acc"], f"{name}.Acc") * float(gravity_mps2)
                gyro = np.deg2rad(_mat_numbers(lb["Gyr"], f"{name}.Gyr"))
                mag = _mat_numbers(lb["Mag"], f"{name}.Mag") if "Mag" in lb else None
                stamps = _mat_numbers(lb["Timestamp"], f"{name}.Timestamp").ravel()
                fs = lb.get("Fs", {})
                rate = float(_mat_numbers(fs.get("Acc", 100.0), f"{name}.Fs.Acc").reshape(-1)[0]) \
                    if isinstance(fs, dict) else 100.0
            except (KeyError, TypeError, IndexError) as exc:
                raise _err("path", f"{p}: {test}.{trial}.SU.LowerBack lacks Acc/Gyr/Timestamp") from exc
            if not (0.1 <= rate <= 1e5):
                raise _err("path", f"{p}: {test}.{trial}.SU.LowerBack.Fs.Acc must be a rate in [0.1, 1e5] Hz, "
                                   f"got {rate!r}")
            where = f"path ({test}.{trial})"
            check_imu_units(acc, gyro, acc_name=f"{where} Acc, converted from g",
                            gyro_name=f"{where} Gyr, converted from deg/s")
            if stamps.shape[0] != acc.shape[0]:
                raise _err("path", f"{p}: {test}.{trial}: Timestamp has {stamps.shape[0]} rows, Acc {acc.shape[0]}")
            time_s = stamps - stamps[0]
            _rate_from_time(time_s, where)  # strictly increasing
            intervals, lengths, bounds, contacts = [], [], [], []
            std = node.get("Standards", {}).get("INDIP", {})
            for wb in _as_bouts(std.get("MicroWB", [])):
                bounds.append((float(wb["Start"]), float(wb["End"])))
                ic = np.atleast_1d(np.asarray(wb.get("InitialContact_Event", []), dtype=float))
                ic = ic[np.isfinite(ic)]
                contacts.append(np.round(ic * rate).astype(np.int64))
                sic = np.asarray(wb.get("Stride_InitialContacts", np.zeros((0, 2))), dtype=float).reshape(-1, 2)
                sl = np.atleast_1d(np.asarray(wb.get("Stride_Length", []), dtype=float))
                if sl.shape[0] != sic.shape[0]:
                    raise _err("path", f"{p}: {test}.{trial}: {sic.shape[0]} strides but {sl.shape[0]} lengths")
                ok = np.all(np.isfinite(sic), axis=1) & np.isfinite(sl) & (sl > 0)
                for (a, b), length in zip(sic[ok], sl[ok]):
                    a, b = int(round(a)), int(round(b))
                    if 0 <= a < b < acc.shape[0]:
                        intervals.append((a, b))
                        lengths.append(float(length))
            rec = ImuRecording(name=f"{subject} {test} {trial}", time_s=time_s, acc_mps2=acc,
                               gyro_radps=gyro, rate_hz=rate, truth_xy_m=None, stride_indices=None,
                               closed_loop=False,
                               distance_m=float(np.sum(lengths)) / 2.0 if lengths else None,
                               source_units="acc g, gyro deg/s, mag uT", sensor="mobgap", mag_uT=mag)
            out.append(MobgapTrial(recording=rec, subject=subject, test=test, trial=trial,
                                   stride_intervals=np.asarray(intervals, dtype=np.int64).reshape(-1, 2),
                                   stride_lengths_m=np.asarray(lengths, dtype=float),
                                   bout_bounds_s=np.asarray(bounds, dtype=float).reshape(-1, 2),
                                   bout_initial_contacts=contacts))
    return out


@reads_file("root")
def list_mobgap_files(root: PathLike) -> List[Path]:
    """Sorted ``data.mat`` files under the mobgap folder ``root`` (``.../mobgap_lowerback``)."""
    return _files_in(root, "*/*/data.mat", "no mobgap <group>/<subject>/data.mat under")


__all__ = [
    "STANDARD_GRAVITY_MPS2",
    "ImuRecording",
    "IrregularTimestampsWarning",
    "MobgapTrial",
    "check_imu_units",
    "fit_sample_rate",
    "list_mobgap_files",
    "list_pyshoe_trials",
    "load_mobgap_trials",
    "load_openshoe",
    "load_pyshoe_trial",
    "load_xio",
]
