#include "periodic_bias_compensation/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "periodic_bias_compensation/sim/random.h"

namespace periodic_bias_compensation::sim
{
ImuCovariance imuCovariance(const Scenario& scenario)
{
  ImuCovariance out;
  for (const EffectSpec& raw : scenario.effects)
  {
    if (!raw.enabled)
    {
      continue;
    }
    const EffectSpec e = completeEffect(raw);
    const auto v3 = [&e](const std::string& key) {
      const std::vector<double>& v = e.params.at(key);
      return Vector3(v[0], v[1], v[2]);
    };
    if (e.name == "white_noise")
    {
      out.accel_variance += v3("accel_density").cwiseAbs2() * scenario.rate;
      out.gyro_variance += v3("gyro_density").cwiseAbs2() * scenario.rate;
    }
    else if (e.name == "quantization")
    {
      out.accel_variance += v3("accel_step").cwiseAbs2() / 12.0;
      out.gyro_variance += v3("gyro_step").cwiseAbs2() / 12.0;
    }
  }
  out.orientation_variance = scenario.orientation_stddev * scenario.orientation_stddev;
  return out;
}

double temperatureAt(const TemperatureProfile& profile, double elapsed)
{
  return profile.mean + profile.amplitude * std::sin(2.0 * M_PI * elapsed / profile.period + profile.phase);
}

void idealImu(const Truth& truth, double gravity, Vector3* accel, Vector3* gyro)
{
  *accel = truth.attitude.conjugate() * (truth.acceleration + Vector3(0.0, 0.0, gravity));
  *gyro = truth.angular_rate;
}

TruthOdometry truthOdometry(const Truth& truth)
{
  TruthOdometry out;
  out.total.position = truth.position;
  out.total.orientation = truth.attitude;
  out.total.linear_velocity = truth.attitude.conjugate() * truth.velocity;
  out.total.angular_velocity = truth.angular_rate;
  out.slow.position = truth.slow_position;
  out.slow.orientation = Quaternion(Eigen::AngleAxisd(truth.slow_heading, Vector3::UnitZ()));
  out.slow.linear_velocity = out.slow.orientation.conjugate() * truth.slow_velocity;
  out.slow.angular_velocity = Vector3(0.0, 0.0, truth.slow_yaw_rate);
  out.wave.position = truth.wave_position;
  out.wave.orientation = truth.attitude;
  out.wave.linear_velocity = truth.attitude.conjugate() * truth.wave_velocity;
  out.wave.angular_velocity = truth.angular_rate;
  return out;
}

namespace
{
Scenario completed(const Scenario& scenario)
{
  validateScenario(scenario);
  Scenario out = scenario;
  out.effects.clear();
  for (std::size_t i = 0; i < scenario.effects.size(); ++i)
  {
    out.effects.push_back(completeEffect(scenario.effects[i], "effects[" + std::to_string(i) + "]"));
  }
  return out;
}
}  // namespace

Simulator::Simulator(const Scenario& scenario, std::uint64_t seed, ShipMotion::Outputs outputs)
  : scenario_(completed(scenario)), motion_(scenario_, seed, outputs), count_(sim::sampleCount(scenario_))
{
  std::vector<const EffectSpec*> order;
  for (const EffectSpec& e : scenario_.effects)
  {
    if (e.enabled)
    {
      order.push_back(&e);
    }
  }
  std::stable_sort(order.begin(), order.end(), [](const EffectSpec* a, const EffectSpec* b) {
    return effectInfo(a->name).stage < effectInfo(b->name).stage;
  });
  std::map<std::string, std::uint64_t> occurrence;
  for (const EffectSpec* e : order)
  {
    effects_.push_back(makeEffect(*e, deriveSeed(seed, e->name, occurrence[e->name]++), scenario_.rate));
  }
}

bool Simulator::next(Sample* sample)
{
  return k_ < count_ && next(motion_.evaluate(k_), sample);
}

bool Simulator::next(const Truth& truth, Sample* sample)
{
  if (k_ >= count_)
  {
    return false;
  }
  Sample& s = *sample;
  s.index = k_;
  s.elapsed = k_ / scenario_.rate;
  s.t = scenario_.start_time + s.elapsed;
  s.truth = truth;
  s.has_temperature = scenario_.temperature.enabled;
  s.temperature = s.has_temperature ? temperatureAt(scenario_.temperature, s.elapsed) : 0.0;

  EffectInput in;
  in.elapsed = s.elapsed;
  in.truth = &s.truth;
  in.temperature = s.temperature;
  in.has_temperature = s.has_temperature;
  ImuOutput out;
  idealImu(s.truth, scenario_.gravity, &out.accel, &out.gyro);
  out.orientation = s.truth.attitude;
  for (const std::unique_ptr<Effect>& effect : effects_)
  {
    effect->apply(in, out);
  }
  s.accel = out.accel;
  s.gyro = out.gyro;
  s.orientation = out.orientation;
  s.stamp = s.t + out.stamp_offset;
  s.dropped = out.dropped;
  ++k_;
  return true;
}
}  // namespace periodic_bias_compensation::sim
