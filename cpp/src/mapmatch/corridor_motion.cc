#include "indoorloc/mapmatch/corridor_motion.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"

namespace indoorloc::mapmatch {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Junction hops allowed in one move: a move longer than this many (tiny) segments is a bug in
// the caller (a distance of 1e300), not a walk; the particle stops where it got to.
constexpr int kMaxHopsPerMove = 100000;

// log(2π I0(κ)) without overflow: I0(κ) = e^κ I0e(κ).
double LogVonMisesNormaliser(double kappa) {
  return std::log(2.0 * kPi) + kappa + std::log(std::cyl_bessel_i(0.0, kappa) * std::exp(-kappa));
}

}  // namespace

bool CorridorMotionOptions::IsValid(std::string* error) const {
  return Validator(error)
      .InRange(kappa, 0.0, kMaxCorridorKappa, "kappa")
      .Check(junction_policy == JunctionPolicy::kUniform || junction_policy == JunctionPolicy::kHeadingAware,
             "junction_policy", "must be kUniform or kHeadingAware")
      .InRange(junction_kappa, 0.0, kMaxCorridorKappa, "junction_kappa");
}

CorridorMotion::CorridorMotion(const RoadNetwork& network, const CorridorMotionOptions& options)
    : network_(network), options_(options) {
  ValidateOptions(options_);
  log_normaliser_ = LogVonMisesNormaliser(options_.kappa);
  const int m = network_.num_segments();
  lengths_ = network_.lengths_m();
  headings_ = network_.headings_rad();
  origin_x_.resize(m);
  origin_y_.resize(m);
  unit_x_.resize(m);
  unit_y_.resize(m);
  const RowMatrixXd& ends = network_.segments_m();
  for (int k = 0; k < m; ++k) {
    origin_x_[k] = ends(k, 0);
    origin_y_[k] = ends(k, 1);
    unit_x_[k] = (ends(k, 2) - ends(k, 0)) / lengths_[k];
    unit_y_[k] = (ends(k, 3) - ends(k, 1)) / lengths_[k];
  }
}

void CorridorMotion::HeadingTables(double heading_rad, double* factor, double* disagreement) const {
  const double kappa = options_.kappa;
  for (int s = 0; s < network_.num_segments(); ++s) {
    const double c = std::cos(heading_rad - headings_[s]);
    factor[2 * s + 1] = std::exp(kappa * (c - 1.0));
    factor[2 * s] = std::exp(kappa * (-c - 1.0));
    disagreement[2 * s + 1] = 1.0 - c;
    disagreement[2 * s] = 1.0 + c;
  }
}

double CorridorMotion::MoveAcrossEnds(int* segment, signed char* direction, double* along_m, double distance_m,
                                      double heading_rad, RandomStream& rng) const {
  int s = *segment;
  int d = *direction;
  double u = *along_m + d * distance_m;
  double importance = 1.0;
  for (int hop = 0; hop < kMaxHopsPerMove; ++hop) {
    int end;
    double leftover;
    if (u > lengths_[s]) {
      end = 1;
      leftover = u - lengths_[s];
    } else if (u < 0.0) {
      end = 0;
      leftover = -u;
    } else {
      break;
    }
    // Backwards (a negative distance): stop at the end behind, never back onto a continuation
    // (it would put the particle on a branch it never came from; 7 m of error at κ_P = 5 in the
    // §III experiment, docs/mapmatch.md).
    if ((end == 1) != (d > 0)) {
      u = end == 1 ? lengths_[s] : 0.0;
      break;
    }
    const std::vector<Continuation>& choices = network_.continuations(s, end);
    size_t pick = 0;
    if (choices.size() > 1) {
      if (options_.junction_policy == JunctionPolicy::kUniform) {
        pick = static_cast<size_t>(rng.UniformInt(choices.size()));
      } else {
        // Proposal q_j ∝ exp(κ_J (cos(φ − heading_j) − 1)); the weight is multiplied by
        // prior / proposal = (1 / n) / (q_j / Σq). The q_j are computed twice (total, then the
        // pick) rather than kept in scratch, so that the model stays const and thread-safe.
        auto q = [&](size_t j) {
          const double h = TravelHeading(network_, choices[j].segment, choices[j].enter_end == 0 ? 1 : -1);
          return std::exp(options_.junction_kappa * (std::cos(heading_rad - h) - 1.0));
        };
        double total = 0.0;
        for (size_t j = 0; j < choices.size(); ++j) total += q(j);
        double r = rng.Uniform01() * total;
        double q_pick = q(0);
        while (pick + 1 < choices.size() && r >= q_pick) {
          r -= q_pick;
          q_pick = q(++pick);
        }
        importance *= (total / q_pick) / static_cast<double>(choices.size());
      }
    }
    const Continuation& c = choices[pick];
    s = c.segment;
    d = c.enter_end == 0 ? 1 : -1;
    u = c.enter_end == 0 ? leftover : lengths_[s] - leftover;
  }
  *segment = s;
  *direction = static_cast<signed char>(d);
  *along_m = std::clamp(u, 0.0, lengths_[s]);
  return importance;
}

}  // namespace indoorloc::mapmatch
