#include "periodic_bias_compensation/ros/parameters.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace periodic_bias_compensation
{
namespace
{
using Reader = std::function<bool(const ParameterSource&, const std::string&, Parameters*, std::string*)>;

struct Key
{
  std::string name;
  Reader read;
};

template <class T, class Getter>
Reader field(Getter getter)
{
  return [getter](const ParameterSource& source, const std::string& key, Parameters* p, std::string* why) {
    T* target = getter(p);
    if constexpr (std::is_same_v<T, bool>)
    {
      return source.getBool(key, target, why);
    }
    else if constexpr (std::is_same_v<T, int>)
    {
      return source.getInt(key, target, why);
    }
    else if constexpr (std::is_same_v<T, double>)
    {
      return source.getDouble(key, target, why);
    }
    else
    {
      return source.getString(key, target, why);
    }
  };
}

const std::vector<Key>& keyTable()
{
  static const std::vector<Key> table = [] {
    std::vector<Key> t;
    t.push_back({ "mode", [](const ParameterSource& s, const std::string& key, Parameters* p, std::string* why) {
                   std::string name;
                   if (!s.getString(key, &name, why))
                   {
                     return false;
                   }
                   if (!modeFromString(name, &p->core.mode))
                   {
                     *why = "parameter 'mode': unknown mode '" + name + "' (expected 'paper' or 'default')";
                     return false;
                   }
                   return true;
                 } });
    const char* axes[3] = { "x", "y", "z" };
    for (int i = 0; i < 3; ++i)
    {
      const std::string a = axes[i];
      t.push_back({ "alpha_v_" + a, field<double>([i](Parameters* p) { return &p->core.gains[i].alpha_v; }) });
      t.push_back({ "alpha_p_" + a, field<double>([i](Parameters* p) { return &p->core.gains[i].alpha_p; }) });
      t.push_back({ "beta_v_" + a, field<double>([i](Parameters* p) { return &p->core.gains[i].beta_v; }) });
      t.push_back({ "beta_p_" + a, field<double>([i](Parameters* p) { return &p->core.gains[i].beta_p; }) });
    }
    t.push_back({ "enable_constant", field<bool>([](Parameters* p) { return &p->core.enable_constant; }) });
    t.push_back({ "enable_periodic", field<bool>([](Parameters* p) { return &p->core.enable_periodic; }) });
    t.push_back({ "calibration_duration", field<double>([](Parameters* p) { return &p->core.calibration_duration; }) });
    t.push_back({ "assume_static_calibration",
                  field<bool>([](Parameters* p) { return &p->core.assume_static_calibration; }) });
    t.push_back({ "fft_window", field<double>([](Parameters* p) { return &p->core.fft_window; }) });
    t.push_back({ "fft_hop", field<double>([](Parameters* p) { return &p->core.fft_hop; }) });
    t.push_back({ "min_frequency", field<double>([](Parameters* p) { return &p->core.min_frequency; }) });
    t.push_back({ "max_frequency", field<double>([](Parameters* p) { return &p->core.max_frequency; }) });
    t.push_back({ "min_peak_ratio", field<double>([](Parameters* p) { return &p->core.min_peak_ratio; }) });
    t.push_back({ "harmonics", field<int>([](Parameters* p) { return &p->core.harmonics; }) });
    t.push_back({ "harmonic_memory", field<double>([](Parameters* p) { return &p->core.harmonic_memory; }) });
    t.push_back({ "drift_time_constant", field<double>([](Parameters* p) { return &p->core.drift_time_constant; }) });
    t.push_back({ "heave_filter", field<bool>([](Parameters* p) { return &p->core.heave_filter; }) });
    t.push_back({ "heave_corner_frequency",
                  field<double>([](Parameters* p) { return &p->core.heave_corner_frequency; }) });
    t.push_back({ "gyro_attitude", field<bool>([](Parameters* p) { return &p->core.gyro_attitude; }) });
    t.push_back({ "tilt_time_constant", field<double>([](Parameters* p) { return &p->core.tilt_time_constant; }) });
    t.push_back({ "estimate_gyro_bias", field<bool>([](Parameters* p) { return &p->core.estimate_gyro_bias; }) });
    t.push_back({ "gravity", field<double>([](Parameters* p) { return &p->core.gravity; }) });
    t.push_back({ "max_gap", field<double>([](Parameters* p) { return &p->core.max_gap; }) });
    t.push_back({ "max_rate_change", field<double>([](Parameters* p) { return &p->core.max_rate_change; }) });
    t.push_back({ "max_quaternion_norm_error",
                  field<double>([](Parameters* p) { return &p->core.max_quaternion_norm_error; }) });
    t.push_back({ "odom_frame", field<std::string>([](Parameters* p) { return &p->ros.odom_frame; }) });
    t.push_back({ "base_frame", field<std::string>([](Parameters* p) { return &p->ros.base_frame; }) });
    t.push_back({ "imu_frame", field<std::string>([](Parameters* p) { return &p->ros.imu_frame; }) });
    t.push_back({ "publish_tf", field<bool>([](Parameters* p) { return &p->ros.publish_tf; }) });
    t.push_back({ "path_max_length", field<int>([](Parameters* p) { return &p->ros.path_max_length; }) });
    t.push_back({ "path_rate", field<double>([](Parameters* p) { return &p->ros.path_rate; }) });
    t.push_back({ "mount_timeout", field<double>([](Parameters* p) { return &p->ros.mount_timeout; }) });
    t.push_back({ "identity_mounting", field<bool>([](Parameters* p) { return &p->ros.identity_mounting; }) });
    t.push_back({ "calibration_file", field<std::string>([](Parameters* p) { return &p->ros.calibration_file; }) });
    t.push_back({ "diagnostic_period", field<double>([](Parameters* p) { return &p->ros.diagnostic_period; }) });
    return t;
  }();
  return table;
}

std::string typeError(const std::string& key, const std::string& expected)
{
  return "parameter '" + key + "': expected " + expected;
}
}  // namespace

bool RosOptions::validate(std::string* why) const
{
  auto fail = [why](const std::string& message) {
    if (why != nullptr)
    {
      *why = message;
    }
    return false;
  };
  if (odom_frame.empty())
  {
    return fail("parameter 'odom_frame': must not be empty");
  }
  if (base_frame.empty())
  {
    return fail("parameter 'base_frame': must not be empty");
  }
  if (odom_frame == base_frame)
  {
    return fail("parameters 'odom_frame' and 'base_frame' must differ (both '" + odom_frame + "')");
  }
  if (path_max_length < 1)
  {
    return fail("parameter 'path_max_length': must be >= 1, got " + std::to_string(path_max_length));
  }
  if (!(path_rate > 0.0 && std::isfinite(path_rate)))
  {
    return fail("parameter 'path_rate': must be > 0 Hz");
  }
  if (!(mount_timeout >= 0.0 && std::isfinite(mount_timeout)))
  {
    return fail("parameter 'mount_timeout': must be >= 0 s");
  }
  if (!(diagnostic_period > 0.0 && std::isfinite(diagnostic_period)))
  {
    return fail("parameter 'diagnostic_period': must be > 0 s");
  }
  return true;
}

bool readParameters(const ParameterSource& source, Parameters* params, std::string* why)
{
  std::string message;
  for (const std::string& key : source.keys())
  {
    const auto& table = keyTable();
    const auto it = std::find_if(table.begin(), table.end(), [&key](const Key& k) { return k.name == key; });
    if (it == table.end())
    {
      *why = "unknown parameter '" + key + "' (see config/compensator.yaml for the keys)";
      return false;
    }
    if (!it->read(source, key, params, &message))
    {
      *why = message;
      return false;
    }
  }
  if (!params->core.validate(&message))
  {
    *why = "invalid parameters: " + message;
    return false;
  }
  if (!params->ros.validate(&message))
  {
    *why = message;
    return false;
  }
  return true;
}

RosParameterSource::RosParameterSource(const ros::NodeHandle& pnh) : ns_(pnh.getNamespace())
{
  if (!pnh.getParam(ns_, values_))
  {
    values_ = XmlRpc::XmlRpcValue();
    return;
  }
  if (values_.getType() != XmlRpc::XmlRpcValue::TypeStruct)
  {
    throw std::runtime_error("parameter namespace '" + ns_ + "' is not a dictionary");
  }
}

std::vector<std::string> RosParameterSource::keys() const
{
  std::vector<std::string> result;
  if (values_.getType() != XmlRpc::XmlRpcValue::TypeStruct)
  {
    return result;
  }
  XmlRpc::XmlRpcValue copy = values_;
  for (auto it = copy.begin(); it != copy.end(); ++it)
  {
    result.push_back(it->first);
  }
  return result;
}

bool RosParameterSource::getBool(const std::string& key, bool* value, std::string* why) const
{
  XmlRpc::XmlRpcValue v = XmlRpc::XmlRpcValue(values_)[key];
  if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean)
  {
    *why = typeError(ns_ + "/" + key, "true or false");
    return false;
  }
  *value = static_cast<bool>(v);
  return true;
}

bool RosParameterSource::getInt(const std::string& key, int* value, std::string* why) const
{
  XmlRpc::XmlRpcValue v = XmlRpc::XmlRpcValue(values_)[key];
  if (v.getType() != XmlRpc::XmlRpcValue::TypeInt)
  {
    *why = typeError(ns_ + "/" + key, "an integer");
    return false;
  }
  *value = static_cast<int>(v);
  return true;
}

bool RosParameterSource::getDouble(const std::string& key, double* value, std::string* why) const
{
  XmlRpc::XmlRpcValue v = XmlRpc::XmlRpcValue(values_)[key];
  if (v.getType() == XmlRpc::XmlRpcValue::TypeInt)
  {
    *value = static_cast<int>(v);
    return true;
  }
  if (v.getType() != XmlRpc::XmlRpcValue::TypeDouble)
  {
    *why = typeError(ns_ + "/" + key, "a number");
    return false;
  }
  *value = static_cast<double>(v);
  return true;
}

bool RosParameterSource::getString(const std::string& key, std::string* value, std::string* why) const
{
  XmlRpc::XmlRpcValue v = XmlRpc::XmlRpcValue(values_)[key];
  if (v.getType() != XmlRpc::XmlRpcValue::TypeString)
  {
    *why = typeError(ns_ + "/" + key, "a string");
    return false;
  }
  *value = static_cast<std::string>(v);
  return true;
}

YamlParameterSource::YamlParameterSource(const std::string& path) : path_(path)
{
  try
  {
    root_ = YAML::LoadFile(path);
  }
  catch (const YAML::BadFile&)
  {
    throw std::runtime_error("cannot read parameter file '" + path + "'");
  }
  catch (const YAML::Exception& e)
  {
    throw std::runtime_error("parameter file '" + path + "': YAML error: " + e.what());
  }
  if (root_.IsNull())
  {
    root_ = YAML::Node(YAML::NodeType::Map);
  }
  if (!root_.IsMap())
  {
    throw std::runtime_error("parameter file '" + path + "': the top level must be a map of key: value");
  }
}

std::vector<std::string> YamlParameterSource::keys() const
{
  std::vector<std::string> result;
  for (const auto& entry : root_)
  {
    result.push_back(entry.first.as<std::string>());
  }
  return result;
}

namespace
{
template <class T>
bool yamlScalar(const YAML::Node& root, const std::string& path, const std::string& key, const std::string& expected,
                T* value, std::string* why)
{
  const YAML::Node node = root[key];
  if (!node.IsScalar())
  {
    *why = "parameter file '" + path + "': " + typeError(key, expected);
    return false;
  }
  try
  {
    *value = node.as<T>();
  }
  catch (const YAML::Exception&)
  {
    *why = "parameter file '" + path + "': " + typeError(key, expected) + ", got '" + node.Scalar() + "'";
    return false;
  }
  return true;
}
}  // namespace

bool YamlParameterSource::getBool(const std::string& key, bool* value, std::string* why) const
{
  return yamlScalar(root_, path_, key, "true or false", value, why);
}

bool YamlParameterSource::getInt(const std::string& key, int* value, std::string* why) const
{
  return yamlScalar(root_, path_, key, "an integer", value, why);
}

bool YamlParameterSource::getDouble(const std::string& key, double* value, std::string* why) const
{
  return yamlScalar(root_, path_, key, "a number", value, why);
}

bool YamlParameterSource::getString(const std::string& key, std::string* value, std::string* why) const
{
  return yamlScalar(root_, path_, key, "a string", value, why);
}

}  // namespace periodic_bias_compensation
