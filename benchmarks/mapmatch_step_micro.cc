// Micro benchmark of ParticleMapMatcher::Step (docs/performance.md, the mapmatch profile): the
// warehouse network as bench_mapmatch.py generates it, one simulated 200 s trajectory, recovery
// off, N particles (default 10^4), best of R runs (default 20) in CPU time of the thread, and a
// checksum of every step's estimate and ESS (an optimisation that keeps the numbers keeps it).
// Build against a worktree's library (after /work/devbuild.sh _core):
//   g++ -O3 -std=c++17 -frounding-math -Icpp/include -isystem /usr/include/eigen3 \
//     benchmarks/mapmatch_step_micro.cc build/dev/cpp/libindoorloc.a -o /tmp/mapmatch_step_micro
//   nice -n 10 /tmp/mapmatch_step_micro 10000 20     (INDOORLOC_DISABLE_AVX2=1: the portable path)
#include <cstdio>
#include <ctime>
#include <vector>
#include <algorithm>
#include <array>
#include "indoorloc/mapmatch/particle_map_matcher.h"
#include "indoorloc/mapmatch/trajectory_simulator.h"
using namespace indoorloc; using namespace indoorloc::mapmatch;
static double cpu() { timespec t; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
int main(int argc, char** argv) {
  int n = argc > 1 ? atoi(argv[1]) : 10000, reps = argc > 2 ? atoi(argv[2]) : 20;
  std::vector<std::array<double,4>> rows;
  double hs[3] = {0, 18, 36}; double vx[7] = {0, 10, 20, 30, 40, 50, 60};
  for (double y : hs) { std::vector<double> cuts = {0, 60}; for (double x : vx) { double y1 = (x==10||x==30||x==50) ? 18 : 36; if (y <= y1 && x > 0 && x < 60) cuts.push_back(x);} std::sort(cuts.begin(), cuts.end()); for (size_t k=0;k+1<cuts.size();++k) rows.push_back({cuts[k], y, cuts[k+1], y}); }
  for (double x : vx) { double y1 = (x==10||x==30||x==50) ? 18 : 36; std::vector<double> cuts = {0, y1}; for (double y : hs) if (y > 0 && y < y1) cuts.push_back(y); std::sort(cuts.begin(), cuts.end()); for (size_t k=0;k+1<cuts.size();++k) rows.push_back({x, cuts[k], x, cuts[k+1]}); }
  RowMatrixXd seg(rows.size(), 4); for (size_t k=0;k<rows.size();++k) for (int j=0;j<4;++j) seg(k,j)=rows[k][j];
  RoadNetwork net(seg, Eigen::VectorXi());
  TrajectoryOptions to; to.heading_kappa = 5.0; RandomStream r(0);
  Trajectory tr = SimulateTrajectory(net, to, r);
  FilterOptions o; o.num_particles = n; o.kappa = 1.0; o.noise_halfwidth_m = 0.6; o.seed = 0; o.recovery_disagreement = 0.0;
  ParticleMapMatcher f(net, o);
  double best = 1e9, checksum = 0; int T = tr.speed_mps.size();
  for (int rep = 0; rep < reps; ++rep) {
    f.Reset(); double t0 = cpu(); double cs = 0;
    for (int k = 0; k < T; ++k) { auto e = f.Step(tr.speed_mps[k], tr.heading_rad[k], to.dt_s); cs += e.weighted_mean_m.x() * 1.0 + e.weighted_mean_m.y() * 3.0 + e.ess; }
    best = std::min(best, cpu() - t0); checksum = cs;
  }
  std::printf("resamplings %d of %d\n", f.summary().resamplings, f.summary().steps);
  std::printf("segments %d N %d T %d best %.3f ns/ps checksum %.17g\n", net.num_segments(), n, T, best / (double(n) * T) * 1e9, checksum);
}
