// Named, parameterised sensor effects behind one interface, created by a factory from their
// name. effectVocabulary() lists every effect with its parameters and units.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::sim
{
/// One parameter of an effect.
struct ParamInfo
{
  std::string name;
  std::string unit;
  /// Number of values: 1 scalar, 3 per axis (x, y, z), 9 a row-major 3x3 matrix,
  /// 0 any number (vibration lines).
  std::size_t size = 1;
  std::vector<double> default_value;
  double min = 0.0;  ///< smallest allowed value of every element
  double max = 0.0;  ///< largest allowed value of every element
  std::string description;
};

/// One effect of the vocabulary.
struct EffectInfo
{
  std::string name;
  std::string description;
  std::vector<ParamInfo> params;
  int stage = 0;  ///< application order (lower first), see docs/simulator.md
};

/// Every effect known to the simulator, in stage order.
const std::vector<EffectInfo>& effectVocabulary();

/// The vocabulary entry of an effect.
/// @throws std::runtime_error for an unknown name
const EffectInfo& effectInfo(const std::string& name);

/// An effect with every parameter at its default (mostly zero: no effect).
/// @throws std::runtime_error for an unknown name
EffectSpec defaultEffect(const std::string& name);

/// Fills defaults, broadcasts scalars given for 3-axis parameters, checks names, sizes and
/// ranges.
/// @param spec effect as written
/// @param where prefix of error messages (e.g. "effects[2]")
/// @throws std::runtime_error naming the offending parameter
EffectSpec completeEffect(const EffectSpec& spec, const std::string& where = "effect");

/// What an effect sees of the sample being produced.
struct EffectInput
{
  double elapsed = 0.0;          ///< true time since start [s]
  const Truth* truth = nullptr;  ///< exact motion of base_link
  double temperature = 0.0;      ///< [degC]
  bool has_temperature = false;
};

/// What effects modify.
struct ImuOutput
{
  Vector3 accel = Vector3::Zero();                  ///< specific force, sensor frame [m/s^2]
  Vector3 gyro = Vector3::Zero();                   ///< angular rate, sensor frame [rad/s]
  Quaternion orientation = Quaternion::Identity();  ///< reported sensor -> ENU
  double stamp_offset = 0.0;                        ///< added to the true time stamp [s]
  bool dropped = false;
};

/// A sensor effect. Effects are applied once per sample, in time order.
class Effect
{
public:
  virtual ~Effect() = default;
  /// Modifies the sample.
  /// @param in truth and time of the sample
  /// @param out sample being produced
  virtual void apply(const EffectInput& in, ImuOutput& out) = 0;
};

/// Creates an effect.
/// @param spec effect (completed with completeEffect() first)
/// @param seed seed of this effect's own random stream [-]
/// @param rate sample rate [Hz]
/// @throws std::runtime_error for an unknown name or inconsistent parameters
std::unique_ptr<Effect> makeEffect(const EffectSpec& spec, std::uint64_t seed, double rate);
}  // namespace periodic_bias_compensation::sim
