// The parameters of a configuration structure as data: key, type, accessor, default, accepted
// range, unit, description and whether it may change at run time. One table per structure is
// the only place a parameter is described; readers (ROS parameter server, YAML files,
// dynamic_reconfigure), validation, the reconfigure definition (cfg/Compensator.cfg, checked
// against the table) and the reference page (docs/ros_api.md, generated) all follow it.
// Estimation core, no ROS. The table of CompensatorConfig lives here; that of the ROS wrapper's
// RosOptions beside it (ros/parameters.h).
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"

namespace periodic_bias_compensation
{
/// Type of a parameter; the order is that of ParameterValue's alternatives.
enum class ParameterType
{
  kBool,
  kInt,
  kDouble,
  kString,
};
/// "bool", "int", "double", "string".
std::string toString(ParameterType type);

/// A parameter value; its alternative index is its ParameterType.
using ParameterValue = std::variant<bool, int, double, std::string>;
ParameterType typeOf(const ParameterValue& value);
/// "true", "2", "0.05" (the shortest text that reads back as the same double), "paper".
std::string toString(const ParameterValue& value);
std::string formatNumber(double value);

/// Values accepted for a number. The bounds may be infinite (no bound); a finite value is
/// required either way.
struct ParameterRange
{
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_inclusive = true;
  bool max_inclusive = true;

  bool contains(double value) const;
  /// The smallest and largest accepted values: the bounds, or for an exclusive bound the
  /// nearest double inside it (what a slider that clamps may offer).
  double lowest() const;
  double highest() const;
};
/// [min, max], [min, max), (min, max), [min, inf), (min, inf).
ParameterRange closed(double min, double max);
ParameterRange rightOpen(double min, double max);
ParameterRange open(double min, double max);
ParameterRange atLeast(double min);
ParameterRange above(double min);
/// Interval notation: "[0, 2)", "[0.5, inf)".
std::string toString(const ParameterRange& range);

/// One accepted value of a text parameter with a fixed set of them.
struct ParameterChoice
{
  std::string value;
  std::string description;
};

/// Whether a parameter may be changed while running (dynamic_reconfigure) or only at start-up.
enum class Reconfigure
{
  kStartup,
  kRuntime,
};

/// A parameter without the structure it lives in.
struct ParameterInfo
{
  std::string key;
  ParameterType type = ParameterType::kDouble;
  std::string unit;         ///< SI unit; "-" for a ratio or count, empty for flags and text
  std::string description;  ///< one line
  Reconfigure reconfigure = Reconfigure::kStartup;
  ParameterRange range;                  ///< numbers (kInt, kDouble)
  std::vector<ParameterChoice> choices;  ///< text: the accepted values (empty: any text)
  bool non_empty = false;                ///< text: the empty string is refused
  std::string range_reason;              ///< why the range is what it is (empty: evident)

  bool reconfigurable() const
  {
    return reconfigure == Reconfigure::kRuntime;
  }
};

/// What a parameter accepts, for messages and documentation: "[0, 2)", "default, paper",
/// "not empty", or empty when anything of its type is accepted.
std::string describeAccepted(const ParameterInfo& info);

/// Checks one value of the parameter: its type, range or choices. On failure false and, if
/// why != nullptr, "key = value is out of range [a, b): reason" or the like.
bool checkValue(const ParameterInfo& info, const ParameterValue& value, std::string* why);

/// A parameter of the structure Config: what it is and how to read and write it there.
template <class Config>
struct Parameter : ParameterInfo
{
  std::function<ParameterValue(const Config&)> get;
  /// Writes a value of the parameter's type (for choices, one of them: see assign()).
  std::function<void(Config&, const ParameterValue&)> set;

  /// The default is the value in a default-constructed Config.
  ParameterValue defaultValue() const
  {
    return get(Config{});
  }
};

template <class Config>
using ParameterTable = std::vector<Parameter<Config>>;

/// Builds a parameter of type T whose place in Config is given by `access`, a callable that
/// returns a reference to it for a Config& and for a const Config& (see member()).
template <class T, class Config, class Access>
Parameter<Config> makeParameter(ParameterInfo info, Access access)
{
  static_assert(std::variant_size_v<ParameterValue> == 4, "ParameterType and ParameterValue differ");
  Parameter<Config> parameter;
  static_cast<ParameterInfo&>(parameter) = std::move(info);
  parameter.type = typeOf(ParameterValue(std::in_place_type<T>));
  parameter.get = [access](const Config& config) { return ParameterValue(std::in_place_type<T>, access(config)); };
  parameter.set = [access](Config& config, const ParameterValue& value) { access(config) = std::get<T>(value); };
  return parameter;
}

/// The accessor of a data member, for makeParameter.
template <class Config, class T>
auto member(T Config::*field)
{
  return [field](auto& config) -> auto&
  {
    return config.*field;
  };
}

/// The fields every parameter has.
ParameterInfo makeInfo(const std::string& key, Reconfigure reconfigure, const std::string& unit,
                       const std::string& description, ParameterRange range = {}, const std::string& range_reason = "");

/// A flag, a number (int or double) and a text stored as data members of Config.
template <class Config>
Parameter<Config> flagParameter(const std::string& key, bool Config::*field, Reconfigure reconfigure,
                                const std::string& description)
{
  return makeParameter<bool, Config>(makeInfo(key, reconfigure, "", description), member(field));
}

template <class Config, class T>
Parameter<Config> numberParameter(const std::string& key, T Config::*field, Reconfigure reconfigure,
                                  ParameterRange range, const std::string& unit, const std::string& description,
                                  const std::string& range_reason = "")
{
  static_assert(std::is_same_v<T, int> || std::is_same_v<T, double>, "a number is an int or a double");
  return makeParameter<T, Config>(makeInfo(key, reconfigure, unit, description, range, range_reason), member(field));
}

template <class Config>
Parameter<Config> textParameter(const std::string& key, std::string Config::*field, Reconfigure reconfigure,
                                const std::string& description, bool non_empty)
{
  ParameterInfo info = makeInfo(key, reconfigure, "", description);
  info.non_empty = non_empty;
  return makeParameter<std::string, Config>(info, member(field));
}

/// The entry of `key`, nullptr if there is none.
template <class Config>
const Parameter<Config>* findParameter(const ParameterTable<Config>& table, const std::string& key)
{
  for (const Parameter<Config>& parameter : table)
    if (parameter.key == key)
      return &parameter;
  return nullptr;
}

/// Writes `value` into *config. False with a message naming the key when the value has another
/// type than the parameter or is not one of its choices (ranges are validate()'s business).
template <class Config>
bool assign(const Parameter<Config>& parameter, const ParameterValue& value, Config* config, std::string* why)
{
  if (typeOf(value) != parameter.type || (!parameter.choices.empty() && !checkValue(parameter, value, nullptr)))
  {
    checkValue(parameter, value, why);
    return false;
  }
  parameter.set(*config, value);
  return true;
}

/// Checks every parameter's own range (validate() adds the rules between parameters).
template <class Config>
bool checkRanges(const ParameterTable<Config>& table, const Config& config, std::string* why)
{
  for (const Parameter<Config>& parameter : table)
    if (!checkValue(parameter, parameter.get(config), why))
      return false;
  return true;
}

/// A parameter whose value differs between two configurations.
struct ParameterChange
{
  const ParameterInfo* info;
  ParameterValue before;
  ParameterValue after;
};

template <class Config>
std::vector<ParameterChange> changes(const ParameterTable<Config>& table, const Config& before, const Config& after)
{
  std::vector<ParameterChange> result;
  for (const Parameter<Config>& parameter : table)
  {
    ParameterValue a = parameter.get(before), b = parameter.get(after);
    if (a != b)
      result.push_back({ &parameter, std::move(a), std::move(b) });
  }
  return result;
}

std::vector<std::string> keys(const std::vector<ParameterChange>& changes);

/// A rule between two numbers of one table: lower < upper (strict) or lower <= upper.
struct ParameterOrder
{
  std::string lower;
  std::string upper;
  bool strict = false;
};
/// "fft_hop <= fft_window".
std::string toString(const ParameterOrder& order);
/// The message of a broken rule, naming first the key the user changed: `lower` unless only
/// `upper` is among `changed` ("min_frequency = 5 must be below max_frequency = 2").
std::string orderMessage(const ParameterOrder& order, double lower, double upper,
                         const std::vector<std::string>& changed);

/// Checks the rule in `config`; on failure false and orderMessage() in *why (if not null).
template <class Config>
bool checkOrder(const ParameterTable<Config>& table, const ParameterOrder& order, const Config& config,
                const std::vector<std::string>& changed, std::string* why)
{
  auto number = [&table, &config](const std::string& key) {
    const ParameterValue value = findParameter(table, key)->get(config);
    return typeOf(value) == ParameterType::kInt ? std::get<int>(value) : std::get<double>(value);
  };
  const double lower = number(order.lower), upper = number(order.upper);
  if (order.strict ? lower < upper : lower <= upper)
    return true;
  if (why != nullptr)
    *why = orderMessage(order, lower, upper, changed);
  return false;
}

/// Gain keys are "<term>_<axis>": alpha_v_x ... beta_p_z.
struct GainTerm
{
  const char* name;
  double AxisGains::*field;
};
constexpr GainTerm kGainTerms[4] = { { "alpha_v", &AxisGains::alpha_v },
                                     { "alpha_p", &AxisGains::alpha_p },
                                     { "beta_v", &AxisGains::beta_v },
                                     { "beta_p", &AxisGains::beta_p } };
constexpr const char* kAxisNames[3] = { "x", "y", "z" };
std::string gainKey(const GainTerm& term, int axis);

/// Every key of CompensatorConfig, in the order of config/compensator.yaml.
const ParameterTable<CompensatorConfig>& compensatorParameters();
/// The rules between keys of CompensatorConfig that CompensatorConfig::validate checks after
/// the ranges: fft_hop <= fft_window, min_frequency < max_frequency.
const std::vector<ParameterOrder>& compensatorOrderRules();

}  // namespace periodic_bias_compensation
