"""The parameters of the synthetic ILC 2020 site (:class:`IlcSiteConfig`; the model is described
in :mod:`indoorloc.simulate.ilc_site`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Tuple

from indoorloc.simulate.radio import RadioConfig


def _default_radio() -> RadioConfig:
    # A mall: no thin walls; shop fronts (glass, partitions) cost less than concrete shafts;
    # phones stop reporting below about -93 dBm (the real site's minimum).
    return RadioConfig(aps_per_floor=24, p0_dbm=-38.0, exponent=2.3, obstacle_attenuation_db=5.0,
                       floor_attenuation_db=15.0, shadowing_sd_db=4.0, shadowing_length_m=5.0,
                       noise_sd_db=2.5, sensitivity_dbm=-93.0, miss_probability=0.05)


@dataclass(frozen=True)
class IlcSiteConfig:
    """Parameters of the synthetic site. Metres, seconds, Hz, degrees, dBm, uT as named."""

    # Floor layout
    width_m: float = 60.0
    depth_m: float = 40.0
    corridor_width_m: float = 4.0
    ew_corridors: int = 2                      #: east-west corridors crossing the floor
    ns_corridors: int = 3                      #: north-south corridors crossing the floor
    corridor_jitter_m: float = 1.5             #: random shift of each corridor from even spacing
    shops_per_block: Tuple[int, int] = (1, 3)  #: inclusive range of shops tiling each block
    origin_lon_lat: Tuple[float, float] = (116.3975, 39.9087)  #: south-west corner of the outline
    # Walks
    walk_duration_s: Tuple[float, float] = (20.0, 40.0)
    stand_start_s: Tuple[float, float] = (0.4, 1.0)
    stand_end_s: Tuple[float, float] = (0.5, 1.5)
    corner_cut_m: float = 1.5
    step_length_m: float = 0.7
    step_length_walker_sd_m: float = 0.03      #: spread of the mean stride between walks (clipped to +-0.08 m)
    step_length_sd_fraction: float = 0.04      #: step-to-step variability
    step_frequency_hz: float = 1.8
    step_frequency_walker_sd_hz: float = 0.08
    #: K of L = K (max - min LP|a|)^(1/4) [m / (m/s^2)^(1/4)]; with 0.62-0.78 m strides the bounce
    #: amplitude is 1.6-4 m/s^2, clear of indoorloc.pdr.handheld's 1 m/s^2 peak floor
    weinberg_k: float = 0.46
    yaw_offset_deg: float = 4.0                #: floor-frame heading minus phone heading, site mean
    yaw_offset_walk_sd_deg: float = 1.5        #: per-walk spread of that offset
    heading_error_sd_deg: float = 2.0          #: slow error of the rotation vector's heading
    pitch_deg: Tuple[float, float] = (6.0, 14.0)
    accel_noise_sd_mps2: float = 0.25
    gyro_noise_sd_radps: float = 0.015
    gyro_bias_sd_radps: float = 0.003
    mag_noise_sd_ut: float = 0.5
    magnetic_field_enu_ut: Tuple[float, float, float] = (0.0, 28.0, -40.0)
    sample_rate_hz: float = 50.0
    waypoint_interval_s: Tuple[float, float] = (3.0, 6.0)
    # WiFi
    radio: RadioConfig = field(default_factory=_default_radio)
    p0_5ghz_offset_db: float = -6.0
    scan_interval_s: float = 2.0
    scan_jitter_s: float = 0.15
    sweep_lag_s: Tuple[float, float] = (0.3, 1.2)
    cache_s: float = 10.0
    floor_height_m: float = 5.0

    def validate(self) -> None:
        """Raises ValueError naming the first invalid field."""
        def bad(name: str, why: str) -> None:
            raise ValueError(f"indoorloc: argument 'config.{name}': {why}")
        for name in ("width_m", "depth_m", "corridor_width_m", "corner_cut_m", "step_length_m",
                     "step_frequency_hz", "weinberg_k", "sample_rate_hz", "scan_interval_s", "cache_s",
                     "floor_height_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                bad(name, f"must be finite and > 0, got {v}")
        if self.ew_corridors < 1 or self.ns_corridors < 1:
            bad("ew_corridors", "need at least one corridor each way")
        lo, hi = self.shops_per_block
        if not 1 <= lo <= hi:
            bad("shops_per_block", f"need 1 <= lo <= hi, got {self.shops_per_block}")
        for n, extent in ((self.ns_corridors, self.width_m), (self.ew_corridors, self.depth_m)):
            block = extent / (n + 1) - self.corridor_width_m - 2 * self.corridor_jitter_m
            if block < 2.0:
                bad("corridor_width_m", f"blocks of {block:.1f} m between corridors: floor too small")
        for name in ("walk_duration_s", "stand_start_s", "stand_end_s", "pitch_deg", "waypoint_interval_s",
                     "sweep_lag_s"):
            a, b = getattr(self, name)
            if not (0 <= a <= b and math.isfinite(b)):
                bad(name, f"need 0 <= lo <= hi, got {(a, b)}")
        if self.walk_duration_s[0] < 5.0:
            bad("walk_duration_s", "walks shorter than 5 s have too few steps")
        if self.corner_cut_m > 0.45 * self.corridor_width_m + 1.0:
            bad("corner_cut_m", "rounded corners would leave the corridors")
        if not (0 < self.scan_jitter_s < 0.5 * self.scan_interval_s) or self.sweep_lag_s[1] >= self.scan_interval_s:
            bad("scan_jitter_s", "need 0 < jitter < interval / 2 and sweep lag < interval")
        self.radio.validate()
