// Test helper of the network solvers' tests: two solves of the same network (checkpointed and
// not, or two factorisations) must give the same gravity estimate and sigma, to the bit.
#pragma once

#include <gtest/gtest.h>

namespace indoorloc::network::testing {

/// EXPECT_EQ on gravity_estimate and gravity_sigma of two results (any result types with both).
template <typename ResultA, typename ResultB>
void ExpectSameGravity(const ResultA& a, const ResultB& b) {
  EXPECT_EQ(a.gravity_estimate, b.gravity_estimate);
  EXPECT_EQ(a.gravity_sigma, b.gravity_sigma);
}

}  // namespace indoorloc::network::testing
