#include "indoorloc/core/simd_dispatch.h"

#include <cstdlib>
#include <cstring>

namespace indoorloc {

bool UseAvx2() {
  static const bool use = [] {
#if defined(__x86_64__) || defined(__i386__)
    const char* off = std::getenv("INDOORLOC_DISABLE_AVX2");
    if (off != nullptr && std::strcmp(off, "") != 0 && std::strcmp(off, "0") != 0) return false;
    return __builtin_cpu_supports("avx2") != 0;
#else
    return false;
#endif
  }();
  return use;
}

}  // namespace indoorloc
