// Scenario description of the ship IMU simulator: plain structs that code can fill directly,
// and a strict YAML loader (docs/simulator.md lists every key with unit, default and range).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::sim
{
/// Degrees of freedom of the wave motion, in the heading-following ship frame.
enum Dof
{
  kSurge = 0,  ///< along the ship's x axis [m]
  kSway = 1,   ///< along the ship's y axis [m]
  kHeave = 2,  ///< up [m]
  kRoll = 3,   ///< about x [rad]
  kPitch = 4,  ///< about y [rad]
  kYaw = 5,    ///< about z [rad]
};

/// Names of the DOFs in Dof order: surge, sway, heave, roll, pitch, yaw.
const std::array<std::string, 6>& dofNames();

/// One sinusoid: amplitude * sin(2 pi frequency t + phase).
struct Sinusoid
{
  double amplitude = 0.0;  ///< [m] for surge/sway/heave, [rad] for roll/pitch/yaw
  double frequency = 0.0;  ///< [Hz]
  double phase = 0.0;      ///< [rad]
};

/// One wave system of an irregular sea.
struct WaveSystem
{
  std::string spectrum = "jonswap";  ///< "jonswap" or "pierson_moskowitz" (gamma = 1)
  double significant_height = 1.0;   ///< Hs [m]
  double peak_period = 8.0;          ///< Tp [s]
  double gamma = 3.3;                ///< JONSWAP peak enhancement [-]
  double direction = 0.0;            ///< direction the waves travel TOWARD, ENU yaw (0 = east) [rad]
  double spreading = 0.0;            ///< standard deviation of component directions [rad] (0 = long-crested)
};

/// Irregular sea with a simple per-DOF ship response.
struct Sea
{
  std::vector<WaveSystem> systems;  ///< swell, wind sea, ...
  int components = 120;             ///< wave components per system [-]
  /// Response amplitude factors [-] per Dof: surge/sway/heave follow the water particle motion
  /// times the factor, roll/pitch/yaw follow the wave slope times the factor.
  std::array<double, 6> response{ { 0.5, 0.5, 0.9, 0.8, 0.6, 0.1 } };
  /// How closely surge, sway, roll, pitch and yaw keep the phase of the wave at the ship [-]:
  /// 1 = exactly (particle motion and slope); below 1 each of them lags every component by
  /// (1 - coherence) x U(-pi, pi) of its own, as a hull's response phases do (they vary with
  /// frequency and are not the local slope's). The heave keeps the wave's phase.
  double response_coherence = 1.0;
  /// Ship length [m]: waves shorter than the ship move it less, every component's response is
  /// scaled by 1 / (1 + (length / wavelength)^2). 0 = the ship follows the water at a point.
  double length = 0.0;
};

/// One leg of a route.
struct RouteLeg
{
  double heading = 0.0;   ///< ENU yaw of the leg (0 = east, pi/2 = north) [rad]
  double speed = 0.0;     ///< speed over ground [m/s]
  double duration = 0.0;  ///< time on the leg after the turn and the speed change [s]
};

/// A route: the ship turns at turn_rate to each leg's heading, then changes speed at
/// acceleration, then keeps the leg for its duration. After the last leg it keeps going.
struct Route
{
  double turn_rate = 0.02;     ///< [rad/s]
  double acceleration = 0.05;  ///< [m/s^2]
  std::vector<RouteLeg> legs;
};

/// Kind of motion.
enum class MotionType
{
  kStatic,     ///< at rest at position, heading, roll, pitch
  kSinusoids,  ///< per-DOF sinusoids around a point moving at speed along heading
  kSea,        ///< irregular sea, ship at constant speed along heading
  kRoute,      ///< route legs (slow motion) plus optional sea (wave motion)
};

/// "static", "sinusoids", "sea", "route".
std::string toString(MotionType type);

/// Motion of the reference point base_link.
struct Motion
{
  MotionType type = MotionType::kStatic;
  Vector3 position = Vector3::Zero();   ///< initial position, ENU [m]
  double heading = 0.0;                 ///< initial heading, ENU yaw [rad]
  double roll = 0.0;                    ///< constant roll offset [rad]
  double pitch = 0.0;                   ///< constant pitch offset [rad]
  double speed = 0.0;                   ///< forward speed (sinusoids, sea) [m/s]
  std::array<Sinusoid, 6> sinusoids{};  ///< per Dof (sinusoids)
  Sea sea;                              ///< sea, route (route: used when sea.systems is not empty)
  Route route;                          ///< route
};

/// Sensor temperature: mean + amplitude * sin(2 pi elapsed / period + phase).
struct TemperatureProfile
{
  bool enabled = false;
  double mean = 20.0;       ///< [degC]
  double amplitude = 0.0;   ///< [K]
  double period = 86400.0;  ///< [s]
  double phase = 0.0;       ///< [rad]
};

/// One sensor effect, by name (see effectVocabulary()) with its parameters. Missing
/// parameters take the vocabulary's defaults; a scalar given for a 3-axis parameter applies
/// to all axes.
struct EffectSpec
{
  std::string name;
  bool enabled = true;
  std::map<std::string, std::vector<double>> params;
};

/// A complete scenario.
struct Scenario
{
  std::string name;                   ///< free text
  std::string description;            ///< free text
  double rate = 100.0;                ///< IMU sample rate [Hz]
  double duration = 60.0;             ///< simulated time [s]
  double start_time = 1000.0;         ///< time stamp of the first sample [s] (> 0)
  std::uint64_t seed = 1;             ///< default seed (the command line may override it)
  double gravity = kStandardGravity;  ///< [m/s^2]
  double orientation_stddev = 0.01;   ///< stated accuracy of the reported orientation [rad]
  Motion motion;
  TemperatureProfile temperature;
  std::vector<EffectSpec> effects;  ///< applied in the fixed stage order of docs/simulator.md
};

/// Loads and validates a scenario file.
/// @param path YAML file
/// @throws std::runtime_error naming the file and the offending key
Scenario loadScenario(const std::string& path);

/// Parses and validates a scenario from YAML text.
/// @param text YAML document
/// @param origin name used in error messages (e.g. a file name)
/// @throws std::runtime_error naming the offending key
Scenario parseScenario(const std::string& text, const std::string& origin = "<string>");

/// Writes a scenario as YAML that parseScenario() reads back to the same scenario (every key
/// written, numbers with 17 significant digits). Useful to save a scenario built or fitted in code.
/// @param scenario scenario
std::string toYaml(const Scenario& scenario);

/// Checks ranges and effect parameters of a scenario built in code.
/// @throws std::runtime_error naming the offending field
void validateScenario(const Scenario& scenario);

/// Number of samples the scenario produces: those at k / rate < duration, k = 0, 1, ...
std::int64_t sampleCount(const Scenario& scenario);

/// The first effect of that name, or nullptr.
EffectSpec* findEffect(Scenario& scenario, const std::string& name);
const EffectSpec* findEffect(const Scenario& scenario, const std::string& name);

/// Enables or disables every effect of that name.
/// @return true if at least one effect of that name exists
bool setEffectEnabled(Scenario& scenario, const std::string& name, bool enabled);
}  // namespace periodic_bias_compensation::sim
