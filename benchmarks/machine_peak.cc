// Peak double-precision flops of one core for the SSE2 build (docs/performance.md):
// g++ -O3 -o /tmp/machine_peak benchmarks/machine_peak.cc && /tmp/machine_peak
#include <chrono>
#include <cstdio>
#include <ctime>
int main() {
  // 16 independent mul+add chains, vectorisable to SSE2 pairs: peak double flops on one core.
  double a[16], b = 1.0000001, c = 1e-9;
  for (int i = 0; i < 16; ++i) a[i] = i;
  const long n = 200000000;
  auto t0 = std::chrono::steady_clock::now(); std::clock_t c0 = std::clock();
  for (long k = 0; k < n; ++k) {
#pragma GCC unroll 16
    for (int i = 0; i < 16; ++i) a[i] = a[i] * b + c;
  }
  double s = 0; for (int i = 0; i < 16; ++i) s += a[i];
  double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC; std::printf("%.2f Gflop/s wall, %.2f per CPU-s (sum %g)\n", 2.0 * 16 * n / sec / 1e9, 2.0 * 16 * n / cpu / 1e9, s);
}
