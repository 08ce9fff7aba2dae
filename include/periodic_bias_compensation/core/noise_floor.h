// White-noise level of a sampled signal that spectral lines do not inflate (estimation core, no
// ROS).
//
// The mean square of first differences, `E[(a_k - a_k-1)^2] = 2 sigma^2`, reads every line above
// the wave band as noise: an engine's lines of 0.1 and 0.08 m/s^2 at 24.5 and 39 Hz read as 26
// times the white noise of a 2e-3 m/s^2/sqrt(Hz) accelerometer at 100 Hz. The spectral heave
// design subtracts that level from the wave band, where the vibration is not (the design's
// low-pass removes it), and then passes too little of a swell. NoiseFloor therefore takes blocks
// of kBlock samples, their Hann-windowed periodogram, and the median over the upper half of the
// band (a quarter to half the sample rate: no wave acceleration worth the name, and a few lines
// occupy a few of the kBlock / 4 bins taken). For white noise the periodogram's bins are
// exponentially distributed, their median ln 2 times their mean, the mean sigma^2 times the
// window's sum of squares.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <memory>
#include <vector>

#include "periodic_bias_compensation/core/unshared_transform.h"

namespace periodic_bias_compensation
{
class NoiseFloor
{
public:
  static constexpr int kBlock = 512;  ///< samples per periodogram

  NoiseFloor();
  /// Forgets the block being filled and the last estimate.
  void reset();
  /// Takes one sample (a non-finite one is skipped); returns true when it completed a block, whose
  /// estimate blockVariance() then holds.
  bool add(double value);
  /// Per-sample variance of the white noise in the last completed block [unit^2] (0 before one).
  double blockVariance() const
  {
    return variance_;
  }

private:
  std::vector<double> block_;
  int filled_ = 0;
  double variance_ = 0.0;
  double window_power_ = 0.0;  ///< sum of squares of window_, set with it (declared first)
  std::vector<double> window_;
  std::vector<double> bins_;
  /// The transform, made at the first block.
  UnsharedTransform transform_;
};

}  // namespace periodic_bias_compensation
