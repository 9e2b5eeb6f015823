// Cooperative interruption of long C++ loops (Ctrl-C from Python).
//
// Long work (Monte Carlo runs, parallel batches, step loops) calls CheckInterrupt() between runs
// or steps. The host installs a poll function with SetInterruptHook: the Python module installs
// one that runs PyErr_CheckSignals, so Ctrl-C reaches Python while C++ works with the GIL
// released. The hook is only ever called on the thread that installed it (Python's main
// thread); other threads see the stop flag that a poll on that thread sets. Without a hook
// (plain C++ use) CheckInterrupt costs two relaxed atomic loads.
#pragma once

#include <stdexcept>

namespace indoorloc {

/// Thrown by CheckInterrupt when the host asked to stop (Python: KeyboardInterrupt).
class Interrupted : public std::runtime_error {
 public:
  Interrupted() : std::runtime_error("indoorloc: interrupted") {}
};

/// Installs the host's poll function (returns true when the work should stop), or nullptr.
/// It is called only on the installing thread, by CheckInterrupt at most every 20 ms.
void SetInterruptHook(bool (*poll)());

/// Throws Interrupted if a stop is pending (polling the hook when on its thread).
void CheckInterrupt();

/// Polls the hook now (on its thread) and returns whether a stop is pending; does not throw.
/// For a thread that waits for workers.
bool PollInterrupt();

/// Clears a pending stop (once the Interrupted exception has been reported).
void ClearInterrupt();

}  // namespace indoorloc
