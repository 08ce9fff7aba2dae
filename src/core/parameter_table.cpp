#include "periodic_bias_compensation/core/parameter_table.h"
#include "periodic_bias_compensation/core/harmonic_model.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

namespace periodic_bias_compensation
{
std::string toString(ParameterType type)
{
  const char* const names[] = { "bool", "int", "double", "string" };
  return names[static_cast<int>(type)];
}

ParameterType typeOf(const ParameterValue& value)
{
  return static_cast<ParameterType>(value.index());
}

std::string formatNumber(double value)
{
  if (std::isnan(value))
    return "nan";
  if (std::isinf(value))
    return value > 0 ? "inf" : "-inf";
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  return std::string(text, end);
}

std::string toString(const ParameterValue& value)
{
  switch (typeOf(value))
  {
    case ParameterType::kBool:
      return std::get<bool>(value) ? "true" : "false";
    case ParameterType::kInt:
      return std::to_string(std::get<int>(value));
    case ParameterType::kDouble:
      return formatNumber(std::get<double>(value));
    case ParameterType::kString:
      return std::get<std::string>(value);
  }
  return "";
}

bool ParameterRange::contains(double value) const
{
  return std::isfinite(value) && (min_inclusive ? value >= min : value > min) &&
         (max_inclusive ? value <= max : value < max);
}

double ParameterRange::lowest() const
{
  return min_inclusive || std::isinf(min) ? min : std::nextafter(min, max);
}

double ParameterRange::highest() const
{
  return max_inclusive || std::isinf(max) ? max : std::nextafter(max, min);
}

ParameterRange closed(double min, double max)
{
  return { min, max, true, true };
}

ParameterRange rightOpen(double min, double max)
{
  return { min, max, true, false };
}

ParameterRange open(double min, double max)
{
  return { min, max, false, false };
}

ParameterRange atLeast(double min)
{
  return { min, std::numeric_limits<double>::infinity(), true, true };
}

ParameterRange above(double min)
{
  return { min, std::numeric_limits<double>::infinity(), false, true };
}

std::string toString(const ParameterRange& range)
{
  const bool unbounded = std::isinf(range.max);
  return (range.min_inclusive ? "[" : "(") + formatNumber(range.min) + ", " + formatNumber(range.max) +
         (range.max_inclusive && !unbounded ? "]" : ")");
}

std::string describeAccepted(const ParameterInfo& info)
{
  switch (info.type)
  {
    case ParameterType::kInt:
    case ParameterType::kDouble:
      return toString(info.range);
    case ParameterType::kString:
    {
      std::string choices;
      for (const ParameterChoice& choice : info.choices)
        choices += (choices.empty() ? "" : ", ") + choice.value;
      return !choices.empty() ? choices : info.non_empty ? "not empty" : "";
    }
    case ParameterType::kBool:
      break;
  }
  return "";
}

bool checkValue(const ParameterInfo& info, const ParameterValue& value, std::string* why)
{
  std::string error;
  if (typeOf(value) != info.type)
  {
    error = info.key + ": expected " + toString(info.type) + ", got " + toString(typeOf(value));
  }
  else if (info.type == ParameterType::kInt || info.type == ParameterType::kDouble)
  {
    const double number = info.type == ParameterType::kInt ? std::get<int>(value) : std::get<double>(value);
    if (!info.range.contains(number))
      error = info.key + " = " + toString(value) + " is out of range " + toString(info.range) +
              (info.range_reason.empty() ? "" : ": " + info.range_reason);
  }
  else if (info.type == ParameterType::kString)
  {
    const std::string& text = std::get<std::string>(value);
    bool listed = info.choices.empty();
    for (const ParameterChoice& choice : info.choices)
      listed = listed || choice.value == text;
    if (!listed)
      error = info.key + " = '" + text + "' is not one of " + describeAccepted(info);
    else if (info.non_empty && text.empty())
      error = info.key + " must not be empty";
  }
  if (error.empty())
    return true;
  if (why != nullptr)
    *why = error;
  return false;
}

std::vector<std::string> keys(const std::vector<ParameterChange>& changes)
{
  std::vector<std::string> result;
  for (const ParameterChange& change : changes)
    result.push_back(change.info->key);
  return result;
}

std::string toString(const ParameterOrder& order)
{
  return order.lower + (order.strict ? " < " : " <= ") + order.upper;
}

std::string orderMessage(const ParameterOrder& order, double lower, double upper,
                         const std::vector<std::string>& changed)
{
  auto holds = [&changed](const std::string& key) {
    return std::find(changed.begin(), changed.end(), key) != changed.end();
  };
  const std::string low = order.lower + " = " + formatNumber(lower), high = order.upper + " = " + formatNumber(upper);
  if (holds(order.upper) && !holds(order.lower))
    return high + " must be " + (order.strict ? "above " : "at least ") + low;
  return low + " must be " + (order.strict ? "below " : "at most ") + high;
}

std::string gainKey(const GainTerm& term, int axis)
{
  return std::string(term.name) + "_" + kAxisNames[axis];
}

ParameterInfo makeInfo(const std::string& key, Reconfigure reconfigure, const std::string& unit,
                       const std::string& description, ParameterRange range, const std::string& range_reason)
{
  ParameterInfo info;
  info.key = key;
  info.reconfigure = reconfigure;
  info.unit = unit;
  info.description = description;
  info.range = range;
  info.range_reason = range_reason;
  return info;
}

namespace
{
using C = CompensatorConfig;

Parameter<C> modeParameter()
{
  ParameterInfo i = makeInfo("mode", Reconfigure::kRuntime, "", "compensation mode");
  i.choices = { { toString(Mode::kDefault), "the estimator of this project: harmonic tracking and comb drift removal" },
                { toString(Mode::kPaper), "Eq. 1-7 of Kim et al. 2005 as written" } };
  Parameter<C> p;
  static_cast<ParameterInfo&>(p) = i;
  p.type = ParameterType::kString;
  p.get = [](const C& c) { return ParameterValue(toString(c.mode)); };
  p.set = [](C& c, const ParameterValue& value) { modeFromString(std::get<std::string>(value), &c.mode); };
  return p;
}

void addGains(ParameterTable<C>* table)
{
  // Comb loop d(t+1) = beta * midrange + alpha * (drift over one period): the velocity/position
  // error over one period is multiplied by (1 - alpha) each period, so 0 <= alpha < 2 keeps it
  // stable; the mid-range term adds damping that destabilises the loop above beta = 12
  // (measured, test_compensator: PaperGainLimits).
  const char* what[4] = { "velocity error gain", "position error gain", "velocity periodic offset gain",
                          "position periodic offset gain" };
  for (int axis = 0; axis < 3; ++axis)
    for (int t = 0; t < 4; ++t)
    {
      const GainTerm& term = kGainTerms[t];
      const bool alpha = t < 2;
      ParameterInfo i =
          makeInfo(gainKey(term, axis), Reconfigure::kRuntime, "-",
                   std::string(what[t]) + " " + term.name + ", level axis " + kAxisNames[axis] + " (Eq. 6-7)",
                   alpha ? rightOpen(0.0, 2.0) : closed(0.0, 12.0),
                   alpha ? "the comb loop is unstable from 2 on" : "larger values make the loop oscillate and diverge");
      const auto field = term.field;
      table->push_back(makeParameter<double, C>(
          i, [ axis, field ](auto& config) -> auto& { return config.gains[axis].*field; }));
    }
}

void addLeverArm(ParameterTable<C>* table)
{
  for (int axis = 0; axis < 3; ++axis)
  {
    ParameterInfo i =
        makeInfo(std::string("lever_arm_") + kAxisNames[axis], Reconfigure::kRuntime, "m",
                 std::string("position of the IMU from the point the odometry describes, ") + kAxisNames[axis] +
                     " in the base frame (the wave part of its tilt is taken off odometry/wave; default mode)",
                 closed(-100.0, 100.0), "beyond the size of a ship");
    table->push_back(makeParameter<double, C>(
        i, [axis](auto& config) -> auto& { return config.lever_arm[axis]; }));
  }
}
}  // namespace

const ParameterTable<CompensatorConfig>& compensatorParameters()
{
  static const ParameterTable<C> table = [] {
    const Reconfigure run = Reconfigure::kRuntime, start = Reconfigure::kStartup;
    ParameterTable<C> t;
    t.push_back(modeParameter());
    t.push_back(flagParameter("enable_constant", &C::enable_constant, run, "estimate and remove the constant bias"));
    t.push_back(flagParameter("enable_periodic", &C::enable_periodic, run, "estimate and remove the periodic bias"));
    addGains(&t);
    t.push_back(numberParameter("calibration_duration", &C::calibration_duration, start, closed(0.0, 3600.0), "s",
                                "length of the constant-bias window at the start and after ~calibrate"));
    t.push_back(
        flagParameter("assume_static_calibration", &C::assume_static_calibration, start,
                      "the sensor is at rest during the calibration window (paper Sec. 3.1); false: motion allowed"));
    t.push_back(numberParameter("fft_window", &C::fft_window, run, closed(2.0, 3600.0), "s",
                                "length of the sliding FFT window of the period search"));
    t.push_back(
        numberParameter("fft_hop", &C::fft_hop, run, closed(0.01, 3600.0), "s", "time between two FFT updates"));
    // Below 1 mHz a period no longer fits three times in the longest window, and the period
    // tables (rate / min_frequency samples) would outgrow any memory.
    t.push_back(numberParameter("min_frequency", &C::min_frequency, run, atLeast(0.001), "Hz",
                                "lowest dominant (wave encounter) frequency searched"));
    t.push_back(numberParameter("max_frequency", &C::max_frequency, run, atLeast(0.001), "Hz",
                                "highest dominant (wave encounter) frequency searched"));
    t.push_back(numberParameter("min_peak_ratio", &C::min_peak_ratio, run, atLeast(1.0), "-",
                                "peak power / median power in the band needed to lock a period"));
    t.push_back(numberParameter("harmonics", &C::harmonics, run, closed(1.0, kMaxHarmonics), "-",
                                "harmonics of the dominant frequency tracked (default mode)"));
    t.push_back(numberParameter("harmonic_memory", &C::harmonic_memory, run, atLeast(0.5), "s",
                                "time constant of the harmonic estimator (default mode)"));
    t.push_back(numberParameter("drift_time_constant", &C::drift_time_constant, run, atLeast(0.5), "s",
                                "time constant of the slow-motion drift removal (default mode)",
                                "faster drift removal would follow the waves"));
    t.push_back(flagParameter("heave_filter", &C::heave_filter, run,
                              "wave motion from the whole wave band, not only the harmonic model (default mode)"));
    t.push_back(numberParameter("heave_corner_frequency", &C::heave_corner_frequency, run, closed(0.002, 0.05), "Hz",
                                "corner of the drift removal of the broadband heave filter",
                                "the wave band must start well above it"));
    t.push_back(
        flagParameter("gyro_attitude", &C::gyro_attitude, run,
                      "samples without orientation: attitude integrated from the gyro, not one level frame (default "
                      "mode)"));
    t.push_back(numberParameter("tilt_time_constant", &C::tilt_time_constant, run, closed(2.0, 3600.0), "s",
                                "time constant of the pull of the gyro attitude towards the gravity direction",
                                "shorter follows the wave accelerations"));
    t.push_back(flagParameter("estimate_gyro_bias", &C::estimate_gyro_bias, run,
                              "estimate the gyro bias on the level axes (gyro attitude)"));
    addLeverArm(&t);
    t.push_back(numberParameter("gravity", &C::gravity, start, open(9.0, 10.5), "m/s^2", "local gravity magnitude"));
    // 0 is a gap of more than kSlowStreamSteps sample periods (TimeBase).
    t.push_back(numberParameter("max_gap", &C::max_gap, run, atLeast(0.0), "s",
                                "a gap between IMU stamps longer than this resets the integration"));
    t.push_back(numberParameter("max_rate_change", &C::max_rate_change, start, open(0.0, 1.0), "-",
                                "relative change of the sample rate that restarts the period search"));
    t.push_back(numberParameter("max_quaternion_norm_error", &C::max_quaternion_norm_error, start, open(0.0, 0.5), "-",
                                "|1 - |q|| above this rejects the orientation of a sample as non-unit"));
    return t;
  }();
  return table;
}

const std::vector<ParameterOrder>& compensatorOrderRules()
{
  static const std::vector<ParameterOrder> rules = { { "fft_hop", "fft_window", false },
                                                     { "min_frequency", "max_frequency", true } };
  return rules;
}

}  // namespace periodic_bias_compensation
