#include "indoorloc/mapmatch/trajectory_simulator.h"

#include <cmath>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::mapmatch {
namespace {
constexpr double kPi = 3.14159265358979323846;
double Wrap(double a) {
  a = std::remainder(a, 2.0 * kPi);
  return a <= -kPi ? a + 2.0 * kPi : a;
}
}  // namespace

bool TrajectoryOptions::IsValid(std::string* error) const {
  Validator v(error);
  v.Scale(duration_s, "duration_s").Scale(dt_s, "dt_s");
  if (v) v.Check(duration_s / dt_s <= 1e7, "duration_s / dt_s", "must be <= 1e7 steps (58 days at 2 Hz)");
  // Speeds above 1e6 m/s turn positions into inf after a few steps.
  return v.InRange(speed_mps, 0.0, 1e6, "speed_mps")
      .InRange(speed_noise_sd_mps, 0.0, 1e6, "speed_noise_sd_mps")
      .InRange(speed_bias_halfwidth_mps, 0.0, 1e6, "speed_bias_halfwidth_mps")
      .NonNegative(heading_kappa, "heading_kappa");
}

double TravelHeading(const RoadNetwork& network, int segment, int direction) {
  return direction > 0 ? network.headings_rad()[segment] : Wrap(network.headings_rad()[segment] + kPi);
}

Trajectory SimulateTrajectory(const RoadNetwork& network, const TrajectoryOptions& options, RandomStream& rng) {
  ValidateOptions(options);
  const int steps = static_cast<int>(std::floor(options.duration_s / options.dt_s + 1e-9));
  Trajectory out;
  out.positions_m.resize(steps, 2);
  out.segments.resize(steps);
  out.heading_true_rad.resize(steps);
  out.speed_mps.resize(steps);
  out.heading_rad.resize(steps);
  out.speed_bias_mps = rng.Uniform(-options.speed_bias_halfwidth_mps, options.speed_bias_halfwidth_mps);
  // Unknown start: a segment with probability proportional to its length, a uniform position on
  // it and a random direction.
  double pick = rng.Uniform(0.0, network.total_length_m());
  int s = 0;
  while (s + 1 < network.num_segments() && pick > network.lengths_m()[s]) pick -= network.lengths_m()[s++];
  double u = std::min(pick, network.lengths_m()[s]);
  int d = rng.Uniform01() < 0.5 ? 1 : -1;
  out.start_m = network.point_at(s, u);
  const double step_m = options.speed_mps * options.dt_s;
  std::vector<Continuation> turns;
  for (int k = 0; k < steps; ++k) {
    u += d * step_m;
    for (int guard = 0; guard < 100000; ++guard) {
      int end;
      double leftover;
      if (d > 0 && u > network.lengths_m()[s]) {
        end = 1;
        leftover = u - network.lengths_m()[s];
      } else if (d < 0 && u < 0.0) {
        end = 0;
        leftover = -u;
      } else {
        break;
      }
      const auto& options_here = network.continuations(s, end);
      // Turns only (|heading change| >= 30°) unless straight travel is allowed or no turn exists.
      turns.clear();
      const double heading_in = TravelHeading(network, s, d);
      for (const Continuation& c : options_here) {
        const double heading_out = TravelHeading(network, c.segment, c.enter_end == 0 ? 1 : -1);
        if (options.allow_straight || std::cos(heading_out - heading_in) < std::cos(kPi / 6)) turns.push_back(c);
      }
      const std::vector<Continuation>& pool = turns.empty() ? options_here : turns;
      const Continuation& c = pool[rng.UniformInt(pool.size())];
      s = c.segment;
      d = c.enter_end == 0 ? 1 : -1;
      u = c.enter_end == 0 ? leftover : network.lengths_m()[s] - leftover;
    }
    out.positions_m.row(k) = network.point_at(s, u).transpose();
    out.segments[k] = s;
    out.heading_true_rad[k] = TravelHeading(network, s, d);
    out.speed_mps[k] = options.speed_mps + out.speed_bias_mps + rng.Normal(0.0, options.speed_noise_sd_mps);
    out.heading_rad[k] = Wrap(out.heading_true_rad[k] + rng.VonMises(0.0, options.heading_kappa));
  }
  return out;
}

}  // namespace indoorloc::mapmatch
