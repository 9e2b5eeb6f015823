// Python bindings of the fusion trackers' estimates: typed read-only objects bound once by
// result_binding.h: TrackerEstimate (ParticleTracker.step / wifi / fix / estimate),
// GridFilterEstimate (GridFilterSession.add_step / estimate) and LiveEstimate (every LiveSession
// event: the grid filter's estimate plus the plan's floor numbers and the most probable floor).
// They replace the dicts the tracker bindings used to copy field by field; reading them as those
// dicts still works for one release with a DeprecationWarning (docs/api_changes.md). The grid
// filter's fields are declared once below, for both the session's and the live session's estimate.
#include <cstddef>
#include <utility>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "fusion_estimates.h"
#include "result_binding.h"

namespace indoorloc::bindings {

namespace {

constexpr const char* kSince = "house (issue 27)";

void BindTrackerEstimate(py::module_& m) {
  using R = fusion::TrackerEstimate;
  ResultBinder<R>(m, "TrackerEstimate",
                  "The particle tracker's estimate after an update (ParticleTracker.step, wifi, fix, estimate).")
      .Field("time_s", [](const R& e) { return e.time_s; }, "Time of the latest update [s].")
      .Field("mean_m", [](const R& e) { return Eigen::Vector2d(e.mean_m); }, "(2,) weighted mean position [m].")
      .Field("covariance_m2", [](const R& e) { return Eigen::Matrix2d(e.covariance_m2); },
             "(2, 2) weighted covariance [m²].")
      .Field("floor_probabilities", [](const R& e) { return Eigen::VectorXd(e.floor_probabilities); },
             "(F,) weight per tracker floor (the order of ParticleTracker.floors).")
      .Field("floor_index", [](const R& e) { return e.floor_index; }, "Index of the most probable floor.")
      .Field("heading_offset_rad", [](const R& e) { return e.heading_offset_rad; },
             "Weighted circular mean of the PDR-to-floor yaw [rad].")
      .Field("scale", [](const R& e) { return e.scale; }, "Weighted mean step-length scale.")
      .Field("ess", [](const R& e) { return e.ess; }, "Effective sample size before resampling.")
      .Field("log_likelihood", [](const R& e) { return e.log_likelihood; }, "Log-likelihood increment of the event.")
      .Field("blocked_fraction", [](const R& e) { return e.blocked_fraction; },
             "Weight fraction blocked by walls (step events).")
      .Field("resampled", [](const R& e) { return e.resampled; })
      .Field("recovered", [](const R& e) { return e.recovered; },
             "Particles were redrawn from the observation (the unknown start placed, or a recovery).")
      .Field("lagged_m", [](const R& e) { return Eigen::Vector2d(e.lagged_m); },
             "(2,) fixed-lag smoothed position smoothing_lag_steps back [m] (NaN until that many steps).")
      .MappingDeprecated(kSince)
      .Finish();
}

/// The grid filter's estimate, read from R by `grid` (the estimate itself, or a live estimate's).
template <typename R, typename Grid>
void GridEstimateFields(ResultBinder<R>& b, Grid grid) {
  b.Field("time_s", [grid](const R& r) { return grid(r).time_s; }, "Time of the latest step [s].")
      .Field("steps", [grid](const R& r) { return grid(r).steps; }, "Steps added so far.")
      .Field("mean_m", [grid](const R& r) { return Eigen::VectorXd(grid(r).mean_m); }, "(2,) posterior mean [m].")
      .Field("covariance_m2", [grid](const R& r) { return Eigen::VectorXd(grid(r).covariance_m2); },
             "(3,) = (xx, xy, yy) [m²], calibrated as GridTracker.run's.")
      .Field("posterior_covariance_m2", [grid](const R& r) { return Eigen::VectorXd(grid(r).posterior_covariance_m2); },
             "(3,) the posterior's own covariance [m²].")
      .Field("fix_distance_m", [grid](const R& r) { return grid(r).fix_distance_m; }, "To the latest fix's centre [m].")
      .Field("fix_sd_m", [grid](const R& r) { return grid(r).fix_sd_m; }, "The latest fix's own sd [m].")
      .Field("floor_probabilities", [grid](const R& r) { return Eigen::VectorXd(grid(r).floor_probabilities); },
             "(F,) per floor of the plan.")
      .Field("heading_offset_rad", [grid](const R& r) { return grid(r).heading_offset_rad; },
             "Posterior circular mean of the heading offset [rad].")
      .Field("log_evidence", [grid](const R& r) { return grid(r).log_evidence; }, "log p(fixes so far | steps so far).")
      .Field("fixes", [grid](const R& r) { return grid(r).fixes; }, "Fixes applied so far.")
      .Field("located", [grid](const R& r) { return grid(r).located; },
             "A known start or at least one fix applied; False: the unknown start's prior (not a position).");
}

void BindGridFilterEstimate(py::module_& m) {
  using R = fusion::GridFilterEstimate;
  ResultBinder<R> b(m, "GridFilterEstimate", "The grid filter's estimate after a step (GridFilterSession.add_step, estimate).");
  GridEstimateFields(b, [](const R& r) -> const R& { return r; });
  b.MappingDeprecated(kSince).Finish();
}

void BindLiveEstimate(py::module_& m) {
  using R = LiveEstimate;
  ResultBinder<R> b(m, "LiveEstimate",
                    "The live session's estimate after an event: the grid filter's, the plan's floors and the most probable.");
  GridEstimateFields(b, [](const R& r) -> const fusion::GridFilterEstimate& { return r.grid; });
  b.Field("floors", [](const R& r) {
             py::array_t<long long> out(static_cast<py::ssize_t>(r.floors.size()));
             for (std::size_t i = 0; i < r.floors.size(); ++i) out.mutable_at(static_cast<py::ssize_t>(i)) = r.floors[i];
             return out;
           }, "(F,) floor numbers of the plan, the order of floor_probabilities.")
      .Field("floor", [](const R& r) { return r.floor; }, "The most probable floor's number.")
      .MappingDeprecated(kSince)
      .Finish();
}

}  // namespace

LiveEstimate MakeLiveEstimate(const fusion::GridFilterEstimate& grid, std::vector<int> floors) {
  LiveEstimate out;
  out.grid = grid;
  Eigen::Index best = 0;
  if (grid.floor_probabilities.size()) grid.floor_probabilities.maxCoeff(&best);
  out.floor = floors.empty() ? 0 : floors[static_cast<std::size_t>(best)];
  out.floors = std::move(floors);
  return out;
}

void BindFusionEstimates(py::module_& m) {
  BindTrackerEstimate(m);
  BindGridFilterEstimate(m);
  BindLiveEstimate(m);
}

}  // namespace indoorloc::bindings
