#include "periodic_bias_compensation/core/calibration_file.h"

#include <cmath>
#include <ctime>
#include <fstream>

#include <yaml-cpp/yaml.h>

#include "periodic_bias_compensation/core/compensator.h"

namespace periodic_bias_compensation
{
bool loadCalibration(const std::string& path, Eigen::Vector3d* bias, std::string* why)
{
  auto fail = [&](const std::string& message) {
    if (why)
      *why = path + ": " + message;
    return false;
  };
  YAML::Node root;
  try
  {
    root = YAML::LoadFile(path);
  }
  catch (const std::exception& e)
  {
    return fail(std::string("cannot read calibration file (") + e.what() + ")");
  }
  if (!root.IsMap())
    return fail("expected a map with the key 'constant_bias' (constant_bias: [bx, by, bz] in m/s^2)");
  const YAML::Node node = root["constant_bias"];
  if (!node)
    return fail("key 'constant_bias' missing (expected constant_bias: [bx, by, bz] in m/s^2)");
  if (!node.IsSequence() || node.size() != 3)
    return fail("key 'constant_bias' must be a list of 3 numbers [m/s^2]");
  Eigen::Vector3d value;
  for (int i = 0; i < 3; ++i)
  {
    try
    {
      value[i] = node[i].as<double>();
    }
    catch (const std::exception&)
    {
      return fail("key 'constant_bias' element " + std::to_string(i) + " is not a number");
    }
    if (!std::isfinite(value[i]) || std::abs(value[i]) > kMaxConstantBias)
      return fail("key 'constant_bias' element " + std::to_string(i) + " must be finite and within +-" +
                  std::to_string(static_cast<int>(kMaxConstantBias)) + " m/s^2");
  }
  *bias = value;
  return true;
}

bool saveCalibration(const std::string& path, const Eigen::Vector3d& bias, std::string* why)
{
  if (!bias.allFinite())
  {
    if (why)
      *why = "refusing to save a non-finite bias";
    return false;
  }
  const std::string temporary = path + ".tmp";
  {
    std::ofstream file(temporary);
    if (!file)
    {
      if (why)
        *why = path + ": cannot write calibration file";
      return false;
    }
    const std::time_t now = std::time(nullptr);
    char stamp[64];
    std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
    file.precision(17);
    file << "# Constant accelerometer bias in the level ENU frame [m/s^2], periodic_bias_compensation\n"
         << "# written " << stamp << "\n"
         << "constant_bias: [" << bias.x() << ", " << bias.y() << ", " << bias.z() << "]\n";
    if (!file)
    {
      if (why)
        *why = path + ": write failed";
      return false;
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
  {
    if (why)
      *why = path + ": cannot replace the file";
    return false;
  }
  return true;
}
}  // namespace periodic_bias_compensation
