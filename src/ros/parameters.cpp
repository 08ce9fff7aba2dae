#include "periodic_bias_compensation/ros/parameters.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace periodic_bias_compensation
{
namespace
{
std::string typeError(const std::string& key, const std::string& expected)
{
  return "parameter '" + key + "': expected " + expected;
}

/// Reads a present key as a value of `type`.
bool readValue(const ParameterSource& source, const std::string& key, ParameterType type, ParameterValue* value,
               std::string* why)
{
  switch (type)
  {
    case ParameterType::kBool:
      return source.getBool(key, &value->emplace<bool>(), why);
    case ParameterType::kInt:
      return source.getInt(key, &value->emplace<int>(), why);
    case ParameterType::kDouble:
      return source.getDouble(key, &value->emplace<double>(), why);
    case ParameterType::kString:
      return source.getString(key, &value->emplace<std::string>(), why);
  }
  return false;
}

/// Reads `key` into *config when it is one of `table`'s keys; *found tells whether it is.
template <class Config>
bool readKey(const ParameterSource& source, const std::string& key, const ParameterTable<Config>& table, Config* config,
             bool* found, std::string* why)
{
  const Parameter<Config>* parameter = findParameter(table, key);
  *found = parameter != nullptr;
  if (parameter == nullptr)
    return true;
  ParameterValue value;
  std::string message;
  if (!readValue(source, key, parameter->type, &value, why))
    return false;
  if (!assign(*parameter, value, config, &message))
  {
    *why = "parameter '" + key + "': " + message;
    return false;
  }
  return true;
}

ParameterValue valueOf(const dynamic_reconfigure::BoolParameter& entry)
{
  return entry.value != 0;
}
ParameterValue valueOf(const dynamic_reconfigure::IntParameter& entry)
{
  return static_cast<int>(entry.value);
}
ParameterValue valueOf(const dynamic_reconfigure::DoubleParameter& entry)
{
  return static_cast<double>(entry.value);
}
ParameterValue valueOf(const dynamic_reconfigure::StrParameter& entry)
{
  return entry.value;
}

template <class Entry>
bool applyEntries(const std::vector<Entry>& entries, CompensatorConfig* config, std::string* why)
{
  for (const Entry& entry : entries)
  {
    const Parameter<CompensatorConfig>* parameter = findParameter(compensatorParameters(), entry.name);
    if (parameter == nullptr || !parameter->reconfigurable())
    {
      *why = "'" + entry.name + "' is not a run-time parameter of the compensator";
      return false;
    }
    if (!assign(*parameter, valueOf(entry), config, why))
      return false;
  }
  return true;
}

/// Sets the entry `name` of *entries to `value`, appending it when there is none.
template <class Entry, class T>
void put(std::vector<Entry>* entries, const std::string& name, const T& value)
{
  for (Entry& entry : *entries)
    if (entry.name == name)
    {
      entry.value = value;
      return;
    }
  Entry entry;
  entry.name = name;
  entry.value = value;
  entries->push_back(entry);
}
}  // namespace

const ParameterTable<RosOptions>& rosOptionParameters()
{
  static const ParameterTable<RosOptions> table = [] {
    using R = RosOptions;
    const Reconfigure start = Reconfigure::kStartup;
    ParameterTable<R> t;
    t.push_back(textParameter("calibration_file", &R::calibration_file, start,
                              "constant-bias YAML (constant_bias: [bx, by, bz], m/s^2, level frame): loaded at "
                              "start when it exists, written by ~save_calibration; empty: none",
                              false));
    t.push_back(textParameter("odom_frame", &R::odom_frame, start,
                              "header.frame_id of odometry/*, bias_state and path/* (the level ENU frame)", true));
    t.push_back(textParameter("base_frame", &R::base_frame, start,
                              "child_frame_id of the odometry; the IMU mounting is looked up as imu frame -> "
                              "base_frame",
                              true));
    t.push_back(textParameter("imu_frame", &R::imu_frame, start,
                              "required frame_id of imu/data; empty: that of the first message used", false));
    t.push_back(numberParameter("mount_timeout", &R::mount_timeout, start, atLeast(0.0), "s",
                                "message time to wait for the imu -> base transform before taking the identity"));
    t.push_back(flagParameter("identity_mounting", &R::identity_mounting, start,
                              "the IMU is mounted aligned with base_frame: no transform looked up"));
    t.push_back(flagParameter("publish_tf", &R::publish_tf, start,
                              "broadcast the TF odom_frame -> base_frame from odometry/filtered"));
    t.push_back(numberParameter("path_max_length", &R::path_max_length, start, atLeast(1.0), "-",
                                "poses kept in path/filtered and path/raw"));
    t.push_back(numberParameter("path_rate", &R::path_rate, start, above(0.0), "Hz",
                                "rate of the poses added to path/filtered and path/raw, and of their publication"));
    t.push_back(numberParameter("diagnostic_period", &R::diagnostic_period, start, above(0.0), "s",
                                "period of the /diagnostics status"));
    t.push_back(flagParameter("imu_thread", &R::imu_thread, start,
                              "imu/data served by a thread of its own (named pbc_imu): one thread wake-up per sample, "
                              "where a nodelet manager's queues take two; false: the node handle's callback queue"));
    t.push_back(numberParameter("imu_thread_priority", &R::imu_thread_priority, start, closed(0.0, 99.0), "-",
                                "real-time priority of the pbc_imu thread (SCHED_FIFO, 1-99): it then runs ahead of "
                                "every ordinary thread of the machine; needs CAP_SYS_NICE or an rtprio limit "
                                "(limits.conf), where refused a warning and ordinary scheduling; 0: ordinary"));
    t.push_back(numberParameter("cpu_wakeup_latency", &R::cpu_wakeup_latency, start, closed(-1.0, 1.0), "s",
                                "while the node runs, the longest any CPU of the machine may take to come out of "
                                "idle (Linux PM QoS, /dev/cpu_dma_latency): 0 keeps idle CPUs polling, so a "
                                "sample's threads wake at once, for the power an idle CPU saves; needs write "
                                "access to the device (root, or a udev rule), where refused a warning; "
                                "negative: no request"));
    return t;
  }();
  return table;
}

bool RosOptions::validate(std::string* why) const
{
  if (!checkRanges(rosOptionParameters(), *this, why))
    return false;
  if (odom_frame == base_frame)
  {
    if (why != nullptr)
      *why = "odom_frame and base_frame must differ (both '" + odom_frame + "')";
    return false;
  }
  if (imu_thread_priority > 0 && !imu_thread)
  {
    if (why != nullptr)
      *why = "imu_thread_priority needs imu_thread: true (the priority is that thread's)";
    return false;
  }
  return true;
}

bool readParameters(const ParameterSource& source, Parameters* params, std::string* why)
{
  std::string message;
  const std::vector<std::string> present = source.keys();
  for (const std::string& key : present)
  {
    bool core = false, ros = false;
    if (!readKey(source, key, compensatorParameters(), &params->core, &core, why) ||
        (!core && !readKey(source, key, rosOptionParameters(), &params->ros, &ros, why)))
      return false;
    if (!core && !ros)
    {
      *why = "unknown parameter '" + key + "' (docs/ros_api.md lists the keys)";
      return false;
    }
  }
  if (!params->core.validate(&message, present))
  {
    *why = "invalid parameters: " + message;
    return false;
  }
  if (!params->ros.validate(&message))
  {
    *why = "invalid parameters: " + message;
    return false;
  }
  return true;
}

bool applyTuning(const dynamic_reconfigure::Config& request, CompensatorConfig* config, std::string* why)
{
  return applyEntries(request.bools, config, why) && applyEntries(request.ints, config, why) &&
         applyEntries(request.doubles, config, why) && applyEntries(request.strs, config, why);
}

void toTuning(const CompensatorConfig& config, dynamic_reconfigure::Config* message)
{
  for (const Parameter<CompensatorConfig>& parameter : compensatorParameters())
  {
    if (!parameter.reconfigurable())
      continue;
    const ParameterValue value = parameter.get(config);
    switch (parameter.type)
    {
      case ParameterType::kBool:
        put(&message->bools, parameter.key, std::get<bool>(value));
        break;
      case ParameterType::kInt:
        put(&message->ints, parameter.key, std::get<int>(value));
        break;
      case ParameterType::kDouble:
        put(&message->doubles, parameter.key, std::get<double>(value));
        break;
      case ParameterType::kString:
        put(&message->strs, parameter.key, std::get<std::string>(value));
        break;
    }
  }
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
