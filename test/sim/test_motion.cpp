// Motion truth: consistency of positions, velocities, accelerations, attitude and rates;
// sea statistics and encounter frequency; route geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "periodic_bias_compensation/sim/motion.h"
#include "sim_test_util.h"

namespace sim = periodic_bias_compensation::sim;

namespace
{
std::vector<sim::Truth> truths(const sim::Scenario& s, std::uint64_t seed = 3)
{
  sim::ShipMotion motion(s, seed);
  std::vector<sim::Truth> out;
  for (std::int64_t k = 0; k < sim::sampleCount(s); ++k)
  {
    out.push_back(motion.evaluate(k));
  }
  return out;
}

sim::Scenario seaScenario(double rate, double duration)
{
  sim::Scenario s;
  s.rate = rate;
  s.duration = duration;
  s.motion.type = sim::MotionType::kSea;
  s.motion.speed = 6.0;
  s.motion.heading = 0.3;
  sim::WaveSystem swell;
  swell.significant_height = 2.0;
  swell.peak_period = 11.0;
  swell.direction = 1.0;
  sim::WaveSystem wind;
  wind.significant_height = 1.5;
  wind.peak_period = 6.0;
  wind.direction = -2.5;
  wind.spreading = 0.4;
  s.motion.sea.systems = { swell, wind };
  return s;
}

sim::Scenario routeScenario(double rate)
{
  sim::Scenario s = seaScenario(rate, 400.0);
  s.motion.type = sim::MotionType::kRoute;
  s.motion.speed = 0.0;
  s.motion.route.turn_rate = 0.05;
  s.motion.route.acceleration = 0.1;
  s.motion.sea.length = 40.0;
  s.motion.route.legs = { { 0.5, 5.0, 60.0 }, { 2.5, 5.0, 60.0 }, { -2.5, 8.0, 60.0 }, { -2.5, 3.0, 1000.0 } };
  return s;
}

// Checks v = dp/dt, a = dv/dt, w = attitude rate, alpha = dw/dt by central differences
// (relative tolerance),
// away from slow-motion segment boundaries (where the route acceleration jumps).
void expectConsistent(const std::vector<sim::Truth>& x, double rate, double tolerance)
{
  const double h = 1.0 / rate;
  int checked = 0;
  for (std::size_t k = 1; k + 1 < x.size(); ++k)
  {
    const sim::Truth& a = x[k - 1];
    const sim::Truth& b = x[k];
    const sim::Truth& c = x[k + 1];
    if ((a.slow_acceleration - c.slow_acceleration).norm() > 1e-12 || a.slow_yaw_rate != c.slow_yaw_rate)
    {
      continue;
    }
    ++checked;
    // Central differences have a relative error (omega h)^2 / 6.
    const auto near = [tolerance](const sim::Vector3& numeric, const sim::Vector3& exact) {
      return (numeric - exact).norm() < tolerance * (1.0 + exact.norm());
    };
    ASSERT_TRUE(near((c.position - a.position) / (2 * h), b.velocity)) << "k " << k;
    ASSERT_TRUE(near((c.velocity - a.velocity) / (2 * h), b.acceleration)) << "k " << k;
    ASSERT_TRUE(near((c.wave_velocity - a.wave_velocity) / (2 * h), b.wave_acceleration)) << "k " << k;
    ASSERT_TRUE(near((c.slow_position - a.slow_position) / (2 * h), b.slow_velocity)) << "k " << k;
    const Eigen::AngleAxisd d(a.attitude.conjugate() * c.attitude);
    ASSERT_TRUE(near(d.angle() * d.axis() / (2 * h), b.angular_rate)) << "k " << k;
    ASSERT_TRUE(near((c.angular_rate - a.angular_rate) / (2 * h), b.angular_acceleration)) << "k " << k;
    ASSERT_LT((b.position - b.slow_position - b.wave_position).norm(), 1e-9);
  }
  EXPECT_GT(checked, static_cast<int>(x.size() / 2));
}
}  // namespace

TEST(Motion, StaticLevelReadsPlusGravityOnZ)
{
  sim::Scenario s;
  s.duration = 1.0;
  s.motion.heading = 1.2;
  sim::Simulator simulator(s, 1);
  sim::Sample smp;
  while (simulator.next(&smp))
  {
    ASSERT_NEAR((smp.accel - sim::Vector3(0.0, 0.0, sim::kStandardGravity)).norm(), 0.0, 1e-12);
    ASSERT_EQ(smp.gyro.norm(), 0.0);
    ASSERT_NEAR(smp.orientation.angularDistance(sim::Quaternion(Eigen::AngleAxisd(1.2, sim::Vector3::UnitZ()))), 0.0,
                1e-12);
    ASSERT_EQ(smp.truth.velocity.norm(), 0.0);
  }
  EXPECT_DOUBLE_EQ(smp.t, 1000.0 + 99.0 / 100.0);
}

TEST(Motion, StaticTiltedReadsRotatedGravity)
{
  sim::Scenario s;
  s.duration = 0.1;
  s.motion.pitch = 0.1;  // nose down (REP-103: positive pitch about y-left)
  sim::Simulator simulator(s, 1);
  sim::Sample smp;
  ASSERT_TRUE(simulator.next(&smp));
  EXPECT_NEAR(smp.accel.x(), -sim::kStandardGravity * std::sin(0.1), 1e-12);
  EXPECT_NEAR(smp.accel.z(), sim::kStandardGravity * std::cos(0.1), 1e-12);
}

TEST(Motion, SinusoidSurgeGivesExpectedSpecificForce)
{
  sim::Scenario s;
  s.rate = 87.7;
  s.duration = 10.0;
  s.motion.type = sim::MotionType::kSinusoids;
  s.motion.sinusoids[sim::kSurge] = { 0.05, 0.443, 0.0 };
  sim::Simulator simulator(s, 1);
  sim::Sample smp;
  while (simulator.next(&smp))
  {
    const double w = 2.0 * M_PI * 0.443;
    ASSERT_NEAR(smp.accel.x(), -0.05 * w * w * std::sin(w * smp.elapsed), 1e-12);
    ASSERT_NEAR(smp.truth.position.x(), 0.05 * std::sin(w * smp.elapsed), 1e-12);
    ASSERT_NEAR(smp.accel.z(), sim::kStandardGravity, 1e-12);
  }
}

TEST(Motion, SinusoidTruthIsConsistent)
{
  sim::Scenario s;
  s.rate = 400.0;
  s.duration = 20.0;
  s.motion.type = sim::MotionType::kSinusoids;
  s.motion.speed = 3.0;
  s.motion.heading = 0.7;
  s.motion.sinusoids = { { { 0.5, 0.2, 0.0 },
                           { 0.3, 0.15, 1.0 },
                           { 1.0, 0.1, 2.0 },
                           { 0.3, 0.12, 0.0 },
                           { 0.1, 0.2, 0.3 },
                           { 0.2, 0.05, 1.0 } } };
  expectConsistent(truths(s), s.rate, 1e-4);
}

TEST(Motion, SeaTruthIsConsistent)
{
  // Up to 15 rad/s encounter frequency in these head seas: sample fast for the differences.
  const sim::Scenario s = seaScenario(1000.0, 30.0);
  expectConsistent(truths(s), s.rate, 1e-3);
}

TEST(Motion, RouteTruthIsConsistentThroughTurnsAndSpeedChanges)
{
  const sim::Scenario s = routeScenario(100.0);
  expectConsistent(truths(s), s.rate, 2e-3);
}

TEST(Motion, RouteFollowsLegs)
{
  sim::Scenario s = routeScenario(10.0);
  s.motion.sea.systems.clear();
  const std::vector<sim::Truth> x = truths(s);
  // Leg 1: turn 0.5 rad at 0.05 rad/s (10 s, at speed 0), accelerate to 5 m/s (50 s), hold 60 s.
  const sim::Truth& leg1 = x[static_cast<std::size_t>(100.0 * s.rate)];
  EXPECT_NEAR(leg1.slow_heading, 0.5, 1e-9);
  EXPECT_NEAR(leg1.slow_velocity.norm(), 5.0, 1e-9);
  EXPECT_NEAR(std::atan2(leg1.slow_velocity.y(), leg1.slow_velocity.x()), 0.5, 1e-9);
  EXPECT_EQ(leg1.wave_position.norm(), 0.0);
  // Leg 2 starts at 120 s with a 2 rad turn (40 s): mid-turn yaw rate +0.05 rad/s.
  const sim::Truth& turning = x[static_cast<std::size_t>(140.0 * s.rate)];
  EXPECT_NEAR(turning.slow_yaw_rate, 0.05, 1e-12);
  EXPECT_NEAR(turning.slow_acceleration.norm(), 5.0 * 0.05, 1e-9);  // centripetal v r
  // Leg 3: shortest turn from 2.5 to -2.5 rad goes through pi (+1.28 rad, turning left).
  const sim::Truth& third = x[static_cast<std::size_t>(225.0 * s.rate)];
  EXPECT_NEAR(third.slow_yaw_rate, 0.05, 1e-12);
  // Continuity of the slow position.
  for (std::size_t k = 1; k < x.size(); ++k)
  {
    ASSERT_LT((x[k].slow_position - x[k - 1].slow_position).norm(), 8.0 / s.rate + 1e-9);
  }
}

TEST(Motion, SeaComponentsReproduceSignificantHeight)
{
  sim::Sea sea;
  sim::WaveSystem w;
  w.significant_height = 3.0;
  w.peak_period = 9.0;
  sea.systems = { w };
  sea.components = 200;
  const std::vector<sim::WaveComponent> c = sim::drawWaveComponents(sea, sim::kStandardGravity, 5);
  ASSERT_EQ(c.size(), 200u);
  double m0 = 0.0;
  for (const sim::WaveComponent& x : c)
  {
    m0 += 0.5 * x.amplitude * x.amplitude;
  }
  EXPECT_NEAR(4.0 * std::sqrt(m0), 3.0, 0.1);
}

TEST(Motion, SeaHeaveStatisticsMatchSpectrum)
{
  sim::Scenario s = seaScenario(5.0, 3600.0);
  s.motion.speed = 0.0;
  s.motion.sea.systems.resize(1);
  s.motion.sea.response[sim::kHeave] = 1.0;
  const std::vector<sim::Truth> x = truths(s);
  std::vector<double> heave;
  for (const sim::Truth& t : x)
  {
    heave.push_back(t.position.z());
  }
  double mean = 0.0;
  double stddev = 0.0;
  sim_test::meanStd(heave, &mean, &stddev);
  EXPECT_NEAR(4.0 * stddev, 2.0, 0.3);
  EXPECT_NEAR(mean, 0.0, 0.1);
}

TEST(Motion, EncounterFrequencyShiftsWithCourse)
{
  // Narrow swell from the east toward the west (direction pi); the ship heads east at 8 m/s
  // (head seas, mu = pi) or west (following seas, mu = 0).
  const auto centroid = [](double heading, double speed, double* expected) {
    sim::Scenario s;
    s.rate = 4.0;
    s.duration = 3000.0;
    s.motion.type = sim::MotionType::kSea;
    s.motion.heading = heading;
    s.motion.speed = speed;
    sim::WaveSystem w;
    w.significant_height = 2.0;
    w.peak_period = 12.0;
    w.gamma = 7.0;
    w.direction = M_PI;
    s.motion.sea.systems = { w };
    sim::ShipMotion motion(s, 9);
    double num = 0.0;
    double den = 0.0;
    for (const sim::WaveComponent& c : motion.waveComponents())
    {
      const double we = sim::encounterFrequency(c.omega, speed, c.direction - heading, s.gravity);
      num += c.amplitude * c.amplitude * std::abs(we) / (2.0 * M_PI);
      den += c.amplitude * c.amplitude;
    }
    *expected = num / den;
    std::vector<double> heave;
    for (std::int64_t k = 0; k < sim::sampleCount(s); ++k)
    {
      heave.push_back(motion.evaluate(k).position.z());
    }
    double pn = 0.0;
    double pd = 0.0;
    for (double f = 0.01; f < 0.5; f += 0.0005)
    {
      const double p = std::pow(sim_test::lineAmplitude(heave, s.rate, f), 2);
      pn += p * f;
      pd += p;
    }
    return pn / pd;
  };
  double e_head = 0.0;
  double e_still = 0.0;
  double e_follow = 0.0;
  const double head = centroid(0.0, 8.0, &e_head);
  const double still = centroid(0.0, 0.0, &e_still);
  const double follow = centroid(M_PI, 8.0, &e_follow);
  EXPECT_NEAR(head / e_head, 1.0, 0.03);
  EXPECT_NEAR(still / e_still, 1.0, 0.03);
  EXPECT_NEAR(follow / e_follow, 1.0, 0.03);
  EXPECT_GT(head, 1.3 * still);
  EXPECT_LT(follow, 0.8 * still);
}

TEST(Motion, BeamSeasRollMoreThanPitch)
{
  sim::Scenario s = seaScenario(5.0, 1200.0);
  s.motion.speed = 0.0;
  s.motion.heading = 0.0;
  s.motion.sea.systems.resize(1);
  s.motion.sea.systems[0].direction = M_PI / 2;  // waves travel north: from starboard to port
  double roll2 = 0.0;
  double pitch2 = 0.0;
  double surge2 = 0.0;
  double sway2 = 0.0;
  for (const sim::Truth& t : truths(s))
  {
    const sim::Vector3 e = t.attitude.toRotationMatrix().eulerAngles(2, 1, 0);
    const double roll = std::remainder(e[2], M_PI);
    const double pitch = std::remainder(e[1], M_PI);
    roll2 += roll * roll;
    pitch2 += pitch * pitch;
    surge2 += t.wave_position.x() * t.wave_position.x();
    sway2 += t.wave_position.y() * t.wave_position.y();
  }
  EXPECT_GT(roll2, 100.0 * pitch2);
  EXPECT_GT(sway2, 100.0 * surge2);
}

TEST(Motion, RandomAccessMatchesSequentialEvaluation)
{
  const sim::Scenario s = routeScenario(20.0);
  const std::vector<sim::Truth> forward = truths(s);
  sim::ShipMotion motion(s, 3);
  for (std::int64_t k = sim::sampleCount(s) - 1; k >= 0; k -= 7)
  {
    const sim::Truth t = motion.evaluate(k);
    ASSERT_LT((t.position - forward[k].position).norm(), 1e-9) << k;
    ASSERT_LT((t.acceleration - forward[k].acceleration).norm(), 1e-9) << k;
    ASSERT_LT(t.attitude.angularDistance(forward[k].attitude), 1e-9) << k;
  }
}

TEST(Motion, IncoherentResponsesAreConsistentAndDecorrelated)
{
  // Response lags of their own: the truth stays consistent (fast path and turns), the heave is
  // the coherent sea's, and the roll (k a sin) no longer follows the sway's acceleration
  // (-w^2 a sin, the same frequency weighting) as the wave slope makes it.
  sim::Scenario coherent = seaScenario(200.0, 600.0);
  coherent.motion.speed = 0.0;
  coherent.motion.sea.systems.resize(1);
  coherent.motion.sea.systems[0].direction = M_PI / 2;  // beam seas: sway and roll both large
  sim::Scenario lagged = coherent;
  lagged.motion.sea.response_coherence = 0.0;
  sim::validateScenario(lagged);
  const std::vector<sim::Truth> a = truths(coherent), b = truths(lagged);
  expectConsistent(b, lagged.rate, 1e-3);
  sim::Scenario route = routeScenario(100.0);
  route.motion.sea.response_coherence = 0.3;
  expectConsistent(truths(route), route.rate, 2e-3);
  const auto correlation = [](const std::vector<sim::Truth>& x) {
    double sxy = 0.0, sxx = 0.0, syy = 0.0;
    for (const sim::Truth& t : x)
    {
      const double roll = std::remainder(t.attitude.toRotationMatrix().eulerAngles(2, 1, 0)[2], M_PI);
      const double sway = t.wave_acceleration.y();
      sxy += roll * sway;
      sxx += roll * roll;
      syy += sway * sway;
    }
    return sxy / std::sqrt(sxx * syy);
  };
  EXPECT_GT(std::abs(correlation(a)), 0.95);
  EXPECT_LT(std::abs(correlation(b)), 0.3);
  double heave_difference = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k)
  {
    heave_difference = std::max(heave_difference, std::abs(a[k].wave_position.z() - b[k].wave_position.z()));
  }
  EXPECT_LT(heave_difference, 1e-9);
}

TEST(Motion, SensorOutputsAreThoseOfEveryOutput)
{
  // What the sensor reads is the same to the bit with Outputs::kSensor (fewer rows of the sea
  // synthesised), on a steady course, with response lags and through a route's turns; the sea's
  // part of position and velocity is left out on the steady parts only.
  sim::Scenario lagged = seaScenario(50.0, 120.0);
  lagged.motion.sea.response_coherence = 0.4;
  for (const sim::Scenario& s : { seaScenario(50.0, 120.0), lagged, routeScenario(60.0) })
  {
    sim::ShipMotion all(s, 4), sensor(s, 4, sim::ShipMotion::Outputs::kSensor);
    int zero_wave = 0;
    for (std::int64_t k = 0; k < sim::sampleCount(s); ++k)
    {
      const sim::Truth a = all.evaluate(k), b = sensor.evaluate(k);
      ASSERT_EQ(a.acceleration, b.acceleration) << k;
      ASSERT_EQ(a.angular_rate, b.angular_rate) << k;
      ASSERT_EQ(a.angular_acceleration, b.angular_acceleration) << k;
      ASSERT_EQ(a.attitude.coeffs(), b.attitude.coeffs()) << k;
      ASSERT_EQ(a.slow_position, b.slow_position) << k;
      zero_wave += b.wave_position.isZero(0.0) && b.wave_velocity.isZero(0.0);
    }
    EXPECT_GT(zero_wave, sim::sampleCount(s) / 4) << s.name;
  }
}
