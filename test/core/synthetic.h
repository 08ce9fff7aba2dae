// Test inputs made in the test itself: a level sensor shaken sinusoidally with bias and noise.
// (Scenario-level data comes from the simulator; these are the minimal signals a unit test needs.)
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include "../common/random_vector.h"
#include "periodic_bias_compensation/core/compensator.h"

namespace periodic_bias_compensation
{
namespace test
{
struct Shake
{
  double rate = 87.7;                        ///< [Hz]
  double duration = 60.0;                    ///< [s]
  Vector3 amplitude{ 0.05, 0.0, 0.0 };       ///< displacement amplitude per axis [m]
  Vector3 frequency{ 0.443, 0.476, 0.443 };  ///< [Hz]
  Vector3 phase{ 0.3, 1.1, 2.0 };            ///< [rad]
  Vector3 bias{ 0.02, -0.01, 0.015 };        ///< constant accelerometer bias [m/s^2]
  double noise_density = 0.003;              ///< white accelerometer noise [m/s^2/sqrt(Hz)]
  double chirp = 0.0;                        ///< linear frequency drift [Hz/s]
  unsigned seed = 1;
  bool with_orientation = true;
};

struct ShakeRecord
{
  std::vector<ImuSample> samples;
  std::vector<Vector3> position;  ///< true (wave) displacement; the slow motion is zero
};

inline ShakeRecord makeShake(const Shake& shake)
{
  ShakeRecord record;
  std::mt19937_64 rng(shake.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double sigma = shake.noise_density * std::sqrt(shake.rate / 2.0);
  const int n = static_cast<int>(shake.duration * shake.rate);
  for (int k = 0; k < n; ++k)
  {
    const double t = k / shake.rate;
    ImuSample s;
    s.t = 1000.0 + t;
    Vector3 position, acceleration;
    for (int i = 0; i < 3; ++i)
    {
      // Phase of a linear chirp: 2 pi (f t + c t^2 / 2); acceleration from its exact derivatives.
      const double f = shake.frequency[i] + shake.chirp * t;
      const double phi = 2.0 * M_PI * (shake.frequency[i] * t + 0.5 * shake.chirp * t * t) + shake.phase[i];
      const double w = 2.0 * M_PI * f, dw = 2.0 * M_PI * shake.chirp;
      position[i] = shake.amplitude[i] * std::sin(phi);
      acceleration[i] = shake.amplitude[i] * (-w * w * std::sin(phi) + dw * std::cos(phi));
    }
    s.specific_force = acceleration + Vector3(0, 0, kStandardGravity) + shake.bias +
                       sigma * test::drawVector([&] { return normal(rng); });
    s.has_orientation = shake.with_orientation;
    record.samples.push_back(s);
    record.position.push_back(position);
  }
  return record;
}
}  // namespace test
}  // namespace periodic_bias_compensation
