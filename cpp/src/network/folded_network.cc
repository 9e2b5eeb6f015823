#include "indoorloc/network/folded_network.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "indoorloc/core/check.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"

namespace indoorloc::network {
namespace {

constexpr int kP = 18;  // unknowns per epoch
constexpr int kGravity = 15;  // first δg unknown of an epoch

}  // namespace

FoldedOrdering::FoldedOrdering(int base_blocks, int base_block_size)
    : n_(base_blocks), b_(base_block_size), h_(base_blocks / 2) {
  CheckArgument(base_blocks >= 1, "base_blocks", "must be >= 1, got " + std::to_string(base_blocks));
  CheckArgument(base_block_size >= 1, "base_block_size", "must be >= 1, got " + std::to_string(base_block_size));
}

int FoldedOrdering::SuperBlock(int j) const {
  assert(j >= 0 && j < n_);
  if (n_ % 2 == 0) return j < h_ ? h_ - 1 - j : j - h_;
  return j <= h_ ? h_ - j : j - h_;  // odd: the middle block h sits alone in super-block 0
}

int FoldedOrdering::Slot(int j) const {
  assert(j >= 0 && j < n_);
  if (n_ % 2 == 0) return j < h_ ? 0 : 1;
  return j <= h_ ? 0 : 1;
}

int FoldedOrdering::BaseBlock(int k, int s) const {
  assert(k >= 0 && k < num_blocks() && (s == 0 || s == 1));
  if (n_ % 2 == 0) return s == 0 ? h_ - 1 - k : h_ + k;
  if (s == 0) return h_ - k;
  return k == 0 ? -1 : h_ + k;
}

long long FoldedOrdering::FoldedIndex(long long u) const {
  const int j = static_cast<int>(u / b_);
  const long long within = u - static_cast<long long>(j) * b_;
  return static_cast<long long>(SuperBlock(j)) * (2LL * b_) + static_cast<long long>(Slot(j)) * b_ + within;
}

BlockRowAssembler FoldedAssembler(const FoldedOrdering& ordering, BlockRowAssembler base, const std::vector<Tie>& ties) {
  CheckArgument(static_cast<bool>(base), "base", "the base assembler is empty");
  const long long N = static_cast<long long>(ordering.base_blocks()) * ordering.base_block_size();
  const int K = ordering.num_blocks();
  struct Model {
    FoldedOrdering ord{1, 1};
    BlockRowAssembler base;
    std::vector<Tie> ties;
    std::vector<long long> fa, fb;      // folded indices of the tie ends
    std::vector<long long> start;       // CSR: ties touching super-block k at index[start[k] .. start[k+1])
    std::vector<int> index;
  };
  auto model = std::make_shared<Model>();
  model->ord = ordering;
  model->base = std::move(base);
  model->ties = ties;
  const size_t T = ties.size();
  model->fa.resize(T);
  model->fb.resize(T);
  std::vector<long long> count(static_cast<size_t>(K) + 1, 0);
  const long long super_size = 2LL * ordering.base_block_size();
  for (size_t t = 0; t < T; ++t) {
    const Tie& tie = ties[t];
    const std::string which = "tie " + std::to_string(t);
    CheckArgument(tie.a >= 0 && tie.a < N && tie.b >= 0 && tie.b < N, "ties",
                  which + " joins unknowns " + std::to_string(tie.a) + " and " + std::to_string(tie.b) +
                      ": outside the network (0 .. " + std::to_string(N - 1) + ")");
    CheckArgument(tie.a != tie.b, "ties", which + " ties unknown " + std::to_string(tie.a) + " to itself");
    CheckArgument(std::isfinite(tie.weight) && tie.weight > 0.0, "ties", which + ": weight must be finite and > 0");
    CheckArgument(std::isfinite(tie.value), "ties", which + ": value must be finite");
    model->fa[t] = ordering.FoldedIndex(tie.a);
    model->fb[t] = ordering.FoldedIndex(tie.b);
    const long long ka = model->fa[t] / super_size, kb = model->fb[t] / super_size;
    CheckArgument(std::llabs(ka - kb) <= 1, "ties",
                  which + " joins unknowns " + std::to_string(tie.a) + " and " + std::to_string(tie.b) +
                      ", which fold into super-blocks " + std::to_string(ka) + " and " + std::to_string(kb) +
                      ": not adjacent, so the tie would break the band (only ties between repeated passes, "
                      "an epoch and its mirror epoch or a neighbour of it, fold)");
    ++count[static_cast<size_t>(ka) + 1];
    if (kb != ka) ++count[static_cast<size_t>(kb) + 1];
  }
  for (int k = 0; k < K; ++k) count[static_cast<size_t>(k) + 1] += count[static_cast<size_t>(k)];
  model->start = count;
  model->index.resize(static_cast<size_t>(count.back()));
  std::vector<long long> fill(count.begin(), count.end() - 1);
  for (size_t t = 0; t < T; ++t) {
    const long long ka = model->fa[t] / super_size, kb = model->fb[t] / super_size;
    model->index[static_cast<size_t>(fill[static_cast<size_t>(ka)]++)] = static_cast<int>(t);
    if (kb != ka) model->index[static_cast<size_t>(fill[static_cast<size_t>(kb)]++)] = static_cast<int>(t);
  }

  return [model](int k, Eigen::MatrixXd* D, Eigen::MatrixXd* Lo, Eigen::VectorXd* r) {
    const Model& M = *model;
    const FoldedOrdering& ord = M.ord;
    const int b = ord.base_block_size();
    const int n = ord.base_blocks();
    Eigen::MatrixXd Db(b, b), Lb(b, b);
    Eigen::VectorXd rb(b);
    auto call = [&](int j) {
      Db.setZero();
      Lb.setZero();
      rb.setZero();
      M.base(j, &Db, &Lb, &rb);
    };
    for (int s = 0; s < 2; ++s) {
      const int j = ord.BaseBlock(k, s);
      if (j < 0) {  // padding: decoupled unknowns with A = I, b = 0
        D->block(s * b, s * b, b, b).diagonal().setOnes();
        continue;
      }
      call(j);
      D->block(s * b, s * b, b, b) += Db;
      r->segment(s * b, b) += rb;
      // Lower coupling A_{j,j-1} of the base band.
      if (j >= 1) {
        const int kk = ord.SuperBlock(j - 1), ss = ord.Slot(j - 1);
        if (kk == k) {
          D->block(s * b, ss * b, b, b) += Lb;
          D->block(ss * b, s * b, b, b) += Lb.transpose();
        } else if (kk == k - 1) {
          Lo->block(s * b, ss * b, b, b) += Lb;
        }
        // kk == k + 1: row k + 1 holds it.
      }
      // Upper coupling A_{j,j+1} = (A_{j+1,j})ᵀ when j+1 folded into the previous super-block.
      if (j + 1 < n && ord.SuperBlock(j + 1) == k - 1) {
        const int ss = ord.Slot(j + 1);
        call(j + 1);
        Lo->block(s * b, ss * b, b, b) += Lb.transpose();
      }
    }
    // Ties x_a - x_b = l (weight w): w (e_a - e_b)(e_a - e_b)ᵀ and w l (e_a - e_b).
    const long long B = 2LL * b, first = static_cast<long long>(k) * B;
    for (long long p = M.start[static_cast<size_t>(k)]; p < M.start[static_cast<size_t>(k) + 1]; ++p) {
      const size_t t = static_cast<size_t>(M.index[static_cast<size_t>(p)]);
      const Tie& tie = M.ties[t];
      const long long fa = M.fa[t], fb = M.fb[t];
      const bool a_here = fa / B == k, b_here = fb / B == k;
      const int ia = static_cast<int>(fa - first), ib = static_cast<int>(fb - first);
      if (a_here) {
        (*D)(ia, ia) += tie.weight;
        (*r)[ia] += tie.weight * tie.value;
      }
      if (b_here) {
        (*D)(ib, ib) += tie.weight;
        (*r)[ib] -= tie.weight * tie.value;
      }
      if (a_here && b_here) {
        (*D)(ia, ib) -= tie.weight;
        (*D)(ib, ia) -= tie.weight;
      } else if (a_here && fb / B == k - 1) {
        (*Lo)(ia, static_cast<int>(fb - (first - B))) -= tie.weight;
      } else if (b_here && fa / B == k - 1) {
        (*Lo)(ib, static_cast<int>(fa - (first - B))) -= tie.weight;
      }
    }
  };
}

RepeatedPassLayout MakeRepeatedPassLayout(const LinearInsNetworkOptions& network, long long num_ties,
                                          long long num_gupts, double sigma_xover_mps2, double sigma_gupt_mps2,
                                          int component) {
  const NetworkSize size = LinearInsNetworkSize(network);
  const long long E = size.imu_epochs;
  const long long P = E / 2, Q = (E - 1) / 2;
  CheckArgument(num_ties >= 0 && num_ties <= P + Q, "num_ties",
                "must be in 0 .. " + std::to_string(P + Q) + " (mirror pairs and their neighbours of " +
                    std::to_string(E) + " epochs), got " + std::to_string(num_ties));
  CheckArgument(num_gupts >= 0 && num_gupts <= E, "num_gupts",
                "must be in 0 .. " + std::to_string(E) + ", got " + std::to_string(num_gupts));
  CheckArgument(std::isfinite(sigma_xover_mps2) && sigma_xover_mps2 > 0.0, "sigma_xover_mps2", "must be finite and > 0");
  CheckArgument(std::isfinite(sigma_gupt_mps2) && sigma_gupt_mps2 > 0.0, "sigma_gupt_mps2", "must be finite and > 0");
  CheckArgument(component >= 0 && component < 3, "component", "must be 0, 1 or 2 (a δg axis)");
  RepeatedPassLayout layout;
  layout.ties.reserve(static_cast<size_t>(num_ties));
  const long long mirror = std::min(num_ties, P);
  for (long long i = 0; i < mirror; ++i) {
    const long long t = (i * P) / mirror;
    layout.ties.push_back(GravityTie{t, E - 1 - t, component, sigma_xover_mps2});
  }
  const long long extra = num_ties - mirror;
  for (long long i = 0; i < extra; ++i) {
    const long long t = (i * Q) / extra;
    layout.ties.push_back(GravityTie{t, E - 2 - t, component, sigma_xover_mps2});
  }
  layout.gupts.reserve(static_cast<size_t>(num_gupts));
  for (long long i = 0; i < num_gupts; ++i) {
    const long long n = ((2 * i + 1) * E) / (2 * num_gupts);
    layout.gupts.push_back(GravityUpdate{n, component, sigma_gupt_mps2});
  }
  return layout;
}

bool FoldedNetworkOptions::IsValid(std::string* error) const {
  // num_threads <= 0 means the hardware's, as in BlockTridiagonalOptions; above 1024 is a typo.
  return Validator(error)
      .AtLeast(checkpoint_interval, 0, "checkpoint_interval")
      .IntInRange(num_threads, -1024, 1024, "num_threads");
}

std::string FoldedNetworkResult::BriefReport() const {
  std::ostringstream s;
  s << "folded network: " << size.imu_epochs << " epochs, " << size.unknowns << " unknowns, " << ties << " ties, "
    << gupts << " GUPT, " << equations << " equations; " << folded_blocks << " super-blocks of " << folded_block_size
    << ", total " << total_seconds << " s, max error " << max_abs_error << ", δg RMSE " << gravity_rmse << " m/s²";
  return s.str();
}

BlockRowAssembler FoldedLinearInsAssembler(const LinearInsNetworkOptions& network, const std::vector<GravityTie>& ties,
                                           const std::vector<GravityUpdate>& gupts) {
  const NetworkSize size = LinearInsNetworkSize(network);
  const long long E = size.imu_epochs;
  const int g = size.block_size / kP;
  const double rate = network.imu_rate_hz;
  auto epoch_ok = [E](long long n) { return n >= 0 && n < E; };
  std::vector<Tie> unknown_ties;
  unknown_ties.reserve(ties.size());
  for (size_t i = 0; i < ties.size(); ++i) {
    const GravityTie& t = ties[i];
    const std::string which = "tie " + std::to_string(i);
    CheckArgument(epoch_ok(t.epoch_a) && epoch_ok(t.epoch_b), "ties",
                  which + " joins epochs " + std::to_string(t.epoch_a) + " and " + std::to_string(t.epoch_b) +
                      ": outside the network (0 .. " + std::to_string(E - 1) + ")");
    CheckArgument(t.epoch_a != t.epoch_b, "ties", which + " ties epoch " + std::to_string(t.epoch_a) + " to itself");
    CheckArgument(t.component >= 0 && t.component < 3, "ties", which + ": component must be 0, 1 or 2 (a δg axis)");
    CheckArgument(std::isfinite(t.sigma_mps2) && t.sigma_mps2 > 0.0, "ties",
                  which + ": sigma_mps2 must be finite and > 0, got " + std::to_string(t.sigma_mps2));
    const int c = kGravity + t.component;
    const double value = LinearInsTruth(t.epoch_a, rate)[c] - LinearInsTruth(t.epoch_b, rate)[c];  // noise-free
    unknown_ties.push_back(Tie{t.epoch_a * kP + c, t.epoch_b * kP + c, 1.0 / (t.sigma_mps2 * t.sigma_mps2), value});
  }
  // GUPTs indexed by base block: a diagonal term on the base block of their epoch.
  auto by_block = std::make_shared<std::vector<std::vector<GravityUpdate>>>(static_cast<size_t>(size.num_blocks));
  for (size_t i = 0; i < gupts.size(); ++i) {
    const GravityUpdate& u = gupts[i];
    const std::string which = "GUPT " + std::to_string(i);
    CheckArgument(epoch_ok(u.epoch), "gupts",
                  which + " at epoch " + std::to_string(u.epoch) + ": outside the network (0 .. " +
                      std::to_string(E - 1) + ")");
    CheckArgument(u.component >= 0 && u.component < 3, "gupts", which + ": component must be 0, 1 or 2 (a δg axis)");
    CheckArgument(std::isfinite(u.sigma_mps2) && u.sigma_mps2 > 0.0, "gupts",
                  which + ": sigma_mps2 must be finite and > 0, got " + std::to_string(u.sigma_mps2));
    (*by_block)[static_cast<size_t>(u.epoch / g)].push_back(u);
  }
  BlockRowAssembler lin = LinearInsAssembler(network);
  BlockRowAssembler with_gupt = [lin, by_block, g, rate](int j, Eigen::MatrixXd* D, Eigen::MatrixXd* Lo,
                                                         Eigen::VectorXd* r) {
    lin(j, D, Lo, r);
    for (const GravityUpdate& u : (*by_block)[static_cast<size_t>(j)]) {
      const int i = static_cast<int>(u.epoch - static_cast<long long>(g) * j) * kP + kGravity + u.component;
      const double w = 1.0 / (u.sigma_mps2 * u.sigma_mps2);
      (*D)(i, i) += w;
      (*r)[i] += w * LinearInsTruth(u.epoch, rate)[kGravity + u.component];
    }
  };
  return FoldedAssembler(FoldedOrdering(size.num_blocks, size.block_size), with_gupt, unknown_ties);
}

FoldedNetworkResult SolveFoldedLinearInsNetwork(const LinearInsNetworkOptions& network,
                                                const std::vector<GravityTie>& ties,
                                                const std::vector<GravityUpdate>& gupts,
                                                const FoldedNetworkOptions& options) {
  ValidateOptions(options);
  WallTimer total;
  FoldedNetworkResult result;
  result.size = LinearInsNetworkSize(network);
  result.ties = static_cast<long long>(ties.size());
  result.gupts = static_cast<long long>(gupts.size());
  result.equations = result.size.equations + result.ties + result.gupts;
  const BlockRowAssembler assemble = FoldedLinearInsAssembler(network, ties, gupts);
  const FoldedOrdering ord(result.size.num_blocks, result.size.block_size);
  result.folded_blocks = ord.num_blocks();
  result.folded_block_size = ord.block_size();
  const long long E = result.size.imu_epochs;
  const int b = ord.base_block_size(), g = b / kP;

  BlockTridiagonalOptions so;
  so.checkpoint_interval = options.checkpoint_interval;
  so.num_threads = options.num_threads;
  if (options.gravity_covariance) {
    for (int s = 0; s < 2; ++s)
      for (int e = 0; e < g; ++e)
        for (int c = 0; c < 3; ++c) so.selected.push_back(s * b + e * kP + kGravity + c);
  }
  const BlockTridiagonalSolution sol = SolveBlockTridiagonal(ord.num_blocks(), ord.block_size(), assemble, so);
  result.solver = sol.summary;

  double max_err = 0.0, g_sq = 0.0;
  if (options.keep_gravity_estimate) result.gravity_estimate.resize(E, 3);
  if (options.gravity_covariance) result.gravity_sigma.resize(E, 3);
  for (long long n = 0; n < E; ++n) {
    const Eigen::Matrix<double, 18, 1> xs = LinearInsTruth(n, network.imu_rate_hz);
    const long long f = ord.FoldedIndex(n * kP);  // the 18 unknowns of an epoch stay contiguous
    const auto x = sol.x.segment<kP>(f);
    max_err = std::max(max_err, (x - xs).cwiseAbs().maxCoeff());
    g_sq += (x.tail<3>() - xs.tail<3>()).squaredNorm();
    if (options.keep_gravity_estimate) result.gravity_estimate.row(n) = x.tail<3>().transpose();
    if (options.gravity_covariance) {
      const int j = static_cast<int>(n / g);
      const Eigen::MatrixXd& cov = sol.covariance[static_cast<size_t>(ord.SuperBlock(j))];
      const int pos = 3 * (ord.Slot(j) * g + static_cast<int>(n % g));
      for (int c = 0; c < 3; ++c) result.gravity_sigma(n, c) = std::sqrt(std::max(0.0, cov(pos + c, pos + c)));
    }
  }
  result.max_abs_error = max_err;
  result.gravity_rmse = std::sqrt(g_sq / (3.0 * static_cast<double>(E)));
  result.total_seconds = total.ElapsedSeconds();
  return result;
}

}  // namespace indoorloc::network
