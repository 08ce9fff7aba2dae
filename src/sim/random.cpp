#include "periodic_bias_compensation/sim/random.h"

#include <array>
#include <cmath>

namespace periodic_bias_compensation::sim
{
namespace
{
/// The uniform in [0, 1) of 64 random bits: their top 53.
double unitOf(std::uint64_t bits)
{
  return static_cast<double>(bits >> 11) * 0x1.0p-53;
}
}  // namespace

Rng::Rng(std::uint64_t seed) : engine_(seed)
{
}

std::uint64_t Rng::bits()
{
  return engine_();
}

double Rng::uniform()
{
  return unitOf(bits());
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

namespace
{
/// The ziggurat of N(0, 1) in 128 strips of equal area (Marsaglia and Tsang 2000, in Doornik's
/// double-precision form, 2005): the strips' right edges and the ratio of each next edge to it.
struct Ziggurat
{
  static constexpr int kStrips = 128;
  static constexpr double kTail = 3.442619855899;       // right edge of the first strip
  static constexpr double kArea = 9.91256303526217e-3;  // of each strip
  std::array<double, kStrips + 1> edge;
  std::array<double, kStrips> ratio;

  Ziggurat()
  {
    const auto f = [](double x) { return std::exp(-0.5 * x * x); };
    edge[0] = kArea / f(kTail);  // the base strip, its tail folded into a rectangle of that width
    edge[1] = kTail;
    for (int i = 2; i < kStrips; ++i)
    {
      edge[i] = std::sqrt(-2.0 * std::log(kArea / edge[i - 1] + f(edge[i - 1])));
    }
    edge[kStrips] = 0.0;
    for (int i = 0; i < kStrips; ++i)
    {
      ratio[i] = edge[i + 1] / edge[i];
    }
  }
};

const Ziggurat kZiggurat;
}  // namespace

NormalStream::NormalStream(std::uint64_t seed) : rng_(seed)
{
}

double NormalStream::next()
{
  const Ziggurat& z = kZiggurat;
  for (;;)
  {
    // One draw gives the abscissa's 53 bits (u in [-1, 1)) and, from its low bits, the strip.
    const std::uint64_t bits = rng_.bits();
    const double u = 2.0 * unitOf(bits) - 1.0;
    const int i = static_cast<int>(bits & (Ziggurat::kStrips - 1));
    if (std::abs(u) < z.ratio[i])
    {
      return u * z.edge[i];  // inside the strip's rectangle under the next strip: most draws
    }
    if (i == 0)
    {
      // The tail beyond kTail, by Marsaglia's exponential rejection.
      double x, y;
      do
      {
        x = std::log(1.0 - rng_.uniform()) / Ziggurat::kTail;
        y = std::log(1.0 - rng_.uniform());
      } while (-2.0 * y < x * x);
      return u < 0.0 ? x - Ziggurat::kTail : Ziggurat::kTail - x;
    }
    const double x = u * z.edge[i];
    const double f0 = std::exp(-0.5 * (z.edge[i] * z.edge[i] - x * x));
    const double f1 = std::exp(-0.5 * (z.edge[i + 1] * z.edge[i + 1] - x * x));
    if (f1 + rng_.uniform() * (f0 - f1) < 1.0)
    {
      return x;  // under the density in the strip's wedge
    }
  }
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
