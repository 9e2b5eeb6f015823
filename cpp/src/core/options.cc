#include "indoorloc/core/options.h"

namespace indoorloc {

std::string_view ToString(Termination termination) {
  switch (termination) {
    case Termination::kCompleted: return "completed";
    case Termination::kConverged: return "converged";
    case Termination::kMaxIterations: return "max_iterations";
    case Termination::kNoProgress: return "no_progress";
    case Termination::kFailure: return "failure";
  }
  return "unknown";
}

}  // namespace indoorloc
