#include "periodic_bias_compensation/sim/effects.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

#include "periodic_bias_compensation/sim/random.h"

namespace periodic_bias_compensation::sim
{
namespace
{
constexpr double kTwoPi = 2.0 * M_PI;

std::vector<double> rep(double v, std::size_t n)
{
  return std::vector<double>(n, v);
}

ParamInfo axes(const std::string& name, const std::string& unit, double def, double lo, double hi,
               const std::string& description)
{
  return { name, unit, 3, rep(def, 3), lo, hi, description };
}

ParamInfo scalar(const std::string& name, const std::string& unit, double def, double lo, double hi,
                 const std::string& description)
{
  return { name, unit, 1, { def }, lo, hi, description };
}

ParamInfo matrix(const std::string& name, const std::string& unit, double lo, double hi, const std::string& description)
{
  return { name, unit, 9, rep(0.0, 9), lo, hi, description };
}

ParamInfo list(const std::string& name, const std::string& unit, double lo, double hi, const std::string& description)
{
  return { name, unit, 0, {}, lo, hi, description };
}

std::vector<EffectInfo> buildVocabulary()
{
  std::vector<EffectInfo> v;
  v.push_back({ "lever_arm",
                "sensor mounted at an offset from base_link: adds alpha x r + omega x (omega x r)",
                { axes("offset", "m", 0.0, -100.0, 100.0, "sensor position in base_link") },
                0 });
  v.push_back({ "misalignment",
                "cross-axis coupling: out = (I + M) in",
                { matrix("accel", "rad", -0.5, 0.5, "accelerometer coupling matrix M, row-major"),
                  matrix("gyro", "rad", -0.5, 0.5, "gyro coupling matrix M, row-major") },
                1 });
  v.push_back({ "scale_factor",
                "out = (1 + s) in per axis",
                { axes("accel", "-", 0.0, -0.5, 0.5, "accelerometer scale factor error"),
                  axes("gyro", "-", 0.0, -0.5, 0.5, "gyro scale factor error") },
                2 });
  v.push_back({ "constant_bias",
                "constant offset",
                { axes("accel", "m/s^2", 0.0, -100.0, 100.0, "accelerometer bias"),
                  axes("gyro", "rad/s", 0.0, -10.0, 10.0, "gyro bias") },
                3 });
  v.push_back({ "periodic_bias",
                "b = amplitude * sin(2 pi elapsed / period + phase) per axis",
                { axes("accel_amplitude", "m/s^2", 0.0, 0.0, 100.0, "accelerometer amplitude"),
                  axes("accel_period", "s", 10.0, 1e-3, 1e7, "accelerometer period"),
                  axes("accel_phase", "rad", 0.0, -100.0, 100.0, "accelerometer phase"),
                  axes("gyro_amplitude", "rad/s", 0.0, 0.0, 10.0, "gyro amplitude"),
                  axes("gyro_period", "s", 10.0, 1e-3, 1e7, "gyro period"),
                  axes("gyro_phase", "rad", 0.0, -100.0, 100.0, "gyro phase") },
                3 });
  v.push_back({ "thermal_drift",
                "b = coefficient * (T - reference_temperature); needs the scenario's temperature",
                { axes("accel_coefficient", "m/s^2/K", 0.0, -1.0, 1.0, "accelerometer coefficient"),
                  axes("gyro_coefficient", "rad/s/K", 0.0, -1.0, 1.0, "gyro coefficient"),
                  scalar("reference_temperature", "degC", 20.0, -100.0, 200.0, "temperature of zero thermal bias") },
                3 });
  v.push_back({ "bias_random_walk",
                "b += density * sqrt(dt) * N(0,1) each sample (Allan slope +1/2)",
                { axes("accel_density", "m/s^3/sqrt(Hz)", 0.0, 0.0, 10.0, "accelerometer rate random walk"),
                  axes("gyro_density", "rad/s^2/sqrt(Hz)", 0.0, 0.0, 10.0, "gyro rate random walk") },
                3 });
  v.push_back({ "bias_instability",
                "first-order Gauss-Markov bias, stationary from the start",
                { axes("accel_sigma", "m/s^2", 0.0, 0.0, 100.0, "accelerometer standard deviation"),
                  axes("gyro_sigma", "rad/s", 0.0, 0.0, 10.0, "gyro standard deviation"),
                  scalar("correlation_time", "s", 100.0, 1e-3, 1e9, "correlation time") },
                3 });
  v.push_back({ "vibration",
                "lines sin(2 pi frequency elapsed + phase), sampled as is (lines above rate/2 alias); "
                "a bandwidth widens a line to a Lorentzian by a random walk of its phase",
                { list("frequency", "Hz", 0.0, 1e6, "line frequencies, n values"),
                  list("accel_amplitude", "m/s^2", -100.0, 100.0, "x, y, z per line (3n values)"),
                  list("gyro_amplitude", "rad/s", -10.0, 10.0, "x, y, z per line (3n values)"),
                  list("phase", "rad", -100.0, 100.0, "per line (n values, default 0)"),
                  list("bandwidth", "Hz", 0.0, 1e3, "full width at half maximum per line (n values, default 0)") },
                4 });
  v.push_back({ "white_noise",
                "N(0, density^2 * rate) per sample; density = Allan deviation at 1 s, two-sided PSD = density^2",
                { axes("accel_density", "m/s^2/sqrt(Hz)", 0.0, 0.0, 10.0, "accelerometer noise density"),
                  axes("gyro_density", "rad/s/sqrt(Hz)", 0.0, 0.0, 10.0, "gyro noise density") },
                5 });
  v.push_back({ "saturation",
                "clips each axis to +-limit",
                { axes("accel_limit", "m/s^2", 160.0, 1e-6, 1e6, "accelerometer full scale"),
                  axes("gyro_limit", "rad/s", 35.0, 1e-6, 1e6, "gyro full scale") },
                6 });
  v.push_back({ "quantization",
                "rounds each axis to a multiple of step (0 = off)",
                { axes("accel_step", "m/s^2", 0.0, 0.0, 100.0, "accelerometer LSB"),
                  axes("gyro_step", "rad/s", 0.0, 0.0, 10.0, "gyro LSB") },
                7 });
  v.push_back(
      { "gravity_leakage",
        "tilt error of the REPORTED orientation: reported = attitude * R(yaw) R(pitch) R(roll)",
        { scalar("roll", "rad", 0.0, -1.5, 1.5, "roll error"), scalar("pitch", "rad", 0.0, -1.5, 1.5, "pitch error"),
          scalar("yaw", "rad", 0.0, -3.2, 3.2, "yaw error") },
        8 });
  v.push_back({ "sample_hold",
                "the driver polls faster than the sensor updates: a new reading every 1 / sensor_rate s, "
                "repeated in between",
                { scalar("sensor_rate", "Hz", 0.0, 0.0, 1e5, "the sensor's own update rate (0 = off)") },
                8 });
  v.push_back({ "timestamp_jitter",
                "stamp = t + offset + N(0, sigma^2)",
                { scalar("sigma", "s", 0.0, 0.0, 1.0, "standard deviation of the stamp error"),
                  scalar("offset", "s", 0.0, -10.0, 10.0, "constant stamp delay") },
                9 });
  v.push_back({ "dropouts",
                "a burst of lost samples starts with probability per sample; bursts are geometric",
                { scalar("probability", "-", 0.0, 0.0, 1.0, "burst start probability per sample"),
                  scalar("burst_length", "samples", 1.0, 1.0, 1e6, "mean burst length") },
                10 });
  return v;
}

const std::vector<double>& param(const EffectSpec& spec, const std::string& key)
{
  const auto it = spec.params.find(key);
  if (it == spec.params.end())
  {
    throw std::runtime_error("effect " + spec.name + ": missing parameter " + key);
  }
  return it->second;
}

Vector3 vec3(const EffectSpec& spec, const std::string& key)
{
  const std::vector<double>& v = param(spec, key);
  return Vector3(v[0], v[1], v[2]);
}

Matrix3 mat3(const EffectSpec& spec, const std::string& key)
{
  const std::vector<double>& v = param(spec, key);
  Matrix3 m;
  m << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  return m;
}

double num(const EffectSpec& spec, const std::string& key)
{
  return param(spec, key)[0];
}

class LeverArm : public Effect
{
public:
  explicit LeverArm(const EffectSpec& spec) : offset_(vec3(spec, "offset"))
  {
  }
  void apply(const EffectInput& in, ImuOutput& out) override
  {
    const Vector3& w = in.truth->angular_rate;
    const Vector3& a = in.truth->angular_acceleration;
    out.accel += a.cross(offset_) + w.cross(w.cross(offset_));
  }

private:
  Vector3 offset_;
};

class Misalignment : public Effect
{
public:
  explicit Misalignment(const EffectSpec& spec)
    : accel_(Matrix3::Identity() + mat3(spec, "accel")), gyro_(Matrix3::Identity() + mat3(spec, "gyro"))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel = accel_ * out.accel;
    out.gyro = gyro_ * out.gyro;
  }

private:
  Matrix3 accel_;
  Matrix3 gyro_;
};

class ScaleFactor : public Effect
{
public:
  explicit ScaleFactor(const EffectSpec& spec)
    : accel_(Vector3::Ones() + vec3(spec, "accel")), gyro_(Vector3::Ones() + vec3(spec, "gyro"))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel = out.accel.cwiseProduct(accel_);
    out.gyro = out.gyro.cwiseProduct(gyro_);
  }

private:
  Vector3 accel_;
  Vector3 gyro_;
};

class ConstantBias : public Effect
{
public:
  explicit ConstantBias(const EffectSpec& spec) : accel_(vec3(spec, "accel")), gyro_(vec3(spec, "gyro"))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel += accel_;
    out.gyro += gyro_;
  }

private:
  Vector3 accel_;
  Vector3 gyro_;
};

class PeriodicBias : public Effect
{
public:
  explicit PeriodicBias(const EffectSpec& spec)
    : accel_amplitude_(vec3(spec, "accel_amplitude")),
      accel_omega_(kTwoPi * vec3(spec, "accel_period").cwiseInverse()),
      accel_phase_(vec3(spec, "accel_phase")),
      gyro_amplitude_(vec3(spec, "gyro_amplitude")),
      gyro_omega_(kTwoPi * vec3(spec, "gyro_period").cwiseInverse()),
      gyro_phase_(vec3(spec, "gyro_phase"))
  {
  }
  void apply(const EffectInput& in, ImuOutput& out) override
  {
    for (int i = 0; i < 3; ++i)
    {
      out.accel[i] += accel_amplitude_[i] * std::sin(accel_omega_[i] * in.elapsed + accel_phase_[i]);
      out.gyro[i] += gyro_amplitude_[i] * std::sin(gyro_omega_[i] * in.elapsed + gyro_phase_[i]);
    }
  }

private:
  Vector3 accel_amplitude_;
  Vector3 accel_omega_;
  Vector3 accel_phase_;
  Vector3 gyro_amplitude_;
  Vector3 gyro_omega_;
  Vector3 gyro_phase_;
};

class ThermalDrift : public Effect
{
public:
  explicit ThermalDrift(const EffectSpec& spec)
    : accel_(vec3(spec, "accel_coefficient")),
      gyro_(vec3(spec, "gyro_coefficient")),
      reference_(num(spec, "reference_temperature"))
  {
  }
  void apply(const EffectInput& in, ImuOutput& out) override
  {
    if (!in.has_temperature)
    {
      return;
    }
    const double dT = in.temperature - reference_;
    out.accel += accel_ * dT;
    out.gyro += gyro_ * dT;
  }

private:
  Vector3 accel_;
  Vector3 gyro_;
  double reference_;
};

class BiasRandomWalk : public Effect
{
public:
  BiasRandomWalk(const EffectSpec& spec, std::uint64_t seed, double rate)
    : accel_step_(vec3(spec, "accel_density") / std::sqrt(rate)),
      gyro_step_(vec3(spec, "gyro_density") / std::sqrt(rate)),
      noise_(seed)
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel += accel_bias_;
    out.gyro += gyro_bias_;
    for (int i = 0; i < 3; ++i)
    {
      accel_bias_[i] += accel_step_[i] * noise_.next();
      gyro_bias_[i] += gyro_step_[i] * noise_.next();
    }
  }

private:
  Vector3 accel_step_;
  Vector3 gyro_step_;
  NormalStream noise_;
  Vector3 accel_bias_ = Vector3::Zero();
  Vector3 gyro_bias_ = Vector3::Zero();
};

class BiasInstability : public Effect
{
public:
  BiasInstability(const EffectSpec& spec, std::uint64_t seed, double rate)
    : accel_sigma_(vec3(spec, "accel_sigma")),
      gyro_sigma_(vec3(spec, "gyro_sigma")),
      phi_(std::exp(-1.0 / (rate * num(spec, "correlation_time")))),
      drive_(std::sqrt(1.0 - phi_ * phi_)),
      noise_(seed)
  {
    for (int i = 0; i < 3; ++i)
    {
      accel_bias_[i] = accel_sigma_[i] * noise_.next();
      gyro_bias_[i] = gyro_sigma_[i] * noise_.next();
    }
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel += accel_bias_;
    out.gyro += gyro_bias_;
    for (int i = 0; i < 3; ++i)
    {
      accel_bias_[i] = phi_ * accel_bias_[i] + drive_ * accel_sigma_[i] * noise_.next();
      gyro_bias_[i] = phi_ * gyro_bias_[i] + drive_ * gyro_sigma_[i] * noise_.next();
    }
  }

private:
  Vector3 accel_sigma_;
  Vector3 gyro_sigma_;
  double phi_;
  double drive_;
  NormalStream noise_;
  Vector3 accel_bias_ = Vector3::Zero();
  Vector3 gyro_bias_ = Vector3::Zero();
};

class Vibration : public Effect
{
public:
  Vibration(const EffectSpec& spec, std::uint64_t seed, double rate) : noise_(seed)
  {
    const std::vector<double>& f = param(spec, "frequency");
    const std::size_t n = f.size();
    const std::vector<double> accel = sized(spec, "accel_amplitude", 3 * n);
    const std::vector<double> gyro = sized(spec, "gyro_amplitude", 3 * n);
    const std::vector<double> phase = sized(spec, "phase", n);
    const std::vector<double> bandwidth = sized(spec, "bandwidth", n);
    for (std::size_t l = 0; l < n; ++l)
    {
      // A phase random walk of variance 2 pi B per second gives a Lorentzian of FWHM B [Hz].
      lines_.push_back({ kTwoPi * f[l], phase[l], std::sqrt(kTwoPi * bandwidth[l] / rate),
                         Vector3(accel[3 * l], accel[3 * l + 1], accel[3 * l + 2]),
                         Vector3(gyro[3 * l], gyro[3 * l + 1], gyro[3 * l + 2]) });
    }
  }
  void apply(const EffectInput& in, ImuOutput& out) override
  {
    for (Line& line : lines_)
    {
      const double s = std::sin(line.omega * in.elapsed + line.phase);
      out.accel += s * line.accel;
      out.gyro += s * line.gyro;
      if (line.phase_step > 0.0)
      {
        line.phase += line.phase_step * noise_.next();
      }
    }
  }

private:
  struct Line
  {
    double omega;
    double phase;
    double phase_step;
    Vector3 accel;
    Vector3 gyro;
  };

  static std::vector<double> sized(const EffectSpec& spec, const std::string& key, std::size_t n)
  {
    const std::vector<double>& v = param(spec, key);
    if (v.empty())
    {
      return rep(0.0, n);
    }
    if (v.size() != n)
    {
      std::ostringstream os;
      os << "effect vibration: parameter " << key << " needs " << n << " values (has " << v.size() << ")";
      throw std::runtime_error(os.str());
    }
    return v;
  }

  std::vector<Line> lines_;
  NormalStream noise_;
};

class WhiteNoise : public Effect
{
public:
  WhiteNoise(const EffectSpec& spec, std::uint64_t seed, double rate)
    : accel_sigma_(vec3(spec, "accel_density") * std::sqrt(rate)),
      gyro_sigma_(vec3(spec, "gyro_density") * std::sqrt(rate)),
      noise_(seed)
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    for (int i = 0; i < 3; ++i)
    {
      out.accel[i] += accel_sigma_[i] * noise_.next();
      out.gyro[i] += gyro_sigma_[i] * noise_.next();
    }
  }

private:
  Vector3 accel_sigma_;
  Vector3 gyro_sigma_;
  NormalStream noise_;
};

class Saturation : public Effect
{
public:
  explicit Saturation(const EffectSpec& spec) : accel_(vec3(spec, "accel_limit")), gyro_(vec3(spec, "gyro_limit"))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.accel = out.accel.cwiseMax(-accel_).cwiseMin(accel_);
    out.gyro = out.gyro.cwiseMax(-gyro_).cwiseMin(gyro_);
  }

private:
  Vector3 accel_;
  Vector3 gyro_;
};

class Quantization : public Effect
{
public:
  explicit Quantization(const EffectSpec& spec) : accel_(vec3(spec, "accel_step")), gyro_(vec3(spec, "gyro_step"))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    for (int i = 0; i < 3; ++i)
    {
      out.accel[i] = quantize(out.accel[i], accel_[i]);
      out.gyro[i] = quantize(out.gyro[i], gyro_[i]);
    }
  }

private:
  static double quantize(double x, double step)
  {
    return step > 0.0 ? step * std::round(x / step) : x;
  }
  Vector3 accel_;
  Vector3 gyro_;
};

class GravityLeakage : public Effect
{
public:
  explicit GravityLeakage(const EffectSpec& spec)
    : error_(Eigen::AngleAxisd(num(spec, "yaw"), Vector3::UnitZ()) *
             Eigen::AngleAxisd(num(spec, "pitch"), Vector3::UnitY()) *
             Eigen::AngleAxisd(num(spec, "roll"), Vector3::UnitX()))
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.orientation = (out.orientation * error_).normalized();
  }

private:
  Quaternion error_;
};

class TimestampJitter : public Effect
{
public:
  TimestampJitter(const EffectSpec& spec, std::uint64_t seed)
    : sigma_(num(spec, "sigma")), offset_(num(spec, "offset")), noise_(seed)
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    out.stamp_offset += offset_ + sigma_ * noise_.next();
  }

private:
  double sigma_;
  double offset_;
  NormalStream noise_;
};

/// Zero-order hold at the sensor's rate: measurements and orientation repeat until the next
/// reading (the stamps do not: the driver stamps each poll).
class SampleHold : public Effect
{
public:
  explicit SampleHold(const EffectSpec& spec)
    : interval_(num(spec, "sensor_rate") > 0.0 ? 1.0 / num(spec, "sensor_rate") : 0.0)
  {
  }
  void apply(const EffectInput& in, ImuOutput& out) override
  {
    if (interval_ <= 0.0)
      return;
    // A reading is due at every multiple of the interval; a poll takes the newest one. The
    // tolerance keeps a poll that lands on a reading's time (equal rates) from missing it.
    const double reading = std::floor(in.elapsed / interval_ + 1e-9);
    if (!held_ || reading != reading_)
    {
      held_ = true;
      reading_ = reading;
      accel_ = out.accel;
      gyro_ = out.gyro;
      orientation_ = out.orientation;
      return;
    }
    out.accel = accel_;
    out.gyro = gyro_;
    out.orientation = orientation_;
  }

private:
  double interval_;
  bool held_ = false;
  double reading_ = 0.0;
  Vector3 accel_ = Vector3::Zero();
  Vector3 gyro_ = Vector3::Zero();
  Quaternion orientation_ = Quaternion::Identity();
};

class Dropouts : public Effect
{
public:
  Dropouts(const EffectSpec& spec, std::uint64_t seed)
    : start_(num(spec, "probability")), end_(1.0 / num(spec, "burst_length")), rng_(seed)
  {
  }
  void apply(const EffectInput&, ImuOutput& out) override
  {
    const double u = rng_.uniform();
    in_burst_ = in_burst_ ? (u >= end_) : (u < start_);
    out.dropped = out.dropped || in_burst_;
  }

private:
  double start_;
  double end_;
  Rng rng_;
  bool in_burst_ = false;
};
}  // namespace

const std::vector<EffectInfo>& effectVocabulary()
{
  static const std::vector<EffectInfo> vocabulary = buildVocabulary();
  return vocabulary;
}

const EffectInfo& effectInfo(const std::string& name)
{
  for (const EffectInfo& info : effectVocabulary())
  {
    if (info.name == name)
    {
      return info;
    }
  }
  throw std::runtime_error("unknown effect '" + name + "' (simulate_imu --list-effects lists them)");
}

EffectSpec defaultEffect(const std::string& name)
{
  EffectSpec spec;
  spec.name = name;
  for (const ParamInfo& p : effectInfo(name).params)
  {
    spec.params[p.name] = p.default_value;
  }
  return spec;
}

EffectSpec completeEffect(const EffectSpec& spec, const std::string& where)
{
  const EffectInfo& info = effectInfo(spec.name);
  EffectSpec out = defaultEffect(spec.name);
  out.enabled = spec.enabled;
  for (const auto& [key, values] : spec.params)
  {
    const auto it = std::find_if(info.params.begin(), info.params.end(),
                                 [&key = key](const ParamInfo& p) { return p.name == key; });
    const std::string name = "key '" + where + "." + key + "'";
    if (it == info.params.end())
    {
      throw std::runtime_error(name + ": unknown parameter of effect " + spec.name);
    }
    std::vector<double> v = values;
    if (it->size == 3 && v.size() == 1)
    {
      v = rep(v[0], 3);
    }
    if (it->size != 0 && v.size() != it->size)
    {
      std::ostringstream os;
      os << name << ": expected " << it->size << " values [" << it->unit << "], got " << v.size();
      throw std::runtime_error(os.str());
    }
    for (const double x : v)
    {
      if (!std::isfinite(x) || x < it->min || x > it->max)
      {
        std::ostringstream os;
        os << name << ": value " << x << " outside [" << it->min << ", " << it->max << "] " << it->unit;
        throw std::runtime_error(os.str());
      }
    }
    out.params[key] = v;
  }
  return out;
}

std::unique_ptr<Effect> makeEffect(const EffectSpec& spec, std::uint64_t seed, double rate)
{
  using Factory = std::function<std::unique_ptr<Effect>(const EffectSpec&, std::uint64_t, double)>;
  static const std::map<std::string, Factory> factories = {
    { "lever_arm", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<LeverArm>(e); } },
    { "misalignment", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<Misalignment>(e); } },
    { "scale_factor", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<ScaleFactor>(e); } },
    { "constant_bias", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<ConstantBias>(e); } },
    { "periodic_bias", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<PeriodicBias>(e); } },
    { "thermal_drift", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<ThermalDrift>(e); } },
    { "bias_random_walk",
      [](const EffectSpec& e, std::uint64_t s, double r) { return std::make_unique<BiasRandomWalk>(e, s, r); } },
    { "bias_instability",
      [](const EffectSpec& e, std::uint64_t s, double r) { return std::make_unique<BiasInstability>(e, s, r); } },
    { "vibration",
      [](const EffectSpec& e, std::uint64_t s, double r) { return std::make_unique<Vibration>(e, s, r); } },
    { "white_noise",
      [](const EffectSpec& e, std::uint64_t s, double r) { return std::make_unique<WhiteNoise>(e, s, r); } },
    { "saturation", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<Saturation>(e); } },
    { "quantization", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<Quantization>(e); } },
    { "gravity_leakage",
      [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<GravityLeakage>(e); } },
    { "sample_hold", [](const EffectSpec& e, std::uint64_t, double) { return std::make_unique<SampleHold>(e); } },
    { "timestamp_jitter",
      [](const EffectSpec& e, std::uint64_t s, double) { return std::make_unique<TimestampJitter>(e, s); } },
    { "dropouts", [](const EffectSpec& e, std::uint64_t s, double) { return std::make_unique<Dropouts>(e, s); } },
  };
  const auto it = factories.find(spec.name);
  if (it == factories.end())
  {
    throw std::runtime_error("unknown effect '" + spec.name + "'");
  }
  return it->second(spec, seed, rate);
}
}  // namespace periodic_bias_compensation::sim
