// GyroAttitude: roll and pitch from the gyro with its bias estimated, and the compensator's use
// of it for samples without orientation.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "../common/random_vector.h"
#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/gyro_attitude.h"

namespace pbc = periodic_bias_compensation;
using pbc::Quaternion;
using pbc::Vector3;

namespace
{
/// Angle between the estimated and the true "up" in the sensor frame: the tilt error [rad].
double tiltError(const Quaternion& estimate, const Quaternion& truth)
{
  const Vector3 up_estimate = estimate.conjugate() * Vector3::UnitZ();
  const Vector3 up_truth = truth.conjugate() * Vector3::UnitZ();
  return std::acos(std::clamp(up_estimate.dot(up_truth), -1.0, 1.0));
}

/// A hull rolling and pitching about a tilted mean, with wave accelerations on the level axes.
struct RollingHull
{
  double roll_amplitude = 0.1;     // [rad]
  double pitch_amplitude = 0.05;   // [rad]
  double period = 8.0;             // [s]
  double wave_acceleration = 0.5;  // [m/s^2] horizontal, at the wave period
  Vector3 gyro_bias{ 0, 0, 0 };    // [rad/s]

  double w() const
  {
    return 2.0 * M_PI / period;
  }
  double roll(double t) const
  {
    return 0.02 + roll_amplitude * std::sin(w() * t);
  }
  double pitch(double t) const
  {
    return -0.01 + pitch_amplitude * std::sin(w() * t + 1.0);
  }
  Quaternion attitude(double t) const
  {
    return Quaternion(Eigen::AngleAxisd(0.3, Vector3::UnitZ()) * Eigen::AngleAxisd(pitch(t), Vector3::UnitY()) *
                      Eigen::AngleAxisd(roll(t), Vector3::UnitX()));
  }
  /// Body rate of R = Rz(psi) Ry(theta) Rx(phi): omega = [phi' - sin(theta) psi', ...] with psi' = 0.
  Vector3 rate(double t) const
  {
    const double roll_rate = roll_amplitude * w() * std::cos(w() * t);
    const double pitch_rate = pitch_amplitude * w() * std::cos(w() * t + 1.0);
    const double phi = roll(t);
    return Vector3(roll_rate, std::cos(phi) * pitch_rate, -std::sin(phi) * pitch_rate);
  }
  Vector3 levelAcceleration(double t) const
  {
    return Vector3(wave_acceleration * std::sin(w() * t + 0.4), 0.6 * wave_acceleration * std::cos(w() * t), 0.0);
  }
  pbc::ImuSample sample(double t) const
  {
    pbc::ImuSample s;
    s.t = t;
    s.specific_force = attitude(t).conjugate() * (levelAcceleration(t) + Vector3(0, 0, pbc::kStandardGravity));
    s.angular_rate = rate(t) + gyro_bias;
    s.has_orientation = false;
    return s;
  }
};

constexpr double kRate = 100.0;

/// Largest tilt error over the last `tail` seconds of a `duration` run.
double runTiltError(const RollingHull& hull, const pbc::GyroAttitudeConfig& config, double duration, double tail,
                    Vector3* bias = nullptr)
{
  pbc::GyroAttitude attitude(config);
  double worst = 0.0;
  for (int k = 0; k <= static_cast<int>(duration * kRate); ++k)
  {
    const double t = k / kRate;
    const pbc::ImuSample s = hull.sample(t);
    attitude.update(s.angular_rate, s.specific_force, k == 0 ? 0.0 : 1.0 / kRate);
    if (t > duration - tail)
      worst = std::max(worst, tiltError(attitude.attitude(), hull.attitude(t)));
  }
  if (bias)
    *bias = attitude.gyroBias();
  return worst;
}
}  // namespace

TEST(GyroAttitude, LevelFromSpecificForceIsTheShortestRotationOntoUp)
{
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vector3> forces;
  for (int i = 0; i < 1000; ++i)
    forces.push_back(pbc::test::drawVector([&] { return normal(rng); }));
  // Along the axes, and close to straight down yet outside the opposite-vector case.
  forces.insert(forces.end(), { Vector3::UnitZ(), Vector3::UnitX(), -Vector3::UnitY(), Vector3(1e-5, -2e-5, -1.0) });
  for (const Vector3& force : forces)
  {
    SCOPED_TRACE(::testing::Message() << force.transpose());
    const Quaternion q = pbc::levelFromSpecificForce(9.8 * force);
    const Vector3 up = force.normalized();
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
    EXPECT_LT((q * up - Vector3::UnitZ()).norm(), 1e-9);
    EXPECT_EQ(q.z(), 0.0);  // a horizontal axis: no yaw
    EXPECT_NEAR(2.0 * std::acos(std::clamp(q.w(), -1.0, 1.0)), std::acos(up.z()), 1e-6);
  }
  // Straight down, and down within rounding: half a turn about x, or about the horizontal axis
  // normal to the force.
  const Quaternion down = pbc::levelFromSpecificForce(-Vector3::UnitZ());
  EXPECT_EQ(down.coeffs(), Quaternion(0.0, 1.0, 0.0, 0.0).coeffs());
  const Quaternion nearly_down = pbc::levelFromSpecificForce(Vector3(1e-13, 2e-13, -1.0));
  EXPECT_LT((nearly_down.coeffs() - Quaternion(0.0, 2.0 / std::sqrt(5.0), -1.0 / std::sqrt(5.0), 0.0).coeffs()).norm(),
            1e-12);
  EXPECT_LT((nearly_down * Vector3(1e-13, 2e-13, -1.0) - Vector3::UnitZ()).norm(), 1e-9);
  EXPECT_EQ(pbc::levelFromSpecificForce(Vector3::Zero()).coeffs(), Quaternion::Identity().coeffs());
  EXPECT_TRUE(pbc::levelFromSpecificForce(Vector3(NAN, 0.0, 9.8)).coeffs().hasNaN());
}

TEST(GyroAttitude, FollowsARollingHullThroughWaveAccelerations)
{
  RollingHull hull;
  const double error = runTiltError(hull, {}, 300.0, 100.0);
  // The wave acceleration (0.5 m/s^2, an apparent tilt of 0.05 rad) is filtered to a few mrad;
  // a fixed level frame would be off by the roll itself (0.1 rad).
  EXPECT_LT(error, 0.006);
}

TEST(GyroAttitude, EstimatesTheGyroBiasOnTheLevelAxes)
{
  RollingHull hull;
  hull.gyro_bias = Vector3(0.004, -0.003, 0.002);
  pbc::GyroAttitudeConfig with;
  pbc::GyroAttitudeConfig without;
  without.estimate_bias = false;
  Vector3 bias;
  const double error_with = runTiltError(hull, with, 600.0, 100.0, &bias);
  const double error_without = runTiltError(hull, without, 600.0, 100.0);
  // Without the estimate the tilt stands off by about |b_level| x tilt_time_constant = 0.15 rad.
  EXPECT_GT(error_without, 0.1);
  EXPECT_LT(error_with, 0.008);
  // The sensor's z is near vertical: its bias is mostly unobservable (yaw); x and y are found.
  EXPECT_NEAR(bias.x(), 0.004, 4e-4);
  EXPECT_NEAR(bias.y(), -0.003, 4e-4);
}

TEST(GyroAttitude, StartsFromTheGivenAttitudeAndIgnoresSlams)
{
  RollingHull hull;
  hull.roll_amplitude = 0.0;
  hull.pitch_amplitude = 0.0;
  hull.wave_acceleration = 0.0;
  pbc::GyroAttitude attitude;
  attitude.reset(hull.attitude(0.0));
  ASSERT_TRUE(attitude.initialised());
  // A 2 g slam pointing sideways is not gravity: the tilt is kept.
  attitude.update(Vector3::Zero(), Vector3(2.0 * pbc::kStandardGravity, 0, 0), 0.01);
  EXPECT_LT(tiltError(attitude.attitude(), hull.attitude(0.0)), 1e-9);
  // Uninitialised, it waits for a gravity-like force, then for kStartWindow of it.
  pbc::GyroAttitude fresh;
  fresh.update(Vector3::Zero(), Vector3(0.1, 0, 0.2), 0.0);
  EXPECT_FALSE(fresh.initialised());
  for (int k = 0; k <= static_cast<int>(pbc::kStartWindow * kRate); ++k)
    fresh.update(Vector3::Zero(), hull.sample(0.0).specific_force, k == 0 ? 0.0 : 1.0 / kRate);
  EXPECT_TRUE(fresh.initialised());
  EXPECT_LT(tiltError(fresh.attitude(), hull.attitude(0.0)), 1e-9);
}

TEST(GyroAttitude, AStartAtRestTakesTheGyroBiasFromIt)
{
  // A consumer gyro at rest with a bias of a few degrees per second (a real MPU-6050 reads
  // -3.3, 1.1, -0.6 deg/s): the start window's mean rate is the bias, so the tilt never runs
  // away while the bias loop would catch up. In waves the window is not at rest and the bias is
  // left to the loop.
  const Vector3 bias(-0.058, 0.019, -0.010);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  const pbc::Quaternion tilt(Eigen::AngleAxisd(0.05, Vector3::UnitX()));
  pbc::GyroAttitude at_rest;
  double worst = 0.0;
  for (int k = 0; k <= static_cast<int>(60.0 * kRate); ++k)
  {
    const Vector3 rate = bias + pbc::test::drawVector([&] { return noise(rng); });
    const Vector3 force = tilt.conjugate() * Vector3(0, 0, pbc::kStandardGravity) + 0.01 * Vector3(noise(rng), 0, 0);
    at_rest.update(rate, force, k == 0 ? 0.0 : 1.0 / kRate);
    if (at_rest.initialised())
      worst = std::max(worst, tiltError(at_rest.attitude(), tilt));
  }
  EXPECT_TRUE(at_rest.startedAtRest());
  EXPECT_LT((at_rest.gyroBias() - bias).norm(), 0.002);
  // What is left is the window's mean of the rate noise, 0.002 / sqrt(200) rad/s, integrated
  // until the bias loop takes it over (tilt_time_constant, 30 s): about 0.004 rad. Unseeded, the
  // tilt would run to 0.058 rad/s x 30 s, over a radian.
  EXPECT_LT(worst, 0.01) << "tilt error [rad] over 60 s";

  RollingHull hull;
  pbc::GyroAttitude rolling;
  for (int k = 0; k <= static_cast<int>(pbc::kStartWindow * kRate) + 1; ++k)
  {
    const pbc::ImuSample s = hull.sample(k / kRate);
    rolling.update(s.angular_rate, s.specific_force, k == 0 ? 0.0 : 1.0 / kRate);
  }
  EXPECT_TRUE(rolling.initialised());
  EXPECT_FALSE(rolling.startedAtRest());
  EXPECT_EQ(rolling.gyroBias(), Vector3::Zero());
}

TEST(GyroAttitude, AtRestTheGyroIsNotIntegrated)
{
  // A noisy gyro (0.006 rad/s per sample, as a real ADIS16405 at 100 Hz) whose bias wanders by
  // 0.5 mrad/s over a minute, at rest for 10 min, tilted 0.05 rad about x. Integrated, its bias
  // wander alone tilts the estimate by ~10 mrad; quiet, the tilt is the mean force's and the
  // bias the mean rate. Then the sensor turns by 0.2 rad about x in 2 s: quiet ends at once and
  // the gyro carries the turn.
  std::mt19937_64 rng(8);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Quaternion tilt(Eigen::AngleAxisd(0.05, Vector3::UnitX()));
  const Vector3 bias(0.007, -0.007, 0.004);
  pbc::GyroAttitude attitude;
  double worst = 0.0, quiet = 0.0, count = 0.0;
  const int rest = static_cast<int>(600.0 * kRate);
  for (int k = 0; k <= rest; ++k)
  {
    const double t = k / kRate;
    const Vector3 wander = 5e-4 * Vector3(std::sin(2.0 * M_PI * t / 60.0), std::cos(2.0 * M_PI * t / 90.0), 0.0);
    const Vector3 rate = bias + wander + 0.006 * pbc::test::drawVector([&] { return normal(rng); });
    const Vector3 force = tilt.conjugate() * Vector3(0, 0, pbc::kStandardGravity) +
                          0.04 * pbc::test::drawVector([&] { return normal(rng); });
    attitude.update(rate, force, k == 0 ? 0.0 : 1.0 / kRate);
    if (t >= 60.0)
    {
      worst = std::max(worst, tiltError(attitude.attitude(), tilt));
      quiet += attitude.quiet() ? 1.0 : 0.0;
      count += 1.0;
    }
  }
  EXPECT_GT(quiet / count, 0.95);
  EXPECT_LT(worst, 0.002) << "tilt error [rad] at rest after the first minute";
  std::printf("[at rest] tilt error at most %.4f rad\n", worst);
  EXPECT_LT((attitude.gyroBias() - bias).norm(), 0.002);

  // The turn: 0.1 rad/s about x for 2 s.
  Quaternion truth = tilt;
  for (int k = 1; k <= static_cast<int>(2.0 * kRate); ++k)
  {
    truth = truth * Quaternion(Eigen::AngleAxisd(0.1 / kRate, Vector3::UnitX()));
    const Vector3 rate = bias + Vector3(0.1, 0, 0) + 0.006 * pbc::test::drawVector([&] { return normal(rng); });
    attitude.update(rate, truth.conjugate() * Vector3(0, 0, pbc::kStandardGravity), 1.0 / kRate);
  }
  EXPECT_FALSE(attitude.quiet());
  EXPECT_LT(tiltError(attitude.attitude(), truth), 0.01) << "after a 0.2 rad turn";
}

TEST(GyroAttitude, CompensatorLevelsSamplesWithoutOrientationWithIt)
{
  RollingHull hull;
  hull.gyro_bias = Vector3(0.002, -0.002, 0.0);
  // Tilt of the frame the compensator levelled with, RMS over the last 100 s of 400 s: g times
  // it leaks into the level axes, which the compensator then takes for motion or bias.
  auto tilt_rms = [&hull](bool gyro_attitude) {
    pbc::CompensatorConfig config;
    config.gyro_attitude = gyro_attitude;
    pbc::Compensator compensator(config);
    pbc::CompensatorOutput out;
    double sum = 0.0;
    int n = 0;
    for (int k = 0; k <= static_cast<int>(400.0 * kRate); ++k)
    {
      const double t = k / kRate;
      const pbc::SampleStatus status = compensator.addSample(hull.sample(t), &out);
      EXPECT_TRUE(pbc::producedOutput(status));
      if (t > 300.0)
      {
        sum += std::pow(tiltError(out.orientation, hull.attitude(t)), 2);
        ++n;
      }
    }
    return std::sqrt(sum / n);
  };
  const double fixed = tilt_rms(false);
  const double gyro = tilt_rms(true);
  // A fixed frame is off by the roll and pitch themselves (about 0.08 rad RMS here).
  EXPECT_GT(fixed, 0.05);
  EXPECT_LT(gyro, 0.006);
}

TEST(GyroAttitude, CarriesOnFromTheLastOrientationWhenItStops)
{
  // The IMU's orientation stops at a roll extreme (F4's case): the gyro takes over from that
  // orientation, so the frame keeps following the roll instead of freezing at any one attitude.
  RollingHull hull;
  pbc::Compensator compensator;
  pbc::CompensatorOutput out;
  const double cut = 122.0;
  double worst = 0.0;
  for (int k = 0; k <= static_cast<int>(200.0 * kRate); ++k)
  {
    const double t = k / kRate;
    pbc::ImuSample s = hull.sample(t);
    s.has_orientation = t < cut;
    s.orientation = hull.attitude(t);
    ASSERT_TRUE(pbc::producedOutput(compensator.addSample(s, &out)));
    if (t >= cut)
      worst = std::max(worst, tiltError(out.orientation, hull.attitude(t)));
  }
  // The wave accelerations (an apparent tilt of 0.05 rad) move it by a few mrad, a little more
  // while the loop settles from the handover; any one frame would be off by up to 0.12 rad.
  EXPECT_LT(worst, 0.01);
}
