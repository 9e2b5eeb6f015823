// Test helper shared by the C++ test suites: the message of the std::invalid_argument a call
// throws (the argument checks of indoorloc/core/check.h), to compare with the promised wording.
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

namespace indoorloc {

/// What fn() throws as std::invalid_argument, or "<no exception>".
inline std::string MessageOf(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no exception>";
}

}  // namespace indoorloc
