"""indoorloc.fusion.site_settings: a site file's stored tracker settings read as the indoorloc that
wrote them used them (no mix of stored and new floor-identification evidence), with a warning."""

from __future__ import annotations

import json
import math
import shutil
import sqlite3
import warnings

import numpy as np
import pytest

from indoorloc.fusion import site_model, site_settings
from indoorloc.fusion.site_settings import SiteSettingsWarning

CLASSIFIER_KEYS = ("identification_classifier_weight", "identification_classifier_l2_scale",
                   "identification_classifier_outlier_probability")
CALIBRATION_KEYS = ("identification_temperature", "identification_error_probability", "identification_error_slope")
AP_KEYS = ("identification_ap_weight", "identification_ap_count", "identification_ap_rate_floor",
           "identification_ap_outlier_probability")


def _without(d, keys):
    return {k: v for k, v in d.items() if k not in keys}


def test_current_settings_read_unchanged_and_without_warning():
    s = site_model.TrackSettings(identification_classifier_weight=3.0, identification_ap_weight=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = site_settings.stored_track_settings(s.to_dict(), "x.db")
    assert back == s


def test_a_file_saved_before_the_classifier_keeps_its_rates_and_calibration():
    # What a site file of the rates era stored: λ 2 and the calibration chosen for grid + rates.
    stored = _without(site_model.TrackSettings(identification_ap_weight=2.0, identification_temperature=1.0,
                                               identification_error_probability=0.03,
                                               identification_error_slope=2.0).to_dict(), CLASSIFIER_KEYS)
    before = json.dumps(stored, sort_keys=True)
    assert site_settings.missing_evidence(stored) == ["the floor classifier"]
    with pytest.warns(SiteSettingsWarning, match=r"old\.db was saved before the floor classifier existed.*"
                                                 r"Rebuild the site file.*indoorloc site build SURVEY_DIR -o old\.db"):
        s = site_settings.stored_track_settings(stored, "old.db")
    assert json.dumps(stored, sort_keys=True) == before  # the input is not modified
    assert s.identification_classifier_weight == 0.0  # not the new default 10 beside the stored λ
    assert s.identification_ap_weight == 2.0
    assert (s.identification_temperature, s.identification_error_probability, s.identification_error_slope) == (1.0, 0.03, 2.0)
    # from_dict alone (a dict written by this version) still fills today's defaults.
    assert site_model.TrackSettings.from_dict(stored).identification_classifier_weight == \
        site_model.TrackSettings().identification_classifier_weight


def test_older_files_turn_off_each_missing_evidence():
    grid_only = _without(site_model.TrackSettings().to_dict(),
                         CLASSIFIER_KEYS + CALIBRATION_KEYS + AP_KEYS + ("identification_fix_outlier_probability",))
    grid_only["grid_options"]["fix_outlier_probability"] = 0.05
    assert site_settings.missing_evidence(grid_only) == ["the AP detection rates", "the calibrated floor probabilities",
                                                         "the floor classifier"]
    with pytest.warns(SiteSettingsWarning, match="before the AP detection rates, the calibrated floor probabilities, "
                                                 "the floor classifier existed"):
        s = site_settings.stored_track_settings(grid_only, "g.db")
    assert s.identification_ap_weight == 0.0 and s.identification_classifier_weight == 0.0
    assert (s.identification_temperature, s.identification_error_probability, s.identification_error_slope) == (1.0, 0.0, 0.0)
    assert s.identification_fix_outlier_probability == 0.05  # the tracker's ε, as the pass used then
    with pytest.raises(ValueError, match="unknown keys"), pytest.warns(SiteSettingsWarning):
        site_settings.stored_track_settings(dict(grid_only, bogus=1), "g.db")


def test_a_file_saved_before_the_open_survey_cells_keeps_the_walls_as_drawn():
    stored = site_model.TrackSettings().to_dict()
    stored["grid_options"] = _without(stored["grid_options"], ("survey_walkable_radius_m", "survey_walkable_min_walks"))
    before = json.dumps(stored, sort_keys=True)
    assert site_settings.missing_grid_features(stored) == ["the survey's open cells"]
    assert site_settings.missing_evidence(stored) == []
    with pytest.warns(SiteSettingsWarning, match=r"old\.db was saved before the survey's open cells existed.*"
                                                 r"indoorloc site build SURVEY_DIR -o old\.db"):
        s = site_settings.stored_track_settings(stored, "old.db")
    assert json.dumps(stored, sort_keys=True) == before  # the input is not modified
    assert s.grid_options.survey_walkable_radius_m == 0.0 and s.grid_options.survey_walkable_min_walks == 1
    assert site_model.TrackSettings().grid_options.survey_walkable_radius_m == 0.75  # today's default
    # Everything else as stored.
    assert s.grid_options.fix_survey_distance_factor == site_model.TrackSettings().grid_options.fix_survey_distance_factor


def test_a_file_saved_before_the_second_pass_smooths_in_one_pass():
    stored = _without(site_model.TrackSettings().to_dict(), ("second_pass_start_sd_m",))
    before = json.dumps(stored, sort_keys=True)
    assert site_settings.missing_track_features(stored) == ["the smoother's second pass"]
    with pytest.warns(SiteSettingsWarning, match=r"old\.db was saved before the smoother's second pass existed"):
        s = site_settings.stored_track_settings(stored, "old.db")
    assert json.dumps(stored, sort_keys=True) == before  # the input is not modified
    assert s.second_pass_start_sd_m == 0.0 and site_model.TrackSettings().second_pass_start_sd_m > 0
    assert s.known_start_fix_tempering == site_model.TrackSettings().known_start_fix_tempering
    # The settings round-trip, a hard known-start wall included; bad values are refused by name.
    hard = site_model.TrackSettings(known_start_wall_log_penalty=-math.inf)
    assert site_model.TrackSettings.from_dict(json.loads(json.dumps(hard.to_dict()))) == hard
    for bad in (dict(second_pass_start_sd_m=-1.0), dict(second_pass_start_sd_m=math.nan),
                dict(known_start_fix_tempering=0.0), dict(known_start_fix_outlier_probability=1.0),
                dict(known_start_wall_log_penalty=0.5)):
        with pytest.raises(ValueError, match=f"TrackSettings.{next(iter(bad))}"):
            site_model.TrackSettings(**bad).validate()


@pytest.fixture(scope="module")
def two_floor_survey(tmp_path_factory):
    from indoorloc.simulate.ilc_site import write_ilc_site

    root = tmp_path_factory.mktemp("ilc_settings")
    site = write_ilc_site(root / "site", floors=("F1", "F2"), walks_per_floor=5, seed=3)
    survey, held_out = root / "survey", []
    for floor in ("F1", "F2"):
        shutil.copytree(site / floor, survey / floor)
        walks = sorted((survey / floor / "path_data_files").glob("*.txt"))
        held_out.append((floor, root / f"{floor}_{walks[-1].name}"))
        walks[-1].rename(held_out[-1][1])
    return survey, held_out


def test_an_old_site_file_tracks_as_the_settings_it_was_saved_with(two_floor_survey, tmp_path):
    """A site file whose stored settings lack the classifier keys identifies floors exactly as one
    built with the classifier off and the same stored λ and calibration, and warns once on opening."""
    from indoorloc.fusion.site import Site

    survey, held_out = two_floor_survey
    legacy = site_model.TrackSettings(identification_classifier_weight=0.0, identification_ap_weight=2.0,
                                      identification_temperature=1.0, identification_error_probability=0.03,
                                      identification_error_slope=2.0, identification_floor_change_rate_per_s=0.0)
    site = Site.build(survey, tmp_path / "site.db", settings=legacy)
    old = tmp_path / "old.db"
    old.write_bytes(site.path.read_bytes())
    con = sqlite3.connect(old)
    stored = json.loads(con.execute("SELECT settings FROM tracker_settings WHERE name = 'default'").fetchone()[0])
    con.execute("UPDATE tracker_settings SET settings = ? WHERE name = 'default'",
                (json.dumps(_without(stored, CLASSIFIER_KEYS)),))
    con.commit()
    con.close()
    with pytest.warns(SiteSettingsWarning, match="old.db was saved before the floor classifier"):
        old_site = Site.open(old)
    assert old_site.settings == legacy
    with warnings.catch_warnings():
        warnings.simplefilter("error", SiteSettingsWarning)
        Site.open(site.path)  # a current file: no warning
    for floor, path in held_out:
        a, b = site.track(path, floor="auto"), old_site.track(path, floor="auto")
        assert a.floor == b.floor == floor
        assert a.floor_probabilities == pytest.approx(b.floor_probabilities, abs=0)
        np.testing.assert_array_equal(a.xy_m, b.xy_m)


def test_a_site_file_with_a_damaged_setting_is_refused_naming_file_and_setting(two_floor_survey, tmp_path):
    """A stored value out of range (here a negative second-pass start sd) is not silently read as
    another tracker: opening the file raises SiteFileError naming the file and the setting."""
    from indoorloc.fusion.site import Site
    from indoorloc.fusion.site_store import SiteFileError

    survey, _ = two_floor_survey
    site = Site.build(survey, tmp_path / "site.db")
    bad = tmp_path / "bad.db"
    bad.write_bytes(site.path.read_bytes())
    con = sqlite3.connect(bad)
    stored = json.loads(con.execute("SELECT settings FROM tracker_settings WHERE name = 'default'").fetchone()[0])
    con.execute("UPDATE tracker_settings SET settings = ? WHERE name = 'default'",
                (json.dumps(dict(stored, second_pass_start_sd_m=-1.0)),))
    con.commit()
    con.close()
    with pytest.raises(SiteFileError, match=r"bad\.db: its tracker settings are not usable: .*second_pass_start_sd_m"):
        Site.open(bad)
