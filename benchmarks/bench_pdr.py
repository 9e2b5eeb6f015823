"""Speed of the pdr subsystem, single thread: step detectors, Weinberg stride length, SHOE, the
ZUPT EKF (with and without the RTS smoother), the Mahony attitude filter and the INS-ZUPT step
increments, on a real foot-mounted recording (PyShoe trial, 200 Hz) tiled to about 10^6 samples.

Goals (issue 6): detectors + Weinberg >= 5 M samples/s; ZUPT EKF >= 1 M samples/s. Peers measured
outside the project on the same machine class: OpenShoe's C EKF about 0.4 M samples/s, PyShoe's
Python ESKF about 4.2 k samples/s. Timings are the best of `repeat` calls (least disturbed by
the other jobs on a shared machine), through the Python bindings (the C++ work dominates: the
arrays are passed without copies).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from timing import best_seconds

from indoorloc import pdr

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "pdr"
TARGET_SAMPLES = 1_000_000


def _recording():
    """(time_s, acc, gyro, rate_hz): a PyShoe trial tiled to ~10^6 samples, or a synthetic gait
    when the data folder is absent."""
    trials = sorted((DATA / "pyshoe_vicon").glob("*.mat")) if (DATA / "pyshoe_vicon").is_dir() else []
    if trials:
        from indoorloc.io import load_pyshoe_trial

        rec = load_pyshoe_trial(trials[0])
        acc, gyro, rate = rec.acc_mps2, rec.gyro_radps, rec.rate_hz
        source = f"PyShoe trial {rec.name} tiled"
    else:
        rate = 200.0
        t = np.arange(20000) / rate
        phase = np.mod(t, 1.1) > 0.5
        acc = np.tile([0.0, 0.0, 9.81], (t.size, 1))
        acc[phase] += 5.0 * np.sin(2 * np.pi * t[phase, None] / 0.6 + np.array([0.0, 1.0, 2.0]))
        gyro = np.zeros((t.size, 3))
        gyro[phase] = 3.0 * np.sin(2 * np.pi * t[phase, None] / 0.6 + np.array([0.5, 1.5, 2.5]))
        source = "synthetic gait tiled"
    reps = max(1, math.ceil(TARGET_SAMPLES / acc.shape[0]))
    acc = np.ascontiguousarray(np.tile(acc, (reps, 1)))
    gyro = np.ascontiguousarray(np.tile(gyro, (reps, 1)))
    time_s = np.arange(acc.shape[0]) / rate
    return time_s, acc, gyro, rate, source


def run(quick: bool = False) -> dict:
    repeat = 2 if quick else 5
    time_s, acc, gyro, rate, source = _recording()
    n = acc.shape[0]
    mag = np.ascontiguousarray(30.0 * np.tanh(gyro) + np.array([20.0, 0.0, -40.0]))
    steps, _ = pdr.steps_acceleration(acc, rate)
    steps = np.asarray(steps)
    stance = pdr.shoe_detector(acc, gyro, options=pdr.ShoeOptions(threshold=3e5))
    quats = pdr.attitude_mahony(time_s, acc, gyro)["quaternions_wxyz"]
    stance_steps = np.flatnonzero(stance[1:] & ~stance[:-1]) + 1
    cases = {
        "acceleration step detector (eq. 1-3)": lambda: pdr.steps_acceleration(acc, rate),
        "gyroscope step detector": lambda: pdr.steps_gyro(gyro, rate),
        "magnetometer step detector": lambda: pdr.steps_magnetometer(mag, rate),
        "Weinberg stride length (eq. 4, 3 Hz Butterworth)": lambda: pdr.weinberg_stride_lengths(acc, rate, steps),
        "acceleration detector + Weinberg": lambda: pdr.weinberg_stride_lengths(
            acc, rate, pdr.steps_acceleration(acc, rate)[0]),
        "SHOE zero-velocity detector": lambda: pdr.shoe_detector(acc, gyro, options=pdr.ShoeOptions(threshold=3e5)),
        "ZUPT EKF": lambda: pdr.zupt_ekf(time_s, acc, gyro, stance),
        "ZUPT EKF + RTS smoother": lambda: pdr.zupt_ekf(time_s, acc, gyro, stance, options=pdr.ZuptEkfOptions(smooth=True)),
        "SHOE + ZUPT EKF": lambda: pdr.zupt_ekf(time_s, acc, gyro, pdr.shoe_detector(acc, gyro, options=pdr.ShoeOptions(threshold=3e5))),
        "Mahony attitude filter": lambda: pdr.attitude_mahony(time_s, acc, gyro),
        "INS-ZUPT increments (eq. 5)": lambda: pdr.ins_zupt_increments(time_s, acc, quats, stance_steps),
    }
    rows = {}
    for name, fn in cases.items():
        fn()  # warm up
        sec = best_seconds(fn, repeat)
        rows[name] = {"seconds": sec, "samples_per_s": n / sec}
    return {"title": "pdr (foot-mounted IMU), single thread", "n_samples": n, "source": source,
            "rows": rows,
            "goals": {"detectors + Weinberg": 5e6, "ZUPT EKF": 1e6},
            "peers": {"OpenShoe C EKF": 4e5, "PyShoe Python ESKF": 4.2e3}}


def markdown(result: dict) -> str:
    lines = [f"{result['n_samples']} samples ({result['source']}); best of repeated calls.", "",
             "| step | seconds | samples/s |", "|---|---:|---:|"]
    for name, r in result["rows"].items():
        lines.append(f"| {name} | {r['seconds']:.4f} | {r['samples_per_s'] / 1e6:.2f} M |")
    lines += ["", "Goals: detectors + Weinberg >= 5 M samples/s, ZUPT EKF >= 1 M samples/s. Peers: "
              "OpenShoe C EKF ~0.4 M/s, PyShoe ~4.2 k/s."]
    return "\n".join(lines)


if __name__ == "__main__":
    import json

    res = run(quick=True)
    print(json.dumps({k: v["samples_per_s"] for k, v in res["rows"].items()}, indent=1))
    print(markdown(res))
