"""Map matching with a circular particle filter on a road network (paper 000, El Mokhtari et al.,
"Indoor Localization by Particle Map Matching").

- :class:`RoadNetwork`: straight segments, connectivity at their ends, validation report,
  nearest-segment queries (spatial grid). Load from GeoJSON/CSV with
  :func:`indoorloc.io.load_road_network`; the paper's warehouse is :func:`warehouse_network`.
- :func:`simulate_trajectory`: the paper's §III vehicle (2 m/s, random turns, biased noisy
  odometer, von Mises compass).
- :class:`ParticleMapMatcher` with :class:`FilterOptions`: Algorithm 1 (equal-spacing start,
  uniform propagation noise, von Mises weights, adaptive resampling, projected weighted mean),
  plus recovery, odometer-bias estimation, heading-aware junctions and fixed-lag smoothing.
- :func:`monte_carlo`: the §III experiment in C++ over threads (deterministic per run).
"""

from __future__ import annotations

from indoorloc._core.mapmatch import (
    FilterOptions,
    ParticleMapMatcher,
    RoadNetwork,
    TrajectoryOptions,
    monte_carlo,
    simulate_trajectory,
)


def warehouse_network(**options) -> RoadNetwork:
    """The re-digitised warehouse of the paper's Fig. 2 (26 corridors, docs/mapmatch_warehouse.md)."""
    from indoorloc.io.road_network import warehouse_segments

    segments, ids = warehouse_segments()
    return RoadNetwork(segments, ids.astype("int64"), **options)


__all__ = [
    "FilterOptions",
    "ParticleMapMatcher",
    "RoadNetwork",
    "TrajectoryOptions",
    "monte_carlo",
    "simulate_trajectory",
    "warehouse_network",
]
