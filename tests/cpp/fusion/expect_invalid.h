// Test helper of the fusion tests: an expected std::invalid_argument whose message names things.
#pragma once

#include <initializer_list>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace indoorloc::fusion {

/// Expects `fn` to throw std::invalid_argument whose message contains every string of `parts`.
template <typename Fn>
void ExpectInvalid(Fn fn, std::initializer_list<std::string> parts) {
  try {
    fn();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    for (const std::string& p : parts) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks " << p;
    }
  }
}

}  // namespace indoorloc::fusion
