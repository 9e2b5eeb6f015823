// The particle tracker's absolute observations (a WiFi scan, a position fix), given by their
// log-likelihood at a point, and the recovery they drive. An observation weights the particles
// (log w += log p(observation | particle)), finishes the update (normalisation, ESS,
// resampling, estimate) and reports the predictive log-likelihood. Recovery: when that stays
// more than recovery_log_ratio nats below the best candidate point's for recovery_scans
// observations in a row, a fraction recovery_fraction of the particles is re-drawn from the
// observation's likelihood over the candidates.
#include <algorithm>
#include <cmath>
#include <vector>

#include "indoorloc/core/resampling.h"
#include "particle_tracker_impl.h"

namespace indoorloc::fusion {

// One absolute observation given by its log-likelihood point_ll(x, y, tracker floor): places
// the cloud of an unknown start that is still waiting for one, else weights the particles,
// resamples, and runs the recovery test. `informative`: the observation says something about the
// position (a scan with heard readings, a fix with components).
TrackerEstimate ParticleTracker::Impl::Observe(double time_s, bool informative, const PointLogLikelihood& point_ll) {
  TrackerEstimate est;
  est.time_s = time_s;
  if (awaiting_first_fix && informative) {
    // Unknown start: the first informative observation places the cloud (the seeking phase).
    std::vector<int> all(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) all[i] = i;
    DrawFromCandidates(point_ll, all);
    log_w.setConstant(-std::log(static_cast<double>(n)));
    awaiting_first_fix = false;
    est.recovered = true;
    FillEstimate(&est);
    est.ess = n;
    Snapshot(true);
    return est;
  }
  Eigen::VectorXd ll(n);
  ForBlocks(n, [&](int, int begin, int end, RandomStream&) {
    for (int i = begin; i < end; ++i) ll[i] = point_ll(x[i], y[i], floor[i]);
  });
  log_w += ll;
  // log p(observation | past), tempered (log_w was normalised before the update).
  const double predictive = FinishUpdate(log_w.maxCoeff(), &est);
  est.log_likelihood = predictive;
  summary.total_log_likelihood += predictive;

  // Recovery: the observation fits the best candidate far better than the cloud, several in a row.
  if (options.recovery_log_ratio > 0.0 && informative) {
    std::vector<int> cf, cr;
    const Eigen::VectorXd cll = CandidateLogLikelihoods(point_ll, &cf, &cr);
    const double best = cll.size() > 0 ? cll.maxCoeff() : tracker_detail::kNegInf;
    if (predictive < best - options.recovery_log_ratio) {
      ++consecutive_disagreement;
    } else {
      consecutive_disagreement = 0;
    }
    if (consecutive_disagreement >= options.recovery_scans) {
      if (!est.resampled) {  // equal weights first, so that replacing a subset is unbiased
        Resample(log_w, options.resampling.scheme, rng, &ancestors);
        Gather(ancestors);
        log_w.setConstant(-std::log(static_cast<double>(n)));
      }
      const int every = std::max(1, static_cast<int>(std::lround(1.0 / options.recovery_fraction)));
      std::vector<int> slots;
      for (int i = 0; i < n; i += every) slots.push_back(i);
      DrawFromCandidates(point_ll, slots);
      consecutive_disagreement = 0;
      est.recovered = true;
      ++summary.recoveries;
      FillEstimate(&est);
    }
  }
  Snapshot(true);
  return est;
}

// The WiFi likelihood as a point function of tracker floors.
PointLogLikelihood ParticleTracker::Impl::WifiPointLL(const WifiObservation& obs) const {
  return [this, &obs](double px, double py, int f) { return wifi->LogLikelihood(px, py, model_floor[f], obs); };
}

}  // namespace indoorloc::fusion
