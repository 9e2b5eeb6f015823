#include "indoorloc/analog/catalog.h"

#include "indoorloc/core/check.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/validate.h"

namespace indoorloc::analog {

bool CatalogOptions::IsValid(std::string* error) const {
  return Validator(error).IntInRange(lag, 1, 1000000, "lag").IntInRange(stride, 1, 1000000, "stride");
}

Catalog::Catalog(const std::vector<RowMatrixXd>& trajectories, const CatalogOptions& options) : options_(options) {
  ValidateOptions(options_);
  CheckArgument(!trajectories.empty(), "trajectories", "is empty");
  base_dim_ = static_cast<int>(trajectories[0].cols());
  CheckArgument(base_dim_ > 0, "trajectories", "have zero columns");
  const int lag = options_.lag, stride = options_.stride;
  Eigen::Index total = 0;
  for (size_t i = 0; i < trajectories.size(); ++i) {
    const std::string name = "trajectories[" + std::to_string(i) + "]";
    CheckArgument(trajectories[i].cols() == base_dim_, name,
                  "has " + std::to_string(trajectories[i].cols()) + " columns, the first has " + std::to_string(base_dim_));
    CheckFinite(trajectories[i], name);
    total += std::max<Eigen::Index>(0, trajectories[i].rows() - lag + 1);
  }
  states_.resize(total, static_cast<Eigen::Index>(base_dim_) * lag);
  Eigen::Index row = 0;
  for (const RowMatrixXd& x : trajectories) {
    const Eigen::Index first = row;
    const Eigen::Index count = std::max<Eigen::Index>(0, x.rows() - lag + 1);
    for (Eigen::Index t = lag - 1; t < x.rows(); ++t, ++row) {
      for (int l = 0; l < lag; ++l) states_.block(row, static_cast<Eigen::Index>(l) * base_dim_, 1, base_dim_) = x.row(t - l);
    }
    for (Eigen::Index s = 0; s + stride < count; ++s) {
      analogs_.push_back(static_cast<int>(first + s));
      successors_.push_back(static_cast<int>(first + s + stride));
    }
  }
  CheckArgument(!analogs_.empty(), "trajectories",
                "too short: no state has a successor (need more than lag + stride - 1 samples)");
}

}  // namespace indoorloc::analog
