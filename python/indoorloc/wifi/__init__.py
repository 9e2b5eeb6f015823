"""WiFi RSS localization (paper 004, Jacquet, Mezali & Rodolakis, INRIA RR-7294).

- :class:`SignalMap`: per reference point and AP, RSS mean [dBm] and variance [dB^2], built from
  raw scans with the paper's estimator and a floor-value model for APs not heard.
- :class:`DelaunayInterpolator`: CGAL Delaunay triangulation, linear interpolation of many
  fields with gradients (and Sibson's natural-neighbour interpolant).
- :class:`RssModel`: the interpolated Gaussian model: l(z, v), its gradient and Fisher
  information; simulated scans (the paper's simulated mode).
- :class:`GridPosterior`: posterior-mean (MMSE) fixes of the same model on a grid (beyond the paper).
- :class:`FingerprintLocator`: the baselines NNSS (RADAR), NNSS-AVG, weighted kNN, Horus.
- :class:`SharedApMatcher`: the shared-AP dissimilarity (RMS RSS difference over the APs both
  heard + c x the unshared fraction) and its kNN: the fusion tracker's WiFi matcher, and the
  ``shared_knn`` method of ``indoorloc wifi evaluate``.
- :class:`GradientTracker` (Algorithm 1 with step control) and :func:`locate_ml` (global
  maximum-likelihood fixes, also from k scans at a static point).

Beside the compiled classes, :mod:`indoorloc.wifi.matcher` (formerly ``indoorloc.wifi_matcher``)
pools a walk's WiFi measurements in time into fingerprints and matches them with
:class:`SharedApMatcher` (the fusion tracker's fingerprint fixes build on it).

Derivations: docs/wifi_derivations.md. Example::

    from indoorloc import wifi
    m = wifi.SignalMap.from_scans(train_xy, train_floor, train_rss, wifi.SignalMapOptions(not_heard_sentinel=100.0))
    model = wifi.RssModel(m)
    fixes = wifi.locate_ml(model, m.prepare_scans(test_rss, 100.0))
"""

from __future__ import annotations

from indoorloc._core.wifi import (
    DelaunayInterpolator,
    FingerprintLocator,
    GradientTracker,
    GradientTrackerOptions,
    GridPosterior,
    RssModel,
    RssModelOptions,
    SharedApMatcher,
    SharedApMatcherOptions,
    SignalMap,
    SignalMapOptions,
    locate_ml,
)
from indoorloc.wifi import matcher


def tracker_options(**settings) -> GradientTrackerOptions:
    """GradientTrackerOptions with the given fields set, validated (ValueError if invalid)."""
    options = GradientTrackerOptions()
    for name, value in settings.items():
        if not hasattr(options, name):
            raise ValueError(f"indoorloc: argument '{name}': not a GradientTrackerOptions field")
        setattr(options, name, value)
    options.validate()
    return options


__all__ = [
    "DelaunayInterpolator",
    "FingerprintLocator",
    "GradientTracker",
    "GradientTrackerOptions",
    "GridPosterior",
    "RssModel",
    "RssModelOptions",
    "SharedApMatcher",
    "SharedApMatcherOptions",
    "SignalMap",
    "SignalMapOptions",
    "locate_ml",
    "matcher",
    "tracker_options",
]
