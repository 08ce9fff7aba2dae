#include "periodic_bias_compensation/core/noise_floor.h"

#include <algorithm>
#include <cmath>

#include "real_fft.h"

namespace periodic_bias_compensation
{
NoiseFloor::NoiseFloor() : block_(kBlock, 0.0), window_(hannWindow(kBlock, &window_power_)), bins_(kBlock / 4)
{
}

void NoiseFloor::reset()
{
  filled_ = 0;
  variance_ = 0.0;
}

bool NoiseFloor::add(double value)
{
  if (!std::isfinite(value))
    return false;
  block_[filled_++] = value;
  if (filled_ < kBlock)
    return false;
  filled_ = 0;
  if (!transform_.fft)
    transform_.fft = std::make_shared<RealFft>(kBlock);
  RealFft& fft = *transform_.fft;
  double mean = 0.0;
  for (double v : block_)
    mean += v;
  mean /= kBlock;
  for (int i = 0; i < kBlock; ++i)
    fft.in[i] = window_[i] * (block_[i] - mean);
  fft.execute();
  // Bins kBlock / 4 .. kBlock / 2 - 1: a quarter to half the sample rate, Nyquist left out.
  for (int k = 0; k < kBlock / 4; ++k)
    bins_[k] = fft.power(kBlock / 4 + k);
  const auto middle = bins_.begin() + bins_.size() / 2;
  std::nth_element(bins_.begin(), middle, bins_.end());
  variance_ = *middle / (std::log(2.0) * window_power_);
  return true;
}

}  // namespace periodic_bias_compensation
