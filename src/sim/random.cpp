#include "periodic_bias_compensation/sim/random.h"

#include <cmath>

namespace periodic_bias_compensation::sim
{
Rng::Rng(std::uint64_t seed) : engine_(seed)
{
}

double Rng::uniform()
{
  return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
}

double Rng::uniform(double lo, double hi)
{
  return lo + (hi - lo) * uniform();
}

double Rng::normal()
{
  if (has_spare_)
  {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  const double a = 2.0 * M_PI * u2;
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return r * std::cos(a);
}

std::uint64_t mix64(std::uint64_t x)
{
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::uint64_t deriveSeed(std::uint64_t seed, const std::string& name, std::uint64_t index)
{
  std::uint64_t h = 0xcbf29ce484222325ULL;  // FNV-1a
  for (const char c : name)
  {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return mix64(mix64(seed) ^ mix64(h + index));
}
}  // namespace periodic_bias_compensation::sim
