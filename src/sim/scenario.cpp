#include "periodic_bias_compensation/sim/scenario.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "periodic_bias_compensation/sim/effects.h"

namespace periodic_bias_compensation::sim
{
namespace
{
// A YAML mapping whose keys must all be read: finish() rejects the others.
class Mapping
{
public:
  Mapping(const YAML::Node& node, std::string path) : node_(node), path_(std::move(path))
  {
    if (!node_.IsMap())
    {
      throw std::runtime_error(label() + "must be a mapping");
    }
  }

  bool has(const std::string& key)
  {
    used_.insert(key);
    return static_cast<bool>(node_[key]);
  }

  YAML::Node get(const std::string& key)
  {
    used_.insert(key);
    return node_[key];
  }

  std::string path(const std::string& key) const
  {
    return path_.empty() ? key : path_ + "." + key;
  }

  void number(const std::string& key, double* value)
  {
    if (has(key))
    {
      *value = toNumber(get(key), path(key));
    }
  }

  void text(const std::string& key, std::string* value)
  {
    if (has(key))
    {
      try
      {
        *value = get(key).as<std::string>();
      }
      catch (const YAML::Exception&)
      {
        throw std::runtime_error("key '" + path(key) + "': expected a string");
      }
    }
  }

  void flag(const std::string& key, bool* value)
  {
    if (has(key))
    {
      try
      {
        *value = get(key).as<bool>();
      }
      catch (const YAML::Exception&)
      {
        throw std::runtime_error("key '" + path(key) + "': expected true or false");
      }
    }
  }

  void vector3(const std::string& key, Vector3* value)
  {
    if (has(key))
    {
      const std::vector<double> v = toNumbers(get(key), path(key));
      if (v.size() != 3)
      {
        throw std::runtime_error("key '" + path(key) + "': expected a list of 3 numbers");
      }
      *value = Vector3(v[0], v[1], v[2]);
    }
  }

  void finish() const
  {
    for (const auto& kv : node_)
    {
      const std::string key = kv.first.as<std::string>();
      if (used_.count(key) == 0)
      {
        throw std::runtime_error("unknown key '" + path(key) + "'");
      }
    }
  }

  static double toNumber(const YAML::Node& node, const std::string& path)
  {
    try
    {
      if (!node.IsScalar())
      {
        throw YAML::Exception(YAML::Mark::null_mark(), "not a scalar");
      }
      return node.as<double>();
    }
    catch (const YAML::Exception&)
    {
      throw std::runtime_error("key '" + path + "': expected a number");
    }
  }

  static std::vector<double> toNumbers(const YAML::Node& node, const std::string& path)
  {
    if (node.IsSequence())
    {
      std::vector<double> out;
      for (std::size_t i = 0; i < node.size(); ++i)
      {
        out.push_back(toNumber(node[i], path + "[" + std::to_string(i) + "]"));
      }
      return out;
    }
    return { toNumber(node, path) };
  }

private:
  std::string label() const
  {
    return path_.empty() ? "document " : "key '" + path_ + "' ";
  }

  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

YAML::Node sequence(Mapping& m, const std::string& key)
{
  const YAML::Node node = m.get(key);
  if (!node.IsSequence())
  {
    throw std::runtime_error("key '" + m.path(key) + "': expected a list");
  }
  return node;
}

void check(const std::string& key, double value, double lo, double hi, const std::string& unit, bool open_low = false)
{
  if (!std::isfinite(value) || value < lo || value > hi || (open_low && value == lo))
  {
    std::ostringstream os;
    os << "key '" << key << "': value " << value << " outside " << (open_low ? "(" : "[") << lo << ", " << hi << "] "
       << unit;
    throw std::runtime_error(os.str());
  }
}

// Shortest decimal text that reads back to the same double.
std::string shortest(double x)
{
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), x);
  return std::string(buffer.data(), result.ptr);
}

MotionType motionType(const std::string& name, const std::string& key)
{
  for (const MotionType t : { MotionType::kStatic, MotionType::kSinusoids, MotionType::kSea, MotionType::kRoute })
  {
    if (toString(t) == name)
    {
      return t;
    }
  }
  throw std::runtime_error("key '" + key + "': unknown motion type '" + name + "' (static, sinusoids, sea, route)");
}

void parseSinusoids(Mapping& motion, Motion* out)
{
  Mapping m(motion.get("sinusoids"), motion.path("sinusoids"));
  for (int j = 0; j < 6; ++j)
  {
    const std::string& dof = dofNames()[j];
    if (m.has(dof))
    {
      Mapping s(m.get(dof), m.path(dof));
      s.number("amplitude", &out->sinusoids[j].amplitude);
      s.number("frequency", &out->sinusoids[j].frequency);
      s.number("phase", &out->sinusoids[j].phase);
      s.finish();
    }
  }
  m.finish();
}

void parseSea(Mapping& motion, Sea* out)
{
  Mapping m(motion.get("sea"), motion.path("sea"));
  double components = out->components;
  m.number("components", &components);
  if (components != std::floor(components) || components < 1 || components > 5000)
  {
    throw std::runtime_error("key '" + m.path("components") + "': expected an integer in [1, 5000]");
  }
  out->components = static_cast<int>(components);
  m.number("length", &out->length);
  m.number("response_coherence", &out->response_coherence);
  if (m.has("response"))
  {
    Mapping r(m.get("response"), m.path("response"));
    for (int j = 0; j < 6; ++j)
    {
      r.number(dofNames()[j], &out->response[j]);
    }
    r.finish();
  }
  if (m.has("systems"))
  {
    const YAML::Node list = sequence(m, "systems");
    for (std::size_t i = 0; i < list.size(); ++i)
    {
      Mapping w(list[i], m.path("systems") + "[" + std::to_string(i) + "]");
      WaveSystem system;
      w.text("spectrum", &system.spectrum);
      w.number("significant_height", &system.significant_height);
      w.number("peak_period", &system.peak_period);
      w.number("gamma", &system.gamma);
      w.number("direction", &system.direction);
      w.number("spreading", &system.spreading);
      w.finish();
      out->systems.push_back(system);
    }
  }
  m.finish();
}

void parseRoute(Mapping& motion, Route* out)
{
  Mapping m(motion.get("route"), motion.path("route"));
  m.number("turn_rate", &out->turn_rate);
  m.number("acceleration", &out->acceleration);
  if (m.has("legs"))
  {
    const YAML::Node list = sequence(m, "legs");
    for (std::size_t i = 0; i < list.size(); ++i)
    {
      Mapping l(list[i], m.path("legs") + "[" + std::to_string(i) + "]");
      RouteLeg leg;
      l.number("heading", &leg.heading);
      l.number("speed", &leg.speed);
      l.number("duration", &leg.duration);
      l.finish();
      out->legs.push_back(leg);
    }
  }
  m.finish();
}

Motion parseMotion(Mapping& doc)
{
  Motion out;
  Mapping m(doc.get("motion"), "motion");
  std::string type = toString(out.type);
  m.text("type", &type);
  out.type = motionType(type, "motion.type");
  m.vector3("position", &out.position);
  m.number("heading", &out.heading);
  m.number("roll", &out.roll);
  m.number("pitch", &out.pitch);
  const auto allowed = [&](const std::string& key, bool ok) {
    if (m.has(key) && !ok)
    {
      throw std::runtime_error("key '" + m.path(key) + "': not used by motion.type " + type);
    }
    return m.has(key);
  };
  if (allowed("speed", out.type != MotionType::kStatic))
  {
    m.number("speed", &out.speed);
  }
  if (allowed("sinusoids", out.type == MotionType::kSinusoids))
  {
    parseSinusoids(m, &out);
  }
  if (allowed("sea", out.type == MotionType::kSea || out.type == MotionType::kRoute))
  {
    parseSea(m, &out.sea);
  }
  if (allowed("route", out.type == MotionType::kRoute))
  {
    parseRoute(m, &out.route);
  }
  m.finish();
  return out;
}

TemperatureProfile parseTemperature(Mapping& doc)
{
  TemperatureProfile out;
  out.enabled = true;
  Mapping m(doc.get("temperature"), "temperature");
  m.number("mean", &out.mean);
  m.number("amplitude", &out.amplitude);
  m.number("period", &out.period);
  m.number("phase", &out.phase);
  m.finish();
  return out;
}

std::vector<EffectSpec> parseEffects(Mapping& doc)
{
  std::vector<EffectSpec> out;
  const YAML::Node list = sequence(doc, "effects");
  for (std::size_t i = 0; i < list.size(); ++i)
  {
    const std::string where = "effects[" + std::to_string(i) + "]";
    Mapping m(list[i], where);
    EffectSpec spec;
    if (!m.has("name"))
    {
      throw std::runtime_error("key '" + m.path("name") + "': missing (effect name)");
    }
    m.text("name", &spec.name);
    m.flag("enabled", &spec.enabled);
    for (const auto& kv : list[i])
    {
      const std::string key = kv.first.as<std::string>();
      if (key != "name" && key != "enabled")
      {
        spec.params[key] = Mapping::toNumbers(kv.second, m.path(key));
      }
    }
    out.push_back(spec);
  }
  return out;
}

Scenario parse(const YAML::Node& root)
{
  Scenario s;
  Mapping doc(root, "");
  doc.text("name", &s.name);
  doc.text("description", &s.description);
  doc.number("rate", &s.rate);
  doc.number("duration", &s.duration);
  doc.number("start_time", &s.start_time);
  double seed = static_cast<double>(s.seed);
  doc.number("seed", &seed);
  if (seed < 0 || seed > 9.0e15 || seed != std::floor(seed))
  {
    throw std::runtime_error("key 'seed': expected an integer in [0, 9e15]");
  }
  s.seed = static_cast<std::uint64_t>(seed);
  doc.number("gravity", &s.gravity);
  doc.number("orientation_stddev", &s.orientation_stddev);
  if (doc.has("motion"))
  {
    s.motion = parseMotion(doc);
  }
  if (doc.has("temperature"))
  {
    s.temperature = parseTemperature(doc);
  }
  if (doc.has("effects"))
  {
    s.effects = parseEffects(doc);
  }
  doc.finish();
  return s;
}
}  // namespace

const std::array<std::string, 6>& dofNames()
{
  static const std::array<std::string, 6> names{ { "surge", "sway", "heave", "roll", "pitch", "yaw" } };
  return names;
}

std::string toString(MotionType type)
{
  switch (type)
  {
    case MotionType::kStatic:
      return "static";
    case MotionType::kSinusoids:
      return "sinusoids";
    case MotionType::kSea:
      return "sea";
    case MotionType::kRoute:
      return "route";
  }
  return "static";
}

void validateScenario(const Scenario& s)
{
  check("rate", s.rate, 0.0, 1e5, "Hz", true);
  check("duration", s.duration, 0.0, 1e8, "s", true);
  check("start_time", s.start_time, 0.0, 4e9, "s", true);
  check("gravity", s.gravity, 0.0, 100.0, "m/s^2", true);
  check("orientation_stddev", s.orientation_stddev, 0.0, 3.2, "rad");
  const Motion& m = s.motion;
  for (int i = 0; i < 3; ++i)
  {
    check("motion.position", m.position[i], -1e8, 1e8, "m");
  }
  check("motion.heading", m.heading, -10.0, 10.0, "rad");
  check("motion.roll", m.roll, -1.5, 1.5, "rad");
  check("motion.pitch", m.pitch, -1.5, 1.5, "rad");
  check("motion.speed", m.speed, 0.0, 50.0, "m/s");
  if (m.type == MotionType::kSinusoids)
  {
    for (int j = 0; j < 6; ++j)
    {
      const std::string key = "motion.sinusoids." + dofNames()[j];
      const bool angle = j >= kRoll;
      check(key + ".amplitude", m.sinusoids[j].amplitude, 0.0, angle ? 1.5 : 1000.0, angle ? "rad" : "m");
      check(key + ".frequency", m.sinusoids[j].frequency, 0.0, 0.5 * s.rate, "Hz (below rate / 2)");
      check(key + ".phase", m.sinusoids[j].phase, -100.0, 100.0, "rad");
    }
  }
  if (m.type == MotionType::kSea || m.type == MotionType::kRoute)
  {
    if (m.type == MotionType::kSea && m.sea.systems.empty())
    {
      throw std::runtime_error("key 'motion.sea.systems': motion.type sea needs at least one wave system");
    }
    check("motion.sea.components", m.sea.components, 1, 5000, "");
    check("motion.sea.length", m.sea.length, 0.0, 500.0, "m");
    check("motion.sea.response_coherence", m.sea.response_coherence, 0.0, 1.0, "-");
    for (int j = 0; j < 6; ++j)
    {
      check("motion.sea.response." + dofNames()[j], m.sea.response[j], 0.0, 10.0, "-");
    }
    for (std::size_t i = 0; i < m.sea.systems.size(); ++i)
    {
      const WaveSystem& w = m.sea.systems[i];
      const std::string key = "motion.sea.systems[" + std::to_string(i) + "]";
      if (w.spectrum != "jonswap" && w.spectrum != "pierson_moskowitz")
      {
        throw std::runtime_error("key '" + key + ".spectrum': unknown spectrum '" + w.spectrum +
                                 "' (jonswap, pierson_moskowitz)");
      }
      check(key + ".significant_height", w.significant_height, 0.0, 30.0, "m");
      check(key + ".peak_period", w.peak_period, 1.0, 40.0, "s");
      check(key + ".gamma", w.gamma, 1.0, 10.0, "-");
      check(key + ".direction", w.direction, -10.0, 10.0, "rad");
      check(key + ".spreading", w.spreading, 0.0, 3.2, "rad");
      check(key + ".peak_period", 2.0 * M_PI * 4.0 / w.peak_period, 0.0, M_PI * s.rate,
            "rad/s (4 x peak frequency must stay below rate / 2: peak_period too short for rate)");
    }
  }
  if (m.type == MotionType::kRoute)
  {
    if (m.route.legs.empty())
    {
      throw std::runtime_error("key 'motion.route.legs': motion.type route needs at least one leg");
    }
    check("motion.route.turn_rate", m.route.turn_rate, 0.0, 1.0, "rad/s", true);
    check("motion.route.acceleration", m.route.acceleration, 0.0, 10.0, "m/s^2", true);
    for (std::size_t i = 0; i < m.route.legs.size(); ++i)
    {
      const std::string key = "motion.route.legs[" + std::to_string(i) + "]";
      check(key + ".heading", m.route.legs[i].heading, -10.0, 10.0, "rad");
      check(key + ".speed", m.route.legs[i].speed, 0.0, 50.0, "m/s");
      check(key + ".duration", m.route.legs[i].duration, 0.0, 1e8, "s");
    }
  }
  if (s.temperature.enabled)
  {
    check("temperature.mean", s.temperature.mean, -100.0, 200.0, "degC");
    check("temperature.amplitude", s.temperature.amplitude, 0.0, 200.0, "K");
    check("temperature.period", s.temperature.period, 0.0, 1e9, "s", true);
    check("temperature.phase", s.temperature.phase, -100.0, 100.0, "rad");
  }
  for (std::size_t i = 0; i < s.effects.size(); ++i)
  {
    const std::string where = "effects[" + std::to_string(i) + "]";
    const EffectSpec e = completeEffect(s.effects[i], where);
    try
    {
      makeEffect(e, 0, s.rate);
    }
    catch (const std::runtime_error& error)
    {
      throw std::runtime_error("key '" + where + "' (" + s.effects[i].name + "): " + error.what());
    }
    if (e.enabled && e.name == "thermal_drift" && !s.temperature.enabled)
    {
      throw std::runtime_error("key '" + where + "' (thermal_drift): needs a 'temperature' profile");
    }
  }
}

std::string toYaml(const Scenario& s)
{
  YAML::Emitter out;
  const auto seq = [&out](const std::vector<double>& v) {
    out << YAML::Flow << YAML::BeginSeq;
    for (const double x : v)
    {
      out << shortest(x);
    }
    out << YAML::EndSeq;
  };
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << s.name;
  out << YAML::Key << "description" << YAML::Value << s.description;
  out << YAML::Key << "rate" << YAML::Value << shortest(s.rate);
  out << YAML::Key << "duration" << YAML::Value << shortest(s.duration);
  out << YAML::Key << "start_time" << YAML::Value << shortest(s.start_time);
  out << YAML::Key << "seed" << YAML::Value << s.seed;
  out << YAML::Key << "gravity" << YAML::Value << shortest(s.gravity);
  out << YAML::Key << "orientation_stddev" << YAML::Value << shortest(s.orientation_stddev);

  const Motion& m = s.motion;
  out << YAML::Key << "motion" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "type" << YAML::Value << toString(m.type);
  out << YAML::Key << "position" << YAML::Value;
  seq({ m.position.x(), m.position.y(), m.position.z() });
  out << YAML::Key << "heading" << YAML::Value << shortest(m.heading);
  out << YAML::Key << "roll" << YAML::Value << shortest(m.roll);
  out << YAML::Key << "pitch" << YAML::Value << shortest(m.pitch);
  if (m.type != MotionType::kStatic)
  {
    out << YAML::Key << "speed" << YAML::Value << shortest(m.speed);
  }
  if (m.type == MotionType::kSinusoids)
  {
    out << YAML::Key << "sinusoids" << YAML::Value << YAML::BeginMap;
    for (int j = 0; j < 6; ++j)
    {
      out << YAML::Key << dofNames()[j] << YAML::Value << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "amplitude" << YAML::Value << shortest(m.sinusoids[j].amplitude);
      out << YAML::Key << "frequency" << YAML::Value << shortest(m.sinusoids[j].frequency);
      out << YAML::Key << "phase" << YAML::Value << shortest(m.sinusoids[j].phase);
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  if (m.type == MotionType::kSea || m.type == MotionType::kRoute)
  {
    out << YAML::Key << "sea" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "components" << YAML::Value << m.sea.components;
    out << YAML::Key << "length" << YAML::Value << shortest(m.sea.length);
    out << YAML::Key << "response" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (int j = 0; j < 6; ++j)
    {
      out << YAML::Key << dofNames()[j] << YAML::Value << shortest(m.sea.response[j]);
    }
    out << YAML::EndMap;
    out << YAML::Key << "response_coherence" << YAML::Value << shortest(m.sea.response_coherence);
    out << YAML::Key << "systems" << YAML::Value << YAML::BeginSeq;
    for (const WaveSystem& w : m.sea.systems)
    {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "spectrum" << YAML::Value << w.spectrum;
      out << YAML::Key << "significant_height" << YAML::Value << shortest(w.significant_height);
      out << YAML::Key << "peak_period" << YAML::Value << shortest(w.peak_period);
      out << YAML::Key << "gamma" << YAML::Value << shortest(w.gamma);
      out << YAML::Key << "direction" << YAML::Value << shortest(w.direction);
      out << YAML::Key << "spreading" << YAML::Value << shortest(w.spreading);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  if (m.type == MotionType::kRoute)
  {
    out << YAML::Key << "route" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "turn_rate" << YAML::Value << shortest(m.route.turn_rate);
    out << YAML::Key << "acceleration" << YAML::Value << shortest(m.route.acceleration);
    out << YAML::Key << "legs" << YAML::Value << YAML::BeginSeq;
    for (const RouteLeg& leg : m.route.legs)
    {
      out << YAML::Flow << YAML::BeginMap;
      out << YAML::Key << "heading" << YAML::Value << shortest(leg.heading);
      out << YAML::Key << "speed" << YAML::Value << shortest(leg.speed);
      out << YAML::Key << "duration" << YAML::Value << shortest(leg.duration);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndMap;

  if (s.temperature.enabled)
  {
    out << YAML::Key << "temperature" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "mean" << YAML::Value << shortest(s.temperature.mean);
    out << YAML::Key << "amplitude" << YAML::Value << shortest(s.temperature.amplitude);
    out << YAML::Key << "period" << YAML::Value << shortest(s.temperature.period);
    out << YAML::Key << "phase" << YAML::Value << shortest(s.temperature.phase);
    out << YAML::EndMap;
  }
  out << YAML::Key << "effects" << YAML::Value << YAML::BeginSeq;
  for (const EffectSpec& e : s.effects)
  {
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << e.name;
    out << YAML::Key << "enabled" << YAML::Value << e.enabled;
    for (const auto& [key, values] : e.params)
    {
      out << YAML::Key << key << YAML::Value;
      seq(values);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

Scenario parseScenario(const std::string& text, const std::string& origin)
{
  try
  {
    const Scenario s = parse(YAML::Load(text));
    validateScenario(s);
    return s;
  }
  catch (const YAML::Exception& e)
  {
    throw std::runtime_error(origin + ": YAML error: " + e.what());
  }
  catch (const std::runtime_error& e)
  {
    throw std::runtime_error(origin + ": " + e.what());
  }
}

Scenario loadScenario(const std::string& path)
{
  std::ifstream in(path);
  if (!in)
  {
    throw std::runtime_error(path + ": cannot open scenario file");
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parseScenario(buffer.str(), path);
}

std::int64_t sampleCount(const Scenario& scenario)
{
  return static_cast<std::int64_t>(std::ceil(scenario.duration * scenario.rate - 1e-6));
}

EffectSpec* findEffect(Scenario& scenario, const std::string& name)
{
  for (EffectSpec& e : scenario.effects)
  {
    if (e.name == name)
    {
      return &e;
    }
  }
  return nullptr;
}

const EffectSpec* findEffect(const Scenario& scenario, const std::string& name)
{
  for (const EffectSpec& e : scenario.effects)
  {
    if (e.name == name)
    {
      return &e;
    }
  }
  return nullptr;
}

bool setEffectEnabled(Scenario& scenario, const std::string& name, bool enabled)
{
  bool found = false;
  for (EffectSpec& e : scenario.effects)
  {
    if (e.name == name)
    {
      e.enabled = enabled;
      found = true;
    }
  }
  return found;
}
}  // namespace periodic_bias_compensation::sim
