// A transform made on first use that copies of its owner do not share (estimation core, no ROS).
//
// RealFft's buffers are scratch space: two copies of an estimator writing into one would race.
// A copy of an UnsharedTransform starts empty, and the copy's owner makes its own on first use.
#pragma once

#include <memory>

namespace periodic_bias_compensation
{
class RealFft;

struct UnsharedTransform
{
  UnsharedTransform() = default;
  UnsharedTransform(const UnsharedTransform&)
  {
  }
  UnsharedTransform& operator=(const UnsharedTransform&)
  {
    return *this;
  }
  std::shared_ptr<RealFft> fft;
};

}  // namespace periodic_bias_compensation
