#include "indoorloc/core/interrupt.h"

#include <atomic>
#include <chrono>
#include <thread>

namespace indoorloc {
namespace {

std::atomic<bool (*)()> g_hook{nullptr};
std::atomic<bool> g_stop{false};
std::thread::id g_hook_thread;  // written before g_hook is published

bool PollNow() {
  bool (*hook)() = g_hook.load(std::memory_order_acquire);
  if (hook != nullptr && std::this_thread::get_id() == g_hook_thread && hook()) {
    g_stop.store(true, std::memory_order_relaxed);
  }
  return g_stop.load(std::memory_order_relaxed);
}

}  // namespace

void SetInterruptHook(bool (*poll)()) {
  g_hook.store(nullptr, std::memory_order_release);
  g_hook_thread = std::this_thread::get_id();
  g_hook.store(poll, std::memory_order_release);
}

void CheckInterrupt() {
  // The hook (taking the GIL) costs far more than a loop step: poll at most every 20 ms.
  bool stop = g_stop.load(std::memory_order_relaxed);
  if (!stop && g_hook.load(std::memory_order_relaxed) != nullptr && std::this_thread::get_id() == g_hook_thread) {
    thread_local std::chrono::steady_clock::time_point last;
    const auto now = std::chrono::steady_clock::now();
    if (now - last >= std::chrono::milliseconds(20)) {
      last = now;
      stop = PollNow();
    }
  }
  if (stop) throw Interrupted();
}

bool PollInterrupt() { return PollNow(); }

void ClearInterrupt() { g_stop.store(false, std::memory_order_relaxed); }

}  // namespace indoorloc
