// Site file reader: a site model written by the Python side (`indoorloc site build`,
// python/indoorloc/fusion/site_store.py; docs/your_building.md, "The site file") read without
// Python. The file is one SQLite database per site, a table per concept; this reader gives a
// floor's walkable plan (FloorGeometry in the floor frame, metres east/north of the floor's
// origin), its handheld-PDR calibration, the WiFi fingerprint map, and the default tracker's
// GridTrackerOptions for the floor, so that an application can build a FloorPlan, a GridTracker
// and a LiveSession (fusion/live_session.h) and track raw sensor events on a surveyed building.
//
// SQLite stays behind the implementation (site_file.cc): this header exposes Eigen and std only.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/fusion/floor_plan.h"
#include "indoorloc/fusion/grid_tracker.h"
#include "indoorloc/fusion/live_session.h"

namespace indoorloc::fusion {

/// One floor of a site: name ("F8"), building level, the WGS84 origin of the floor frame,
/// walkable area [m²] and the plan (outlines and obstacles [m], floor = number).
struct SiteFloor {
  std::string name;
  int number = 0;
  double origin_lon_deg = 0.0;
  double origin_lat_deg = 0.0;
  double walkable_area_m2 = 0.0;
  FloorGeometry geometry;
};

/// The floor's handheld-PDR calibration (python pdr_handheld.HandheldCalibration): step length
/// L = k * (a_max - a_min)^(1/4) [m], heading in the floor frame = phone heading + yaw offset [rad].
struct SitePdrCalibration {
  double k = 0.0;
  double yaw_offset_rad = 0.0;
  double yaw_offset_spread_rad = 0.0;
  double length_sd_fraction = 0.0;
  double heading_sd_rad = 0.0;
};

class SiteFile {
 public:
  /// The format version this reader reads (PRAGMA user_version of the file).
  static constexpr int kFormatVersion = 1;
  /// PRAGMA application_id of a site file ("ILOC").
  static constexpr int kApplicationId = 0x494C4F43;

  /// Opens a site file read-only. Throws std::runtime_error naming the file when it is missing,
  /// not SQLite, another application's SQLite file, another format version, or damaged.
  explicit SiteFile(const std::string& path);
  ~SiteFile();
  SiteFile(SiteFile&&) noexcept;
  SiteFile& operator=(SiteFile&&) noexcept;
  SiteFile(const SiteFile&) = delete;
  SiteFile& operator=(const SiteFile&) = delete;

  const std::string& path() const;
  /// Floor names in building order.
  std::vector<std::string> FloorNames() const;
  /// A value of the meta table ("format", "library_version", "built", ...); "" when absent.
  std::string Meta(const std::string& key) const;
  /// Floor by name; std::invalid_argument naming the floor and the file when it is not in the site.
  SiteFloor Floor(const std::string& name) const;
  SitePdrCalibration Calibration(const std::string& floor) const;
  /// The default tracker's options on this floor: the stored options with the heading-offset
  /// prior sd set to the floor's calibrated spread (at least 1e-3 rad), as the Python side runs it.
  GridTrackerOptions TrackerOptions(const std::string& floor) const;
  /// The default tracker of a floor on `plan` (the floor's one-floor plan, which must outlive the
  /// tracker): TrackerOptions(floor), its fixes anchored to the floor's fingerprint positions
  /// (GridTracker::WithSurveyPositions), as the Python side's Site.floor_models(floor).tracker.
  GridTracker Tracker(const FloorPlan* plan, const std::string& floor) const;
  /// Positions (N x 2) [m] of the floor's WiFi fingerprints (where the survey is).
  RowMatrixXd FingerprintPositions(const std::string& floor) const;
  /// The floor's WiFi fingerprint map as the Python side uses it (Site.floor_models(floor).database):
  /// columns and AP reliabilities from the fingerprint_columns table, fingerprints in survey order.
  /// AP weights are the reliabilities to the power of the settings' ap_weight_power. Throws
  /// std::runtime_error naming the file for a file written before that table existed (rebuild it, or
  /// add a walk) or when the floor has no fingerprint.
  FingerprintMap Fingerprints(const std::string& floor) const;
  /// The fix options of the site's tracker settings (python TrackSettings.fixes). Throws
  /// std::runtime_error when they are not reproducible live ("window" pooling, "end" alignment,
  /// the "shared" metric, no beacon columns).
  FingerprintFixOptions FixOptions() const;
  /// The live session's options on a floor: the calibration's detector options, K, heading source
  /// and yaw offset, and the settings' per-step noise (python Site.live(floor)).
  LiveSessionOptions LiveOptions(const std::string& floor) const;
  /// Number of survey walks of a floor ("" = all floors).
  int WalkCount(const std::string& floor = "") const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indoorloc::fusion
