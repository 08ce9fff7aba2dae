#include "periodic_bias_compensation/sim/motion.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/sim/random.h"

namespace periodic_bias_compensation::sim
{
namespace
{
constexpr double kTwoPi = 2.0 * M_PI;
constexpr std::int64_t kBlock = 512;  // samples per cached sea block

// Value and first two derivatives with respect to mu of a DOF's directional gain.
struct Gain
{
  double g0;
  double g1;
  double g2;
  bool cosine;  // the DOF follows cos(theta) (heave) instead of sin(theta)
};

std::array<Gain, 6> gains(const Sea& sea, double k, double mu)
{
  const double ratio = sea.length * k / kTwoPi;  // length / wavelength
  std::array<double, 6> r = sea.response;
  for (double& x : r)
  {
    x /= 1.0 + ratio * ratio;
  }
  const double c = std::cos(mu);
  const double s = std::sin(mu);
  const double c2 = std::cos(2.0 * mu);
  const double s2 = std::sin(2.0 * mu);
  return { { { r[kSurge] * c, -r[kSurge] * s, -r[kSurge] * c, false },
             { r[kSway] * s, r[kSway] * c, -r[kSway] * s, false },
             { r[kHeave], 0.0, 0.0, true },
             { r[kRoll] * k * s, r[kRoll] * k * c, -r[kRoll] * k * s, false },
             { -r[kPitch] * k * c, r[kPitch] * k * s, r[kPitch] * k * c, false },
             { r[kYaw] * k * 0.5 * s2, r[kYaw] * k * c2, -2.0 * r[kYaw] * k * s2, false } } };
}
}  // namespace

SlowMotion::SlowMotion(const Motion& motion)
{
  const double inf = std::numeric_limits<double>::infinity();
  const double speed0 = motion.type == MotionType::kStatic ? 0.0 : motion.speed;
  Segment current{ 0.0, inf, motion.position, motion.heading, speed0, 0.0, 0.0, Vector3::Zero() };
  if (motion.type != MotionType::kRoute || motion.route.legs.empty())
  {
    push(current);
    return;
  }
  double t = 0.0;
  auto add = [&](double duration, double turn_rate, double acceleration) {
    push({ t, t + duration, current.position, current.heading, current.speed, turn_rate, acceleration,
           Vector3::Zero() });
    const SlowState end = at(t + duration);
    current.position = end.position;
    current.heading = end.heading;
    current.speed += acceleration * duration;
    t += duration;
  };
  for (const RouteLeg& leg : motion.route.legs)
  {
    const double turn = wrapAngle(leg.heading - current.heading);
    if (turn != 0.0)
    {
      add(std::abs(turn) / motion.route.turn_rate, std::copysign(motion.route.turn_rate, turn), 0.0);
    }
    current.heading = wrapAngle(leg.heading);
    const double dv = leg.speed - current.speed;
    if (dv != 0.0)
    {
      add(std::abs(dv) / motion.route.acceleration, 0.0, std::copysign(motion.route.acceleration, dv));
    }
    current.speed = leg.speed;
    add(leg.duration, 0.0, 0.0);
  }
  segments_.back().end = inf;
}

void SlowMotion::push(Segment segment)
{
  segment.direction = Vector3(std::cos(segment.heading), std::sin(segment.heading), 0.0);
  segments_.push_back(segment);
}

std::size_t SlowMotion::segmentAt(double elapsed) const
{
  const auto it = std::upper_bound(segments_.begin(), segments_.end(), elapsed,
                                   [](double t, const Segment& s) { return t < s.start; });
  return it == segments_.begin() ? 0 : static_cast<std::size_t>(it - segments_.begin()) - 1;
}

double SlowMotion::segmentEnd(std::size_t segment) const
{
  return segments_[segment].end;
}

bool SlowMotion::segmentSteady(std::size_t segment) const
{
  return segments_[segment].turn_rate == 0.0 && segments_[segment].acceleration == 0.0;
}

SlowState SlowMotion::at(double elapsed) const
{
  const Segment& s = segments_[segmentAt(elapsed)];
  const double tau = elapsed - s.start;
  SlowState out;
  if (s.turn_rate != 0.0)
  {
    const double psi = s.heading + s.turn_rate * tau;
    const double v = s.speed;
    const double r = s.turn_rate;
    out.heading = wrapAngle(psi);
    out.yaw_rate = r;
    out.position =
        s.position + (v / r) * Vector3(std::sin(psi) - std::sin(s.heading), std::cos(s.heading) - std::cos(psi), 0.0);
    out.velocity = v * Vector3(std::cos(psi), std::sin(psi), 0.0);
    out.acceleration = v * r * Vector3(-std::sin(psi), std::cos(psi), 0.0);
    return out;
  }
  const Vector3& h = s.direction;
  out.heading = wrapAngle(s.heading);
  out.position = s.position + (s.speed * tau + 0.5 * s.acceleration * tau * tau) * h;
  out.velocity = (s.speed + s.acceleration * tau) * h;
  out.acceleration = s.acceleration * h;
  return out;
}

double jonswap(double omega, double hs, double tp, double gamma)
{
  if (omega <= 0.0)
  {
    return 0.0;
  }
  const double wp = kTwoPi / tp;
  const double sigma = omega <= wp ? 0.07 : 0.09;
  const double x = (omega - wp) / (sigma * wp);
  const double a_gamma = 1.0 - 0.287 * std::log(gamma);
  const double r = wp / omega;
  return a_gamma * 5.0 / 16.0 * hs * hs * std::pow(wp, 4) * std::pow(omega, -5) * std::exp(-1.25 * std::pow(r, 4)) *
         std::pow(gamma, std::exp(-0.5 * x * x));
}

std::vector<WaveComponent> drawWaveComponents(const Sea& sea, double gravity, std::uint64_t seed)
{
  Rng rng(seed);
  std::vector<WaveComponent> out;
  for (const WaveSystem& w : sea.systems)
  {
    const double gamma = w.spectrum == "pierson_moskowitz" ? 1.0 : w.gamma;
    const double wp = kTwoPi / w.peak_period;
    const double lo = 0.6 * wp;
    const double bin = (4.0 * wp - lo) / sea.components;
    for (int i = 0; i < sea.components; ++i)
    {
      WaveComponent c;
      c.omega = lo + (i + rng.uniform()) * bin;
      c.amplitude = std::sqrt(2.0 * jonswap(c.omega, w.significant_height, w.peak_period, gamma) * bin);
      c.wavenumber = c.omega * c.omega / gravity;
      c.direction = w.direction + w.spreading * rng.normal();
      c.phase = rng.uniform(0.0, kTwoPi);
      out.push_back(c);
    }
  }
  if (sea.response_coherence < 1.0)
  {
    // A stream of its own: the components are those of a coherent sea with the same seed.
    Rng lag_rng(deriveSeed(seed, "response_lag", 0));
    for (WaveComponent& c : out)
    {
      for (int j = 0; j < 6; ++j)
      {
        const double u = lag_rng.uniform(-M_PI, M_PI);
        c.lag[j] = j == kHeave ? 0.0 : (1.0 - sea.response_coherence) * u;
      }
    }
  }
  return out;
}

double encounterFrequency(double omega, double speed, double mu, double gravity)
{
  return omega - omega * omega * speed * std::cos(mu) / gravity;
}

ShipMotion::ShipMotion(const Scenario& scenario, std::uint64_t seed, Outputs outputs)
  : motion_(scenario.motion),
    dt_(1.0 / scenario.rate),
    gravity_(scenario.gravity),
    slow_(scenario.motion),
    outputs_(outputs)
{
  const bool has_sea = motion_.type == MotionType::kSea || motion_.type == MotionType::kRoute;
  if (has_sea)
  {
    components_ = drawWaveComponents(motion_.sea, gravity_, deriveSeed(seed, "sea", 0));
  }
}

ShipMotion::Dofs ShipMotion::sinusoidDofs(double elapsed) const
{
  Dofs d{};
  for (int j = 0; j < 6; ++j)
  {
    const Sinusoid& s = motion_.sinusoids[j];
    const double w = kTwoPi * s.frequency;
    const double a = w * elapsed + s.phase;
    const double sa = std::sin(a);
    d[3 * j] = s.amplitude * sa;
    d[3 * j + 1] = s.amplitude * w * std::cos(a);
    d[3 * j + 2] = -s.amplitude * w * w * sa;
  }
  return d;
}

ShipMotion::Dofs ShipMotion::seaDofsDirect(double elapsed, const SlowState& slow) const
{
  Dofs d{};
  const Vector3 rel = slow.position - motion_.position;
  const double mu_dot = -slow.yaw_rate;
  for (const WaveComponent& c : components_)
  {
    const Vector3 dir(std::cos(c.direction), std::sin(c.direction), 0.0);
    const double th = c.omega * elapsed - c.wavenumber * dir.dot(rel) + c.phase;
    const double th_dot = c.omega - c.wavenumber * dir.dot(slow.velocity);
    const double th_ddot = -c.wavenumber * dir.dot(slow.acceleration);
    const double s = std::sin(th);
    const double co = std::cos(th);
    const std::array<Gain, 6> g = gains(motion_.sea, c.wavenumber, c.direction - slow.heading);
    for (int j = 0; j < 6; ++j)
    {
      const double sj = c.lag[j] == 0.0 ? s : std::sin(th + c.lag[j]);
      const double cj = c.lag[j] == 0.0 ? co : std::cos(th + c.lag[j]);
      const double f0 = g[j].cosine ? cj : sj;
      const double f1 = g[j].cosine ? -sj : cj;
      const double f2 = -f0;
      d[3 * j] += c.amplitude * g[j].g0 * f0;
      d[3 * j + 1] += c.amplitude * (g[j].g1 * mu_dot * f0 + g[j].g0 * f1 * th_dot);
      d[3 * j + 2] += c.amplitude * (g[j].g2 * mu_dot * mu_dot * f0 + 2.0 * g[j].g1 * mu_dot * f1 * th_dot +
                                     g[j].g0 * (f2 * th_dot * th_dot + f1 * th_ddot));
    }
  }
  return d;
}

namespace
{
// The steady-segment synthesis runs over the components four at a time. Its lanes are written
// out (GCC's vector types), so every instruction set computes the same sums in the same order:
// the AVX clone, where the processor has it, gives the samples of the plain one bit for bit (it
// has no fused multiply-add to round differently).
using Lanes = double __attribute__((vector_size(32)));
constexpr int kLanes = 4;

// The functions below inline every one taking or giving a Lanes: no call passes one, whose ABI
// would differ with AVX.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
inline __attribute__((always_inline)) Lanes load(const double* p)
{
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline __attribute__((always_inline)) void store(double* p, Lanes v)
{
  std::memcpy(p, &v, sizeof v);
}

inline __attribute__((always_inline)) double sumOf(Lanes v)
{
  return (v[0] + v[1]) + (v[2] + v[3]);
}

/// What the synthesis of a block reads and writes.
struct SeaPass
{
  const double* coeff;   ///< per group: its rows' coefficients, four lanes each
  double* phasor;        ///< per group: sin, cos, step cos, step sin, four lanes each
  const int* slot;       ///< the Dof slot (3 dof + order) of each row
  std::int64_t groups;   ///< components / 4, rounded up
  std::int64_t samples;  ///< block length
  double* out;           ///< 18 x samples, column-major, zeroed
};

/// Rotates a group's phasors one sample on.
inline __attribute__((always_inline)) void rotate(double* ph, Lanes s, Lanes c)
{
  const Lanes step_c = load(ph + 2 * kLanes), step_s = load(ph + 3 * kLanes);
  store(ph, s * step_c + c * step_s);
  store(ph + kLanes, c * step_c - s * step_s);
}

/// Coherent responses: NS rows follow sin(theta) alone, then NC rows cos(theta) alone.
template <int NS, int NC>
inline __attribute__((always_inline)) void synthesiseSplit(const SeaPass& p)
{
  for (std::int64_t j = 0; j < p.samples; ++j)
  {
    Lanes acc[NS + NC] = {};
    for (std::int64_t g = 0; g < p.groups; ++g)
    {
      double* ph = p.phasor + 4 * kLanes * g;
      const double* co = p.coeff + (NS + NC) * kLanes * g;
      const Lanes s = load(ph), c = load(ph + kLanes);
#pragma GCC unroll 18
      for (int r = 0; r < NS; ++r)
      {
        acc[r] += load(co + kLanes * r) * s;
      }
#pragma GCC unroll 18
      for (int r = NS; r < NS + NC; ++r)
      {
        acc[r] += load(co + kLanes * r) * c;
      }
      rotate(ph, s, c);
    }
    for (int r = 0; r < NS + NC; ++r)
    {
      p.out[18 * j + p.slot[r]] = sumOf(acc[r]);
    }
  }
}

/// Response lags: each of the NR rows has a sin(theta) and a cos(theta) coefficient.
template <int NR>
inline __attribute__((always_inline)) void synthesisePaired(const SeaPass& p)
{
  for (std::int64_t j = 0; j < p.samples; ++j)
  {
    Lanes acc[NR] = {};
    for (std::int64_t g = 0; g < p.groups; ++g)
    {
      double* ph = p.phasor + 4 * kLanes * g;
      const double* co = p.coeff + 2 * NR * kLanes * g;
      const Lanes s = load(ph), c = load(ph + kLanes);
#pragma GCC unroll 18
      for (int r = 0; r < NR; ++r)
      {
        acc[r] += load(co + 2 * kLanes * r) * s + load(co + 2 * kLanes * r + kLanes) * c;
      }
      rotate(ph, s, c);
    }
    for (int r = 0; r < NR; ++r)
    {
      p.out[18 * j + p.slot[r]] = sumOf(acc[r]);
    }
  }
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define PBC_SEA_CLONES __attribute__((target_clones("avx", "default")))
#else
#define PBC_SEA_CLONES
#endif

// Rows the sensor needs (Outputs::kSensor): the translations' accelerations and the rotations'
// angles, rates and accelerations; with every output, all 18.
PBC_SEA_CLONES void synthesiseSensor(const SeaPass& p)
{
  synthesiseSplit<8, 4>(p);
}

PBC_SEA_CLONES void synthesiseAll(const SeaPass& p)
{
  synthesiseSplit<11, 7>(p);
}

PBC_SEA_CLONES void synthesiseSensorLagged(const SeaPass& p)
{
  synthesisePaired<12>(p);
}

PBC_SEA_CLONES void synthesiseAllLagged(const SeaPass& p)
{
  synthesisePaired<18>(p);
}
#pragma GCC diagnostic pop
}  // namespace

void ShipMotion::fillSeaBlock(std::int64_t k0)
{
  const double t0 = k0 * dt_;
  const std::size_t seg = slow_.segmentAt(t0);
  const double end = slow_.segmentEnd(seg);
  std::int64_t n = 1;
  while (n < kBlock && (k0 + n) * dt_ < end)
  {
    ++n;
  }
  block_.resize(18, n);
  block_start_ = k0;
  if (!slow_.segmentSteady(seg))
  {
    for (std::int64_t j = 0; j < n; ++j)
    {
      const double t = (k0 + j) * dt_;
      const Dofs d = seaDofsDirect(t, slow_.at(t));
      block_.col(j) = Eigen::Map<const Eigen::Matrix<double, 18, 1>>(d.data());
    }
    return;
  }
  // Constant velocity and heading: the phases advance linearly, so each component's phasor is
  // rotated by a fixed step and every Dof row is a weighted sum of the phasors' sines and cosines.
  const SlowState slow = slow_.at(t0);
  const Vector3 rel = slow.position - motion_.position;
  if (coeff_segment_ != seg)
  {
    buildSeaCoefficients(slow);
    coeff_segment_ = seg;
  }
  for (std::size_t i = 0; i < components_.size(); ++i)
  {
    const WaveComponent& c = components_[i];
    const Vector3 dir(std::cos(c.direction), std::sin(c.direction), 0.0);
    const double th = c.omega * t0 - c.wavenumber * dir.dot(rel) + c.phase;
    double* ph = phasor_.data() + 4 * kLanes * (i / kLanes) + i % kLanes;
    ph[0] = std::sin(th);
    ph[kLanes] = std::cos(th);
  }
  block_.setZero();
  const SeaPass pass{
    coeff_.data(), phasor_.data(), slot_.data(), static_cast<std::int64_t>(phasor_.size()) / (4 * kLanes), n,
    block_.data()
  };
  const bool sensor = outputs_ == Outputs::kSensor;
  if (lagged_)
  {
    sensor ? synthesiseSensorLagged(pass) : synthesiseAllLagged(pass);
  }
  else
  {
    sensor ? synthesiseSensor(pass) : synthesiseAll(pass);
  }
}

void ShipMotion::buildSeaCoefficients(const SlowState& slow)
{
  // Coherent responses: each Dof's rows follow sin(theta) or cos(theta) alone, sin rows first.
  // With response lags every row 3 j + n (Dof j, derivative n) has both parts: a g0 F_n(theta +
  // lag_j) with F_0 = sin or cos, F_1 = w_e F_0', F_2 = -w_e^2 F_0, and F(x) = A sin x + B cos x
  // at x = theta + lag is (A cos lag - B sin lag) sin theta + (A sin lag + B cos lag) cos theta.
  lagged_ = motion_.sea.response_coherence < 1.0;
  const bool sensor = outputs_ == Outputs::kSensor;
  // The rows made: with kSensor, a translation's acceleration only.
  const auto made = [sensor](int j, int n) { return !sensor || j >= kRoll || n == 2; };
  // Per row: its slot and whether it follows sin(theta) (coherent responses only).
  std::vector<int> sin_slots, cos_slots;
  for (int j = 0; j < 6; ++j)
  {
    for (int n = 0; n < 3; ++n)
    {
      if (made(j, n))
      {
        const bool follows_cos = (j == kHeave) != (n == 1);
        (lagged_ || !follows_cos ? sin_slots : cos_slots).push_back(3 * j + n);
      }
    }
  }
  slot_ = sin_slots;
  slot_.insert(slot_.end(), cos_slots.begin(), cos_slots.end());
  const int rows = static_cast<int>(slot_.size());
  const int width = lagged_ ? 2 * rows : rows;  // coefficients per component
  const std::size_t groups = (components_.size() + kLanes - 1) / kLanes;
  coeff_.assign(groups * width * kLanes, 0.0);
  phasor_.assign(groups * 4 * kLanes, 0.0);
  for (std::size_t i = 0; i < components_.size(); ++i)
  {
    const WaveComponent& c = components_[i];
    const Vector3 dir(std::cos(c.direction), std::sin(c.direction), 0.0);
    const double we = c.omega - c.wavenumber * dir.dot(slow.velocity);
    double* ph = phasor_.data() + 4 * kLanes * (i / kLanes) + i % kLanes;
    ph[2 * kLanes] = std::cos(we * dt_);
    ph[3 * kLanes] = std::sin(we * dt_);
    double* co = coeff_.data() + width * kLanes * (i / kLanes) + i % kLanes;
    const std::array<Gain, 6> g = gains(motion_.sea, c.wavenumber, c.direction - slow.heading);
    for (int r = 0; r < rows; ++r)
    {
      const int j = slot_[r] / 3, n = slot_[r] % 3;
      const double a = c.amplitude * g[j].g0;
      // F_n = A sin + B cos of theta itself, then shifted by the response lag.
      const double A0 = g[j].cosine ? 0.0 : 1.0, B0 = g[j].cosine ? 1.0 : 0.0;
      const double A[3] = { A0, -we * B0, -we * we * A0 };
      const double B[3] = { B0, we * A0, -we * we * B0 };
      const double cl = std::cos(c.lag[j]), sl = std::sin(c.lag[j]);
      const double on_sin = a * (A[n] * cl - B[n] * sl), on_cos = a * (A[n] * sl + B[n] * cl);
      if (lagged_)
      {
        co[kLanes * 2 * r] = on_sin;
        co[kLanes * (2 * r + 1)] = on_cos;
      }
      else
      {
        co[kLanes * r] = r < static_cast<int>(sin_slots.size()) ? on_sin : on_cos;
      }
    }
  }
}

Truth ShipMotion::evaluate(std::int64_t k)
{
  const double t = k * dt_;
  const SlowState slow = slow_.at(t);
  Dofs d{};
  if (motion_.type == MotionType::kSinusoids)
  {
    d = sinusoidDofs(t);
  }
  else if (!components_.empty())
  {
    if (block_start_ < 0 || k < block_start_ || k >= block_start_ + block_.cols())
    {
      fillSeaBlock(k);
    }
    Eigen::Map<Eigen::Matrix<double, 18, 1>>(d.data()) = block_.col(k - block_start_);
  }

  Truth out;
  const double r = slow.yaw_rate;
  // The heading's rotation about z, with one sine and cosine for the three vectors it turns.
  double ch, sh;
  sinCos(slow.heading, &sh, &ch);
  const auto rz = [ch, sh](const Vector3& x) {
    return Vector3(ch * x.x() - sh * x.y(), sh * x.x() + ch * x.y(), x.z());
  };
  const auto perp = [](const Vector3& x) { return Vector3(-x.y(), x.x(), 0.0); };
  const Vector3 q(d[0], d[3], d[6]);
  const Vector3 dq(d[1], d[4], d[7]);
  const Vector3 ddq(d[2], d[5], d[8]);
  out.slow_position = slow.position;
  out.slow_velocity = slow.velocity;
  out.slow_acceleration = slow.acceleration;
  out.slow_heading = slow.heading;
  out.slow_yaw_rate = r;
  out.wave_position = rz(q);
  out.wave_velocity = rz(dq + r * perp(q));
  out.wave_acceleration = rz(ddq + 2.0 * r * perp(dq) + r * r * perp(perp(q)));
  out.position = out.slow_position + out.wave_position;
  out.velocity = out.slow_velocity + out.wave_velocity;
  out.acceleration = out.slow_acceleration + out.wave_acceleration;

  const double phi = motion_.roll + d[9], phi_d = d[10], phi_dd = d[11];
  const double th = motion_.pitch + d[12], th_d = d[13], th_dd = d[14];
  const double psi = slow.heading + d[15], psi_d = r + d[16], psi_dd = d[17];
  // Rz(psi) Ry(th) Rx(phi) from the half angles' sines and cosines; the whole angles' follow from them.
  double cx, sx, cy, sy, cz, sz;
  sinCos(0.5 * phi, &sx, &cx);
  sinCos(0.5 * th, &sy, &cy);
  sinCos(0.5 * psi, &sz, &cz);
  out.attitude = Quaternion(cz * cy * cx + sz * sy * sx, cz * cy * sx - sz * sy * cx, cz * sy * cx + sz * cy * sx,
                            sz * cy * cx - cz * sy * sx);
  const double sp = 2.0 * sx * cx, cp = cx * cx - sx * sx, st = 2.0 * sy * cy, ct = cy * cy - sy * sy;
  out.angular_rate = Vector3(phi_d - psi_d * st, th_d * cp + psi_d * ct * sp, -th_d * sp + psi_d * ct * cp);
  out.angular_acceleration =
      Vector3(phi_dd - psi_dd * st - psi_d * ct * th_d,
              th_dd * cp - th_d * sp * phi_d + psi_dd * ct * sp - psi_d * st * th_d * sp + psi_d * ct * cp * phi_d,
              -th_dd * sp - th_d * cp * phi_d + psi_dd * ct * cp - psi_d * st * th_d * cp - psi_d * ct * sp * phi_d);
  return out;
}
}  // namespace periodic_bias_compensation::sim
