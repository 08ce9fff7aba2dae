#include "periodic_bias_compensation/sim/motion.h"

#include <algorithm>
#include <cmath>
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
  Segment current{ 0.0, inf, motion.position, motion.heading, speed0, 0.0, 0.0 };
  if (motion.type != MotionType::kRoute || motion.route.legs.empty())
  {
    segments_.push_back(current);
    return;
  }
  double t = 0.0;
  auto add = [&](double duration, double turn_rate, double acceleration) {
    const Segment s{ t, t + duration, current.position, current.heading, current.speed, turn_rate, acceleration };
    segments_.push_back(s);
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
  const Vector3 h(std::cos(s.heading), std::sin(s.heading), 0.0);
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

ShipMotion::ShipMotion(const Scenario& scenario, std::uint64_t seed)
  : motion_(scenario.motion), dt_(1.0 / scenario.rate), gravity_(scenario.gravity), slow_(scenario.motion)
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
  // Constant velocity and heading: the phases advance linearly, so rotate phasors and get
  // all DOFs with two matrix products (rows that follow sin(theta) and rows that follow cos).
  const SlowState slow = slow_.at(t0);
  const Vector3 rel = slow.position - motion_.position;
  const Eigen::Index m = static_cast<Eigen::Index>(components_.size());
  if (coeff_segment_ != seg)
  {
    buildSeaCoefficients(slow);
    coeff_segment_ = seg;
  }
  sin_.resize(m, n);
  cos_.resize(m, n);
  for (Eigen::Index i = 0; i < m; ++i)
  {
    const WaveComponent& c = components_[i];
    const Vector3 dir(std::cos(c.direction), std::sin(c.direction), 0.0);
    const double th = c.omega * t0 - c.wavenumber * dir.dot(rel) + c.phase;
    sin_(i, 0) = std::sin(th);
    cos_(i, 0) = std::cos(th);
  }
  for (Eigen::Index j = 1; j < n; ++j)
  {
    sin_.col(j).array() = sin_.col(j - 1).array() * step_cos_ + cos_.col(j - 1).array() * step_sin_;
    cos_.col(j).array() = cos_.col(j - 1).array() * step_cos_ - sin_.col(j - 1).array() * step_sin_;
  }
  if (lagged_)
  {
    block_.noalias() = sin_coeff_ * sin_;
    block_.noalias() += cos_coeff_ * cos_;
    return;
  }
  sin_rows_.noalias() = sin_coeff_ * sin_;
  cos_rows_.noalias() = cos_coeff_ * cos_;
  int rs = 0;
  int rc = 0;
  for (int j = 0; j < 6; ++j)
  {
    const bool cosine = j == kHeave;
    block_.row(3 * j) = cosine ? cos_rows_.row(rc++) : sin_rows_.row(rs++);
    block_.row(3 * j + 1) = cosine ? sin_rows_.row(rs++) : cos_rows_.row(rc++);
    block_.row(3 * j + 2) = cosine ? cos_rows_.row(rc++) : sin_rows_.row(rs++);
  }
}

void ShipMotion::buildSeaCoefficients(const SlowState& slow)
{
  // Coherent responses: each Dof's rows follow sin(theta) or cos(theta) alone (11 and 7 rows).
  // With response lags every row 3 j + n (Dof j, derivative n) has both parts: a g0 F_n(theta +
  // lag_j) with F_0 = sin or cos, F_1 = w_e F_0', F_2 = -w_e^2 F_0, and F(x) = A sin x + B cos x
  // at x = theta + lag is (A cos lag - B sin lag) sin theta + (A sin lag + B cos lag) cos theta.
  const Eigen::Index m = static_cast<Eigen::Index>(components_.size());
  lagged_ = motion_.sea.response_coherence < 1.0;
  sin_coeff_ = Eigen::MatrixXd::Zero(lagged_ ? 18 : 11, m);
  cos_coeff_ = Eigen::MatrixXd::Zero(lagged_ ? 18 : 7, m);
  step_cos_.resize(m);
  step_sin_.resize(m);
  for (Eigen::Index i = 0; i < m; ++i)
  {
    const WaveComponent& c = components_[i];
    const Vector3 dir(std::cos(c.direction), std::sin(c.direction), 0.0);
    const double we = c.omega - c.wavenumber * dir.dot(slow.velocity);
    step_cos_[i] = std::cos(we * dt_);
    step_sin_[i] = std::sin(we * dt_);
    const std::array<Gain, 6> g = gains(motion_.sea, c.wavenumber, c.direction - slow.heading);
    int rs = 0;
    int rc = 0;
    for (int j = 0; j < 6; ++j)
    {
      const double a = c.amplitude * g[j].g0;
      if (lagged_)
      {
        const double cl = std::cos(c.lag[j]), sl = std::sin(c.lag[j]);
        const double A0 = g[j].cosine ? 0.0 : 1.0, B0 = g[j].cosine ? 1.0 : 0.0;
        const double A[3] = { A0, -we * B0, -we * we * A0 };
        const double B[3] = { B0, we * A0, -we * we * B0 };
        for (int n = 0; n < 3; ++n)
        {
          sin_coeff_(3 * j + n, i) = a * (A[n] * cl - B[n] * sl);
          cos_coeff_(3 * j + n, i) = a * (A[n] * sl + B[n] * cl);
        }
      }
      else if (g[j].cosine)
      {
        cos_coeff_(rc++, i) = a;
        sin_coeff_(rs++, i) = -a * we;
        cos_coeff_(rc++, i) = -a * we * we;
      }
      else
      {
        sin_coeff_(rs++, i) = a;
        cos_coeff_(rc++, i) = a * we;
        sin_coeff_(rs++, i) = -a * we * we;
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
  const double ch = std::cos(slow.heading), sh = std::sin(slow.heading);
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
  const double cx = std::cos(0.5 * phi), sx = std::sin(0.5 * phi);
  const double cy = std::cos(0.5 * th), sy = std::sin(0.5 * th);
  const double cz = std::cos(0.5 * psi), sz = std::sin(0.5 * psi);
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
