"""The tracker's steps: detected steps as displacements [m] with their covariances [m²], from
polar steps (length, heading) or foot-mounted ZUPT increments (docs/fusion.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from indoorloc._core.fusion import steps_from_polar
from indoorloc.validate import argument_error as _error
from indoorloc.validate import real_array, real_scalar


@dataclass
class Steps:
    """Detected steps for the tracker: times (M,) [s], displacements (M, 2) [m] in the PDR frame
    and their covariances (M, 3) = (xx, xy, yy) [m²]."""

    times_s: np.ndarray
    displacements_m: np.ndarray
    covariances_m2: np.ndarray

    @classmethod
    def from_polar(cls, times_s, lengths_m, headings_rad, length_sd_m, heading_sd_rad) -> "Steps":
        """From step lengths [m] and headings [rad] with their sd (scalars broadcast), by
        first-order propagation (docs/fusion.md)."""
        times = real_array(times_s, "times_s", ndim=1)
        n = times.shape[0]

        def per_step(value: Any, name: str) -> np.ndarray:
            a = real_array(value, name)
            if a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
                raise _error(name, f"expected a scalar or shape ({n},) (one entry per step of 'times_s'), "
                                   f"got {a.shape}")
            return np.broadcast_to(a, (n,))

        lengths = per_step(lengths_m, "lengths_m")
        headings = per_step(headings_rad, "headings_rad")
        length_sd = per_step(length_sd_m, "length_sd_m")
        heading_sd = per_step(heading_sd_rad, "heading_sd_rad")
        displacements, covariances = steps_from_polar(lengths, headings, length_sd, heading_sd)
        return cls(times.copy(), displacements, covariances)

    @classmethod
    def from_increments(cls, times_s, increments_m, covariances_m2) -> "Steps":
        """From foot-mounted ZUPT increments ΔP_k (M, 2 or 3; x, y used) [m] (paper 002 eq. 9) and
        their covariances (M, 2, 2) or (M, 3) [m²]."""
        inc = real_array(increments_m, "increments_m")
        if inc.ndim != 2 or inc.shape[1] not in (2, 3):
            raise ValueError("indoorloc: argument 'increments_m': expected shape (M, 2) or (M, 3), got "
                             f"{inc.shape}")
        m = inc.shape[0]
        times = real_array(times_s, "times_s", shape=(m,))
        cov = real_array(covariances_m2, "covariances_m2")
        if cov.ndim == 3 and cov.shape[1:] == (2, 2):
            cov = np.stack([cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1]], axis=1)
        if cov.shape != (m, 3):
            raise _error("covariances_m2", f"expected shape ({m}, 2, 2) or ({m}, 3), got {cov.shape}")
        return cls(times.copy(), inc[:, :2].copy(), cov.copy())

    def __len__(self) -> int:
        return int(self.times_s.shape[0])


def rotate(displacements_m, angle_rad: float) -> np.ndarray:
    """Displacements (M, 2) rotated by angle_rad (PDR frame -> floor frame for a known yaw)."""
    d = real_array(displacements_m, "displacements_m", shape=(None, 2))
    angle = real_scalar(angle_rad, "angle_rad")
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]], axis=1)


__all__ = ["Steps", "rotate"]
