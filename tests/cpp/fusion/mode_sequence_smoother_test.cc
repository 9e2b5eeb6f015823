// The (cell, mode) forward-backward smoother on tiny lattices: a hand-worked chain (the direction
// of dx and dy, the posterior of each tick), mass kept without walls and lost into a wall (read
// from the per-tick normalisers, log_evidence), the restart when every path is walled off, and
// the argument checks naming the argument.
#include "indoorloc/fusion/mode_sequence_smoother.h"

#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>

#include <gtest/gtest.h>

#include "fusion/expect_invalid.h"

namespace indoorloc::fusion {
namespace {

// A (ny, nx) lattice whose every cell is a state (row-major), centres (column, row) [m].
ModeSequenceModel FullLattice(int ny, int nx) {
  ModeSequenceModel model;
  model.state_index.resize(ny, nx);
  model.cells_m.resize(ny * nx, 2);
  for (int r = 0; r < ny; ++r) {
    for (int c = 0; c < nx; ++c) {
      model.state_index(r, c) = r * nx + c;
      model.cells_m.row(r * nx + c) << c, r;
    }
  }
  return model;
}

LatticeStencil Stencil(std::initializer_list<std::array<double, 3>> taps) {  // (dx, dy, weight)
  LatticeStencil st;
  st.offsets_cells.resize(static_cast<Eigen::Index>(taps.size()), 2);
  st.weights.resize(static_cast<Eigen::Index>(taps.size()));
  Eigen::Index i = 0;
  for (const auto& t : taps) {
    st.offsets_cells.row(i) << static_cast<int>(t[0]), static_cast<int>(t[1]);
    st.weights(i++) = t[2];
  }
  return st;
}

ModeSequenceEvidence Plain(int ticks, int n) {
  ModeSequenceEvidence ev;
  ev.num_ticks = ticks;
  ev.wall_factor = Eigen::VectorXd::Ones(n);
  ev.fix_ticks.resize(0);
  ev.fix_factors.resize(0, n);
  return ev;
}

TEST(ModeSequenceSmoother, AHandWorkedChainAlongXAndAlongY) {
  // Three cells in a line, one mode moving +1 cell per tick, two ticks: the uniform start loses
  // the last cell's third off the lattice; tick 1 holds (0, ½, ½), tick 0 (½, ½, 0).
  for (const bool along_x : {true, false}) {
    ModeSequenceModel model = along_x ? FullLattice(1, 3) : FullLattice(3, 1);
    model.stencils = {along_x ? Stencil({{1, 0, 1.0}}) : Stencil({{0, 1, 1.0}})};
    model.mode_transition = Eigen::MatrixXd::Ones(1, 1);
    const ModeSequenceResult r = SmoothModeSequence(model, Plain(2, 3), true);
    const int axis = along_x ? 0 : 1;
    EXPECT_NEAR(r.mean_m(0, axis), 0.5, 1e-7);
    EXPECT_NEAR(r.mean_m(1, axis), 1.5, 1e-7);
    EXPECT_NEAR(r.mean_m(0, 1 - axis), 0.0, 1e-12);
    EXPECT_NEAR(r.posterior(1, 0), 0.0, 1e-12);
    EXPECT_NEAR(r.posterior(0, 2), 0.0, 1e-12);
    EXPECT_NEAR(r.summary.log_evidence, std::log(2.0 / 3.0), 1e-12);
    EXPECT_EQ(r.summary.restarts, 0);
  }
}

// A lattice of 9 x 9 states, all mass at the centre at tick 0 (a fix there), two modes.
ModeSequenceModel TwoModes() {
  ModeSequenceModel model = FullLattice(9, 9);
  model.stencils = {Stencil({{0, 0, 0.5}, {1, 0, 0.125}, {-1, 0, 0.125}, {0, 1, 0.125}, {0, -1, 0.125}}),
                    Stencil({{1, 0, 0.7}, {1, 1, 0.3}})};
  model.mode_transition.resize(2, 2);
  model.mode_transition << 0.9, 0.1, 0.2, 0.8;
  return model;
}

ModeSequenceEvidence AtTheCentre(int ticks) {
  ModeSequenceEvidence ev = Plain(ticks, 81);
  ev.fix_ticks.resize(1);
  ev.fix_ticks << 0;
  ev.fix_factors = Eigen::MatrixXd::Zero(1, 81);
  ev.fix_factors(0, 4 * 9 + 4) = 1.0;
  return ev;
}

TEST(ModeSequenceSmoother, MassIsKeptWithoutWalls) {
  // Three ticks from the centre stay inside the 9 x 9 lattice: every normaliser after the first
  // (which is 1/N: M modes of 1/(M N) at one cell) is 1.
  const ModeSequenceResult r = SmoothModeSequence(TwoModes(), AtTheCentre(4), true);
  EXPECT_NEAR(r.summary.log_evidence, -std::log(81.0), 1e-12);
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(r.posterior.row(k).sum(), 1.0, 1e-12);
  EXPECT_NEAR(r.mean_m(0, 0), 4.0, 1e-12);
  EXPECT_GT(r.mean_m(3, 0), 4.0);  // the second mode drifts east
}

TEST(ModeSequenceSmoother, AWallLosesTheMassMovedOntoIt) {
  // The cell east of the centre is no state: the first mode's 0.125 and the second mode's 0.7
  // sent there from the centre at tick 1 are lost. Tick 0's modes are 1/2 each (uniform).
  ModeSequenceModel model = TwoModes();
  const int east = model.state_index(4, 5);
  model.state_index(4, 5) = -1;
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 9; ++c) {
      if (model.state_index(r, c) > east) --model.state_index(r, c);
    }
  }
  Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor> kept(80, 2);
  for (int s = 0, j = 0; s < 81; ++s) {
    if (s != east) kept.row(j++) = model.cells_m.row(s);
  }
  model.cells_m = kept;
  ModeSequenceEvidence ev = AtTheCentre(2);
  ev.wall_factor = Eigen::VectorXd::Ones(80);
  ev.fix_factors = Eigen::MatrixXd::Zero(1, 80);
  ev.fix_factors(0, 4 * 9 + 4) = 1.0;
  const ModeSequenceResult r = SmoothModeSequence(model, ev);
  // After the mode step the modes hold 0.5 (0.9 + 0.2) = 0.55 and 0.45.
  const double kept_mass = 0.55 * (1.0 - 0.125) + 0.45 * (1.0 - 0.7);
  EXPECT_NEAR(r.summary.log_evidence, -std::log(80.0) + std::log(kept_mass), 1e-12);
}

TEST(ModeSequenceSmoother, TheStatesMayBeNumberedInAnyOrder) {
  // The same chain with the states numbered backwards (no run longer than one cell): the same
  // track, and each state's posterior moves with its number.
  const ModeSequenceModel model = TwoModes();
  ModeSequenceModel reversed = model;
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 9; ++c) reversed.state_index(r, c) = 80 - model.state_index(r, c);
  }
  reversed.cells_m = model.cells_m.colwise().reverse();
  ModeSequenceEvidence ev = AtTheCentre(5);
  ev.wall_factor = Eigen::VectorXd::LinSpaced(81, 0.5, 1.0);
  ModeSequenceEvidence ev_reversed = ev;
  ev_reversed.wall_factor = ev.wall_factor.reverse();
  ev_reversed.fix_factors = ev.fix_factors.rowwise().reverse();
  const ModeSequenceResult a = SmoothModeSequence(model, ev, true);
  const ModeSequenceResult b = SmoothModeSequence(reversed, ev_reversed, true);
  EXPECT_LT((a.mean_m - b.mean_m).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((a.posterior - b.posterior.rowwise().reverse()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(a.summary.log_evidence, b.summary.log_evidence, 1e-12);
}

TEST(ModeSequenceSmoother, RestartsFromTheEvidenceWhenEverythingIsWalledOff) {
  ModeSequenceModel model = FullLattice(1, 2);
  model.stencils = {Stencil({{5, 0, 1.0}})};  // off the lattice from every cell
  model.mode_transition = Eigen::MatrixXd::Ones(1, 1);
  ModeSequenceEvidence ev = Plain(2, 2);
  ev.fix_ticks.resize(1);
  ev.fix_ticks << 1;
  ev.fix_factors.resize(1, 2);
  ev.fix_factors << 1.0, 3.0;
  const ModeSequenceResult r = SmoothModeSequence(model, ev, true);
  EXPECT_EQ(r.summary.restarts, 1);
  EXPECT_NEAR(r.mean_m(1, 0), 0.75, 1e-12);
  EXPECT_NEAR(r.mean_m(0, 0), 0.5, 1e-7);  // no path reaches tick 1: tick 0 keeps its forward pass
  EXPECT_TRUE(std::isfinite(r.summary.log_evidence));
}

TEST(ModeSequenceSmoother, BadArgumentsAreNamed) {
  const ModeSequenceModel good = TwoModes();
  const ModeSequenceEvidence ev = AtTheCentre(3);
  auto with = [&](auto change) {
    ModeSequenceModel m = good;
    ModeSequenceEvidence e = ev;
    change(m, e);
    return [m, e] { SmoothModeSequence(m, e); };
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ExpectInvalid(with([](auto& m, auto&) { m.stencils[1].weights(0) = -0.1; }), {"stencils[1]", ">= 0"});
  ExpectInvalid(with([&](auto& m, auto&) { m.stencils[0].weights(2) = nan; }), {"stencils[0]", "nan"});
  ExpectInvalid(with([](auto& m, auto&) { m.stencils[0].weights.resize(2); }), {"stencils[0]", "weights"});
  ExpectInvalid(with([](auto& m, auto&) { m.stencils.pop_back(); }), {"mode_transition", "(1, 1)"});
  ExpectInvalid(with([](auto& m, auto&) { m.mode_transition(0, 1) = -0.1; }), {"mode_transition", ">= 0"});
  ExpectInvalid(with([](auto& m, auto&) { m.state_index(0, 1) = 0; }), {"state_index", "more than once"});
  ExpectInvalid(with([](auto& m, auto&) { m.state_index(0, 1) = 81; }), {"state_index", "[0, 81)"});
  ExpectInvalid(with([](auto& m, auto&) { m.state_index(0, 1) = -1; }), {"state_index", "state 1"});
  ExpectInvalid(with([&](auto& m, auto&) { m.cells_m(3, 1) = nan; }), {"cells_m", "NaN"});
  ExpectInvalid(with([](auto&, auto& e) { e.wall_factor.resize(80); }), {"wall_factor", "81"});
  ExpectInvalid(with([](auto&, auto& e) { e.wall_factor(7) = -1.0; }), {"wall_factor", ">= 0"});
  ExpectInvalid(with([](auto&, auto& e) { e.num_ticks = 0; }), {"num_ticks"});
  ExpectInvalid(with([](auto&, auto& e) { e.fix_ticks << 3; }), {"fix_ticks", "[0, num_ticks = 3)"});
  ExpectInvalid(with([](auto&, auto& e) { e.fix_factors.resize(2, 81); }), {"fix_factors", "(1, 81)"});
  ExpectInvalid(with([](auto&, auto& e) { e.fix_factors.setZero(); }), {"fix_factors", "zero on every state"});
  ExpectInvalid(with([](auto&, auto& e) { e.wall_factor.setZero(); }), {"wall_factor", "zero on every state"});
}

}  // namespace
}  // namespace indoorloc::fusion
