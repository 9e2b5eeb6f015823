// Thread CPU time of SharedApMatcher::Nearest per single query on the dumped maps (exp/dump_bins.py).
#include <time.h>
#include <cstdio>
#include <cstdlib>
#include <vector>
#include <algorithm>
#include "indoorloc/wifi/shared_ap_matcher.h"
using namespace indoorloc::wifi;
static double cpu() { timespec t; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
int main(int argc, char** argv) {
  FILE* f = fopen(argv[1], "rb"); long long nk[2]; fread(nk, 8, 2, f);
  const long N = nk[0], K = nk[1];
  SharedApRowMatrixXd X(N, K), Q(300, K), R(300, K); Eigen::VectorXd g(K);
  fread(X.data(), 8, N * K, f); fread(g.data(), 8, K, f); fread(Q.data(), 8, 300 * K, f); fread(R.data(), 8, 300 * K, f);
  SharedApMatcher m(X, g);
  for (auto* qs : {&Q, &R}) {
    std::vector<double> t;
    for (int rep = 0; rep < 3; ++rep)
      for (int q = 0; q < 300; ++q) { double c = cpu(); m.Nearest(qs->row(q)); t.push_back(cpu() - c); }
    std::sort(t.begin(), t.end());
    printf("%s %s: p50 %.0f p90 %.0f p99 %.0f us\n", argv[1], qs == &Q ? "bench200" : "realish", 1e6 * t[t.size() / 2], 1e6 * t[t.size() * 9 / 10], 1e6 * t[t.size() * 99 / 100]);
  }
}
