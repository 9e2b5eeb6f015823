// Stride counting from stance flags of a foot-mounted IMU, robust to slow walks and runs.
//
// A stride of the instrumented foot is one swing followed by a stance: the strides are the
// stance onsets after a swing (the rest at the very start is not a stride). Stance detectors
// flicker, and the flicker depends on the gait, so the cleaning uses the recording's own rhythm:
//  1. stance runs shorter than min_stance_s inside a swing are swing (a pause of the detector
//     in mid-swing);
//  2. swing runs shorter than max(min_swing_s, min_swing_fraction x the median swing) inside a
//     stance are stance (a shuffle of the resting foot). The median swing is taken over the
//     swings that pass the absolute floor min_swing_s, so a very slow walk, whose swings are
//     above the detector's threshold for only 0.1-0.2 s, keeps them (a fixed 0.3 s floor merged
//     two stances into one and lost the stride in between);
//  3. a swing longer than long_swing_factor x the median swing holds missed stances (running:
//     the foot never comes fully to rest): it counts as round(length / median) strides, the
//     extra onsets placed evenly inside it.
// How each default was chosen is written beside it (leave-one-trial-out over the PyShoe trials).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/pdr/zero_velocity.h"

namespace indoorloc::pdr {

struct StrideCountOptions {
  double min_stance_s = 0.02;        ///< shorter stance runs inside a swing are flicker [s]
  double min_swing_s = 0.1;          ///< absolute floor: shorter swing runs are always flicker [s]
  double min_swing_fraction = 0.5;   ///< rhythm: swings shorter than this x the median swing are flicker
  double long_swing_factor = 1.7;    ///< swings longer than this x the median are split; 0 disables
  bool IsValid(std::string* error) const;
};

struct StrideCountSummary {
  int n_strides = 0;
  int n_flicker_stances = 0;   ///< stance runs merged into swings (step 1)
  int n_flicker_swings = 0;    ///< swing runs merged into stances (step 2)
  int n_split_strides = 0;     ///< strides added by splitting long swings (step 3)
  double median_swing_s = 0.0; ///< the rhythm used by steps 2 and 3 [s]
  double median_stance_s = 0.0;  ///< median stance duration after cleaning [s]
  std::string BriefReport() const;
};

struct StrideCountOutput {
  std::vector<int> stride_indices;  ///< sample index of each stride's stance onset (increasing)
  BoolVector cleaned_stance;        ///< the stance after steps 1-2 (N)
  StrideCountSummary summary;
};

/// Counts strides in stance flags (N) sampled at rate_hz [Hz].
StrideCountOutput CountStrides(const BoolVector& stance, double rate_hz, const StrideCountOptions& options = StrideCountOptions());

}  // namespace indoorloc::pdr
