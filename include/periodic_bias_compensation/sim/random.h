// Deterministic random numbers: the same seed gives bit-identical streams on every run.
#pragma once

#include <cstdint>
#include <random>
#include <string>

namespace periodic_bias_compensation::sim
{
/// std::mt19937_64 with its own uniform and normal transforms (the standard library's
/// distributions are implementation-defined, these are not).
class Rng
{
public:
  /// @param seed stream seed [-]
  explicit Rng(std::uint64_t seed);

  /// The engine's next 64 random bits.
  std::uint64_t bits();

  /// Uniform double in [0, 1) with 53 random bits.
  double uniform();

  /// Uniform double in [lo, hi).
  /// @param lo lower bound
  /// @param hi upper bound
  double uniform(double lo, double hi);

  /// Standard normal N(0, 1) by the Box-Muller transform.
  double normal();

private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

/// Standard normal draws N(0, 1) by the ziggurat method (Marsaglia and Tsang; Doornik's
/// double-precision form): one 64-bit draw and no log, sine or cosine for most of them, unlike
/// Rng::normal(). For the per-sample noise of the sensor effects.
class NormalStream
{
public:
  /// @param seed stream seed [-]
  explicit NormalStream(std::uint64_t seed);

  /// The next standard normal draw.
  double next();

private:
  Rng rng_;
};

/// SplitMix64 finaliser: a well-mixed 64-bit function of x.
std::uint64_t mix64(std::uint64_t x);

/// Seed of an independent stream derived from a base seed, a name and an index, so that
/// switching one effect on or off does not change the random numbers of the others.
/// @param seed base seed [-]
/// @param name stream name (e.g. the effect name)
/// @param index occurrence of that name [-]
std::uint64_t deriveSeed(std::uint64_t seed, const std::string& name, std::uint64_t index);
}  // namespace periodic_bias_compensation::sim
