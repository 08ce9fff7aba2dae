#include "periodic_bias_compensation/gap/csv.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

#include "periodic_bias_compensation/common/numeric.h"

namespace periodic_bias_compensation::gap
{
namespace
{
constexpr std::size_t kMinDataLines = 200;
const std::array<const char*, 6> kImuKeys = { "ax", "ay", "az", "gx", "gy", "gz" };
const std::array<const char*, 7> kTruthKeys = { "px", "py", "pz", "qw", "qx", "qy", "qz" };
const std::array<const char*, 3> kAngleKeys = { "roll", "pitch", "yaw" };
const char* const kValidKeys = "t, ax, ay, az, gx, gy, gz, temp, px, py, pz, qw, qx, qy, qz, roll, pitch, yaw";

bool validKey(const std::string& key)
{
  if (key == "t" || key == "temp")
    return true;
  const auto is = [&key](const char* k) { return key == k; };
  return std::any_of(kImuKeys.begin(), kImuKeys.end(), is) || std::any_of(kTruthKeys.begin(), kTruthKeys.end(), is) ||
         std::any_of(kAngleKeys.begin(), kAngleKeys.end(), is);
}

std::string trim(const std::string& s)
{
  const auto a = s.find_first_not_of(" \t\r");
  const auto b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

/// Fields of a line; ' ' splits on runs of blanks, any other separator outside double quotes.
std::vector<std::string> split(const std::string& line, char separator)
{
  std::vector<std::string> fields;
  if (separator == ' ')
  {
    std::istringstream in(line);
    std::string field;
    while (in >> field)
      fields.push_back(field);
    return fields;
  }
  std::string current;
  bool quoted = false;
  for (char c : line)
  {
    if (c == '"')
      quoted = !quoted;
    else if (c == separator && !quoted)
    {
      fields.push_back(trim(current));
      current.clear();
    }
    else
      current += c;
  }
  fields.push_back(trim(current));
  return fields;
}

std::string listed(const std::vector<std::string>& names)
{
  std::string out;
  for (const std::string& name : names)
    out += (out.empty() ? "" : ", ") + (name.empty() ? std::string("(unnamed)") : name);
  return out;
}

struct Column
{
  std::size_t index = 0;
  double sign = 1.0;
};

/// key -> column, from "key=COLUMN,..." against the header's names.
std::map<std::string, Column> parseColumns(const CsvOptions& o, const std::vector<std::string>& header)
{
  std::map<std::string, Column> columns;
  for (const std::string& item : split(o.columns, ','))
  {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw CsvOptionError("--columns item '" + item + "' is not key=column");
    const std::string key = trim(item.substr(0, eq));
    if (!validKey(key))
      throw CsvOptionError("--columns: unknown key '" + key + "' (keys: " + kValidKeys + ")");
    if (columns.count(key))
      throw CsvOptionError("--columns: key '" + key + "' given twice");
    std::string name = trim(item.substr(eq + 1));
    Column column;
    if (!name.empty() && name[0] == '-')
    {
      column.sign = -1.0;
      name = name.substr(1);
    }
    const auto named = std::find(header.begin(), header.end(), name);
    if (named != header.end())
      column.index = static_cast<std::size_t>(named - header.begin());
    else if (!name.empty() && name.size() < 6 && std::all_of(name.begin(), name.end(), ::isdigit))
    {
      column.index = std::stoul(name);
      if (column.index >= header.size())
        throw CsvOptionError("--columns: " + key + "=" + name + ": " + o.path + " has " +
                             std::to_string(header.size()) + " columns (0 to " + std::to_string(header.size() - 1) +
                             "): " + listed(header));
    }
    else
      throw CsvOptionError("--columns: no column '" + name + "' in " + o.path + "; its columns: " + listed(header));
    columns[key] = column;
  }
  for (const char* key : kImuKeys)
    if (!columns.count(key))
      throw CsvOptionError(std::string("--columns needs ") + key + " (keys: " + kValidKeys + ")");
  if (!columns.count("t") && !(o.rate > 0.0))
    throw CsvOptionError("without a t column, --rate is required");
  const auto truth =
      std::count_if(kTruthKeys.begin(), kTruthKeys.end(), [&](const char* k) { return columns.count(k) > 0; });
  if (truth != 0 && truth != static_cast<long>(kTruthKeys.size()))
    throw CsvOptionError("--columns: truth needs all of px,py,pz,qw,qx,qy,qz");
  const auto angles =
      std::count_if(kAngleKeys.begin(), kAngleKeys.end(), [&](const char* k) { return columns.count(k) > 0; });
  if (angles != 0 && angles != static_cast<long>(kAngleKeys.size()))
    throw CsvOptionError("--columns: the orientation needs all of roll,pitch,yaw");
  return columns;
}

/// The rate and the gravity checks of readCsv (their messages say what to pass instead).
void checkUnits(const Recording& r, const std::string& path)
{
  const double rate = estimateRate(r);
  if (!(rate >= 0.5 && rate <= 2e4))
  {
    std::ostringstream why;
    why << path << ": the stamps give " << rate << " Hz, no IMU's rate: is the time column in s? (--time-scale, e.g. "
        << "1e-3 for ms, 1e-6 for us)";
    throw std::runtime_error(why.str());
  }
  std::vector<double> magnitude(r.size());
  for (std::size_t i = 0; i < r.size(); ++i)
    magnitude[i] = r.data.row(static_cast<Eigen::Index>(i)).head<3>().norm();
  const double g = median(magnitude);
  std::ostringstream why;
  why << path << ": the median specific force is " << g << " m/s^2, not gravity's 9.8: ";
  if (g >= 0.5 && g <= 2.0)
    why << "the accelerations look like g (--accel-scale 9.80665)";
  else if (g >= 500.0 && g <= 2000.0)
    why << "the accelerations look like mg (--accel-scale 0.00980665)";
  else if (g < 0.5)
    why << "gravity looks removed (the diagnosis needs the specific force, gravity included)";
  else if (g > 20.0 || g < 5.0)
    why << "check the accelerometer columns and --accel-scale";
  else
    return;
  throw std::runtime_error(why.str());
}
}  // namespace

char detectDelimiter(const std::string& header)
{
  std::map<char, int> count{ { ',', 0 }, { ';', 0 }, { '\t', 0 } };
  bool quoted = false;
  for (char c : header)
  {
    if (c == '"')
      quoted = !quoted;
    else if (!quoted && count.count(c))
      ++count[c];
  }
  const auto best =
      std::max_element(count.begin(), count.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  return best->second > 0 ? best->first : ' ';
}

Recording readCsv(const CsvOptions& o)
{
  std::ifstream in(o.path);
  if (!in)
    throw std::runtime_error("cannot read " + o.path);
  Recording r;
  r.source = o.path;
  std::string line;
  for (int i = 0; i < o.skip_lines && std::getline(in, line); ++i)
  {
  }
  if (!std::getline(in, line))
    throw std::runtime_error(o.path + ": no header line");
  const char separator = detectDelimiter(line);
  const std::map<std::string, Column> columns = parseColumns(o, split(line, separator));
  const auto has = [&columns](const char* key) { return columns.count(key) > 0; };
  const auto value = [&columns](const std::vector<std::string>& fields, const char* key) {
    const Column& c = columns.at(key);
    return c.sign * std::stod(fields.at(c.index));
  };
  const bool has_truth = has("px") && o.use_truth;
  r.has_orientation = has("roll");
  // x forward, y left, z up from x forward, y right, z down; ENU from NED.
  const Eigen::Vector3d flip = o.ned ? Eigen::Vector3d(1.0, -1.0, -1.0) : Eigen::Vector3d::Ones();
  const Eigen::Quaterniond down_up(Eigen::AngleAxisd(o.ned ? M_PI : 0.0, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond enu_ned =
      o.ned ? Eigen::Quaterniond(Eigen::Matrix3d((Eigen::Matrix3d() << 0, 1, 0, 1, 0, 0, 0, 0, -1).finished()))
            : Eigen::Quaterniond::Identity();

  std::vector<std::array<double, 6>> rows;
  std::size_t k = 0;
  while (std::getline(in, line))
  {
    const std::vector<std::string> fields = split(line, separator);
    try
    {
      std::array<double, 6> v;
      for (int c = 0; c < 6; ++c)
        v[c] = value(fields, kImuKeys[c]) * (c < 3 ? o.accel_scale : o.gyro_scale) * flip[c % 3];
      const double t = has("t") ? value(fields, "t") * o.time_scale : k / o.rate;
      const double temperature = has("temp") ? value(fields, "temp") : 0.0;
      if (!std::isfinite(t) || !std::all_of(v.begin(), v.end(), [](double a) { return std::isfinite(a); }))
        continue;
      Eigen::Quaterniond reported = Eigen::Quaterniond::Identity();
      if (r.has_orientation)
      {
        const double roll = value(fields, "roll"), pitch = value(fields, "pitch"), yaw = value(fields, "yaw");
        if (!std::isfinite(roll + pitch + yaw))
          continue;
        const Eigen::Quaterniond world_sensor = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
        reported = (enu_ned * world_sensor * down_up).normalized();
      }
      if (has_truth)
      {
        double q[7];
        for (int j = 0; j < 7; ++j)
          q[j] = value(fields, kTruthKeys[j]) * (j < 3 ? o.truth_position_scale : 1.0);
        const Eigen::Quaterniond orientation(q[3], q[4], q[5], q[6]);
        if (!(orientation.norm() > 0.5))
          continue;
        r.truth.stamp.push_back(t);
        r.truth.position.emplace_back(q[0], q[1], q[2]);
        r.truth.orientation.push_back(orientation.normalized());
      }

      rows.push_back(v);
      if (r.has_orientation)
        r.orientation.push_back(reported);
      r.stamp.push_back(t);
      r.temperature.push_back(temperature);
      ++k;
    }
    catch (const std::exception&)
    {
      continue;  // not a data line
    }
  }
  if (rows.size() < kMinDataLines)
    throw std::runtime_error(o.path + ": only " + std::to_string(rows.size()) + " data lines (at least " +
                             std::to_string(kMinDataLines) + " needed; delimiter '" +
                             (separator == '\t'  ? std::string("tab")
                              : separator == ' ' ? "blanks"
                                                 : std::string(1, separator)) +
                             "')");
  r.data.resize(static_cast<Eigen::Index>(rows.size()), kChannels);
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (int c = 0; c < 6; ++c)
      r.data(static_cast<Eigen::Index>(i), c) = rows[i][c];
  r.has_temperature = has("temp");
  if (!r.has_temperature)
    r.temperature.clear();
  if (o.rate > 0)
    r.rate = o.rate;
  checkUnits(r, o.path);
  return r;
}

}  // namespace periodic_bias_compensation::gap
