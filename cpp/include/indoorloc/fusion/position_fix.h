// Position fixes: what an external locator (a fingerprint kNN on a crowdsourced map, BLE, UWB,
// a user's tap on the map) says about where the walker is, as an observation of the fusion
// tracker. A fix is a Gaussian mixture over the floor plus an outlier floor:
//
//   p(fix | z, f) = ε / A + (1 - ε) Σ_{k: f_k = f or any} w_k N(z; μ_k, σ_k² I₂)   (z on floor f)
//
// with weights w_k normalised to sum 1, component k on floor f_k (or on any floor), ε the
// probability that the fix has nothing to do with the walker's position (a gross fingerprint
// mismatch across the building) and A the walkable area of all the tracker's floors [m²] (the
// uniform density of an unrelated fix). Components on several floors make the fix say which
// floor too (floor identification); a particle on a floor without components gets the outlier
// density only. The tracker adds τ_fix log p(fix | z, f).
//
// Why a mixture with an outlier term: on real crowdsourced maps (the 2020 indoor-location
// competition's mall) the nearest fingerprints of one scan are often spread over several places
// tens of metres apart (docs/fusion_real.md); a single Gaussian fix at their mean is then
// between them, in a shop, and a light-tailed likelihood lets one such scan wipe out the
// particles that were right. The mixture keeps each candidate place, the ε term bounds what one
// scan can do: at most log((1 - ε) ... ) - log(ε / A) nats between any two positions.
#pragma once
#include <limits>
#include <string>
#include <Eigen/Core>

namespace indoorloc::fusion {

struct PositionFix {
  /// "Any floor" marker (outside every real floor number and exact as a double).
  static constexpr int kAnyFloor = -(1 << 20);
  using Means = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
  double time_s = 0.0;
  Means means_m;  ///< K x 2 component means [m]
  /// K floor numbers of the components; kAnyFloor: the component applies on every floor. Empty:
  /// every component on any floor.
  Eigen::VectorXi floors;
  Eigen::VectorXd sds_m;     ///< K isotropic component sds [m], finite and > 0
  Eigen::VectorXd weights;   ///< K, finite and >= 0 with a positive sum (normalised on use)
  bool empty() const { return means_m.rows() == 0; }
};

struct FixLikelihoodOptions {
  /// ε: probability that a fix is unrelated to the position (uniform over the walkable area).
  /// Default: the leave-one-floor-out choice for WiFi fingerprint fixes on the competition mall
  /// (docs/fusion_real.md); other locators (BLE, UWB) will want their own.
  double outlier_probability = 0.1;
  /// τ_fix: exponent of the fix likelihood in (0, 1] (consecutive fixes from overlapping WiFi
  /// readings are not independent); default chosen with ε.
  double tempering = 0.6;
  bool IsValid(std::string* error) const;
};

/// Throws std::invalid_argument naming `argument` (and the field) on a malformed fix: shapes
/// that disagree, NaN/inf, sd <= 0, negative weights or weights summing to 0.
void CheckPositionFix(const PositionFix& fix, const char* argument);

/// The fix at `time_s` made of the candidates of nonzero weight among K: row j of `means_m`
/// (K x 2) [m], sds_m[j] [m], weights[j] and floors[j] (kAnyFloor: any floor) for candidate j, in
/// order. Candidates of weight 0 are padding and are dropped without being read (their mean and
/// sd may be NaN), so fixes built from K candidates may have fewer components. The result is not
/// checked: call CheckPositionFix on it where the candidates come from outside.
PositionFix FixFromCandidates(double time_s, const Eigen::Ref<const PositionFix::Means>& means_m,
                              const Eigen::Ref<const Eigen::VectorXd>& sds_m,
                              const Eigen::Ref<const Eigen::VectorXd>& weights,
                              const Eigen::Ref<const Eigen::VectorXi>& floors);

/// Evaluates τ_fix log p(fix | z) for one fix.
class FixLikelihood {
 public:
  /// `fix` must have passed CheckPositionFix and outlive this object.
  FixLikelihood(const PositionFix& fix, const FixLikelihoodOptions& options);
  /// Tempered log-likelihood at (x, y) [m] on floor number `floor`; `area_m2` (> 0) is the
  /// walkable area of all floors (the outlier density is ε / area). Thread-safe.
  double LogLikelihood(double x_m, double y_m, int floor, double area_m2) const;

 private:
  const PositionFix& fix_;
  FixLikelihoodOptions options_;
  Eigen::VectorXd log_component_scale_;  // log((1 - ε) w_k / (2π σ_k²))
  Eigen::VectorXd inv_two_var_;          // 1 / (2 σ_k²)
};

}  // namespace indoorloc::fusion
