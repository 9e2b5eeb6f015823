"""What the tracker settings stored in a site file mean when they were written by an older indoorloc.

A site file stores its ``TrackSettings`` as JSON (table ``tracker_settings``). Floor identification
(``track --floor auto``) grew evidence over time, each new piece with its own settings, and each
weight was chosen jointly with the pieces present when it was chosen (docs/fusion_real.md, "Floor
identification"):

1. the all-floor grid filter alone;
2. + the AP detection rates (``identification_ap_*``, weight λ chosen with the filter);
3. + the calibrated probabilities (``identification_temperature``, ``..._error_probability``,
   ``..._error_slope``, chosen on the score of 2);
4. + the floor classifier (``identification_classifier_*``; λ, T, δ_10, b chosen again with it).

``TrackSettings.from_dict`` fills a missing key with today's default, which for a file written at
stage 2 or 3 gives a mix no study chose: the stored λ and calibration beside today's classifier
weight. :func:`stored_track_settings` instead reads a stored dict as the indoorloc that wrote it
used it: a missing evidence is off (weight 0), a missing calibration is the plain normalised score
(T 1, δ 0), a missing ε of the identification fixes is the tracker's own (what the pass used
then), and it warns (:class:`SiteSettingsWarning`) with what to do: rebuild the site file.

The grid tracker's options grew the same way: a file whose ``grid_options`` lack the survey's open
cells (``survey_walkable_radius_m``) was written by a tracker with the walls as drawn, and reads
radius 0 (:data:`LEGACY_GRID_VALUES`), with the same warning. So did the tracker's own settings: a
file without ``second_pass_start_sd_m`` was written by a one-pass smoother and reads 0
(:data:`LEGACY_TRACK_VALUES`).
"""

from __future__ import annotations

import warnings
from typing import Any, Dict, List, Mapping

from indoorloc.fusion import site_model

#: Keys of each floor-identification evidence, and the values that reproduce the indoorloc that
#: wrote a file without them (the evidence off; the probabilities uncalibrated).
LEGACY_VALUES: Dict[str, Dict[str, Any]] = {
    "the AP detection rates": {"identification_ap_weight": 0.0},
    "the calibrated floor probabilities": {"identification_temperature": 1.0, "identification_error_probability": 0.0,
                                           "identification_error_slope": 0.0},
    "the floor classifier": {"identification_classifier_weight": 0.0},
}
#: Grid tracker options (``grid_options``) that a file written before them did not use, and the
#: values that reproduce its tracker: per feature, (marker key, values).
LEGACY_GRID_VALUES: Dict[str, Dict[str, Any]] = {
    "the survey's open cells": {"survey_walkable_radius_m": 0.0, "survey_walkable_min_walks": 1},
}
#: Tracker settings (top-level keys) that a file written before them did not use, and the values
#: that reproduce its tracker: per feature, the values (their keys mark it).
LEGACY_TRACK_VALUES: Dict[str, Dict[str, Any]] = {
    "the smoother's second pass": {"second_pass_start_sd_m": 0.0},
}
#: Keys whose absence marks each evidence (any one of them).
_MARKERS: Dict[str, tuple] = {
    "the AP detection rates": ("identification_ap_weight", "identification_ap_count", "identification_ap_rate_floor",
                               "identification_ap_outlier_probability"),
    "the calibrated floor probabilities": ("identification_temperature", "identification_error_probability",
                                           "identification_error_slope"),
    "the floor classifier": ("identification_classifier_weight", "identification_classifier_l2_scale",
                             "identification_classifier_outlier_probability"),
}


class SiteSettingsWarning(UserWarning):
    """A site file's stored settings predate part of floor identification (rebuild the file)."""


def missing_evidence(stored: Mapping[str, Any]) -> List[str]:
    """The floor-identification evidences (keys of :data:`LEGACY_VALUES`) that the stored settings
    ``stored`` (a ``TrackSettings.to_dict()`` as saved) do not carry at all."""
    return [name for name, keys in _MARKERS.items() if not any(k in stored for k in keys)]


def missing_grid_features(stored: Mapping[str, Any]) -> List[str]:
    """The grid tracker features (keys of :data:`LEGACY_GRID_VALUES`) whose options the stored
    settings' ``grid_options`` do not carry at all (none when no ``grid_options`` is stored)."""
    grid = stored.get("grid_options")
    if not isinstance(grid, Mapping):
        return []
    return [name for name, values in LEGACY_GRID_VALUES.items() if not any(k in grid for k in values)]


def missing_track_features(stored: Mapping[str, Any]) -> List[str]:
    """The tracker features (keys of :data:`LEGACY_TRACK_VALUES`) whose settings the stored
    settings do not carry at all."""
    return [name for name, values in LEGACY_TRACK_VALUES.items() if not any(k in stored for k in values)]


def legacy_completed(stored: Mapping[str, Any]) -> Dict[str, Any]:
    """``stored`` with every missing floor-identification setting set as the writing indoorloc used
    it (module docstring); keys present are kept as stored. Does not modify ``stored``."""
    d = dict(stored)
    for name in missing_evidence(stored):
        d.update(LEGACY_VALUES[name])
    for name in missing_track_features(stored):
        d.update(LEGACY_TRACK_VALUES[name])
    grid_missing = missing_grid_features(stored)
    if grid_missing:
        d["grid_options"] = dict(stored["grid_options"])
        for name in grid_missing:
            d["grid_options"].update(LEGACY_GRID_VALUES[name])
    if "identification_fix_outlier_probability" not in d:
        # Before this key the identification pass used the tracker's own fix ε.
        eps = dict(d.get("grid_options") or {}).get("fix_outlier_probability")
        if eps is not None and 0 < eps < 1:
            d["identification_fix_outlier_probability"] = eps
    return d


def stored_track_settings(stored: Mapping[str, Any], source: str):
    """The ``site_model.TrackSettings`` of settings ``stored`` read from ``source`` (a site file's
    path, for the warning): :func:`legacy_completed`, then ``TrackSettings.from_dict``. Warns
    :class:`SiteSettingsWarning` once, naming the file, what its settings lack and the command that
    rebuilds it, when an evidence is missing. ValueError as ``from_dict`` for unknown keys."""
    missing = missing_evidence(stored)
    grid_missing = missing_grid_features(stored) + missing_track_features(stored)
    if grid_missing:
        warnings.warn(f"indoorloc: site file {source} was saved before {', '.join(grid_missing)} existed: tracks use "
                      f"the tracker it was saved with. Rebuild the site file for the current tracker: "
                      f"'indoorloc site build SURVEY_DIR -o {source}'", SiteSettingsWarning, stacklevel=3)
    if missing:
        warnings.warn(f"indoorloc: site file {source} was saved before {', '.join(missing)} existed: floor "
                      f"identification (floor='auto') uses the evidence and calibration saved with it, without "
                      f"{', '.join(missing)}. Rebuild the site file for the current floor identification: "
                      f"'indoorloc site build SURVEY_DIR -o {source}'", SiteSettingsWarning, stacklevel=3)
    return site_model.TrackSettings.from_dict(legacy_completed(stored))


__all__ = ["LEGACY_GRID_VALUES", "LEGACY_TRACK_VALUES", "LEGACY_VALUES", "SiteSettingsWarning", "legacy_completed",
           "missing_evidence", "missing_grid_features", "missing_track_features", "stored_track_settings"]
