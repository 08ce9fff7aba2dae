// The core's parameter table (core/parameter_table.h): keys, defaults taken from
// CompensatorConfig{}, accessors that reach their own field, ranges that are exactly what
// CompensatorConfig::validate accepts, and the rules between keys naming the key the user changed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/parameter_table.h"

namespace pbc = periodic_bias_compensation;
using pbc::CompensatorConfig;
using pbc::ParameterType;
using pbc::ParameterValue;

namespace
{
const pbc::ParameterTable<CompensatorConfig>& table()
{
  return pbc::compensatorParameters();
}

/// A valid value of the parameter that differs from its default.
ParameterValue otherValue(const pbc::Parameter<CompensatorConfig>& p)
{
  const ParameterValue d = p.defaultValue();
  switch (p.type)
  {
    case ParameterType::kBool:
      return !std::get<bool>(d);
    case ParameterType::kInt:
      return std::get<int>(d) == static_cast<int>(p.range.lowest()) ? std::get<int>(d) + 1
                                                                    : static_cast<int>(p.range.lowest());
    case ParameterType::kDouble:
      return p.range.lowest() != std::get<double>(d) ? p.range.lowest() : std::nextafter(p.range.lowest(), 1e300);
    case ParameterType::kString:
      return p.choices.back().value != std::get<std::string>(d) ? p.choices.back().value : p.choices.front().value;
  }
  return d;
}
}  // namespace

TEST(ParameterTable, KeysAreUniqueAndEveryEntryComplete)
{
  std::set<std::string> keys;
  for (const auto& p : table())
  {
    EXPECT_TRUE(keys.insert(p.key).second) << "key listed twice: " << p.key;
    EXPECT_FALSE(p.description.empty()) << p.key;
    EXPECT_EQ(p.description.find('\n'), std::string::npos) << p.key << ": the description is one line";
    // dynamic_reconfigure refuses quotes in descriptions.
    std::string text = p.description;
    for (const pbc::ParameterChoice& choice : p.choices)
      text += choice.description;
    EXPECT_EQ(text.find_first_of("'\""), std::string::npos) << p.key << ": quotes in a description";
    EXPECT_EQ(pbc::typeOf(p.defaultValue()), p.type) << p.key;
    const bool number = p.type == ParameterType::kInt || p.type == ParameterType::kDouble;
    EXPECT_EQ(number, !p.unit.empty()) << p.key << ": numbers have a unit ('-' if none), flags and text none";
  }
  for (int axis = 0; axis < 3; ++axis)
    for (const pbc::GainTerm& term : pbc::kGainTerms)
      EXPECT_EQ(keys.count(pbc::gainKey(term, axis)), 1u) << pbc::gainKey(term, axis);
  EXPECT_EQ(keys.count("alpha_v_x"), 1u);
  EXPECT_EQ(keys.count("max_quaternion_norm_error"), 1u);
}

TEST(ParameterTable, DefaultsAreTheConfigDefaultsAndValidate)
{
  const CompensatorConfig defaults;
  std::string why;
  EXPECT_TRUE(defaults.validate(&why)) << why;
  for (const auto& p : table())
    EXPECT_TRUE(pbc::checkValue(p, p.defaultValue(), &why)) << why;
  // A few spelt out, so that a wrong accessor cannot hide behind get(CompensatorConfig{}).
  EXPECT_EQ(pbc::findParameter(table(), "beta_p_z")->defaultValue(), ParameterValue(defaults.gains[2].beta_p));
  EXPECT_EQ(pbc::findParameter(table(), "alpha_p_y")->defaultValue(), ParameterValue(defaults.gains[1].alpha_p));
  EXPECT_EQ(pbc::findParameter(table(), "fft_window")->defaultValue(), ParameterValue(defaults.fft_window));
  EXPECT_EQ(pbc::findParameter(table(), "harmonics")->defaultValue(), ParameterValue(defaults.harmonics));
  EXPECT_EQ(pbc::findParameter(table(), "mode")->defaultValue(), ParameterValue(pbc::toString(defaults.mode)));
}

TEST(ParameterTable, EachAccessorReachesItsOwnField)
{
  // Setting one key through the table changes that key and no other.
  for (const auto& p : table())
  {
    CompensatorConfig config;
    const ParameterValue value = otherValue(p);
    std::string why;
    ASSERT_TRUE(pbc::assign(p, value, &config, &why)) << why;
    EXPECT_EQ(p.get(config), value) << p.key;
    const auto changed = pbc::changes(table(), CompensatorConfig(), config);
    ASSERT_EQ(changed.size(), 1u) << p.key;
    EXPECT_EQ(changed[0].info->key, p.key);
  }
  CompensatorConfig config;
  std::string why;
  EXPECT_FALSE(pbc::assign(*pbc::findParameter(table(), "mode"), ParameterValue(std::string("fast")), &config, &why));
  EXPECT_NE(why.find("mode = 'fast' is not one of default, paper"), std::string::npos) << why;
  EXPECT_FALSE(pbc::assign(*pbc::findParameter(table(), "harmonics"), ParameterValue(2.5), &config, &why));
  EXPECT_NE(why.find("harmonics: expected int"), std::string::npos) << why;
}

TEST(ParameterTable, RangesAreWhatValidateAccepts)
{
  // Each finite bound: the nearest value inside is accepted by the key's own check, the nearest
  // outside is refused by validate() naming the key; non-finite values are refused everywhere.
  for (const auto& p : table())
  {
    if (p.type != ParameterType::kInt && p.type != ParameterType::kDouble)
      continue;
    auto with = [&p](double v) {
      CompensatorConfig config;
      p.set(config, p.type == ParameterType::kInt ? ParameterValue(static_cast<int>(v)) : ParameterValue(v));
      return config;
    };
    const double step = p.type == ParameterType::kInt ? 1.0 : 0.0;
    std::string why;
    for (const double inside : { p.range.lowest(), p.range.highest() })
    {
      if (!std::isfinite(inside))
        continue;
      EXPECT_TRUE(pbc::checkRanges(table(), with(inside), &why)) << p.key << " = " << inside << ": " << why;
      const double outside = step > 0 ? inside + (inside == p.range.lowest() ? -step : step)
                                      : std::nextafter(inside, inside == p.range.lowest() ? -1e300 : 1e300);
      if (p.type == ParameterType::kInt && std::abs(outside) > std::numeric_limits<int>::max())
        continue;
      why.clear();
      EXPECT_FALSE(with(outside).validate(&why)) << p.key << " = " << outside << " accepted";
      EXPECT_EQ(why.rfind(p.key + " = ", 0), 0u) << why;
    }
    if (p.type == ParameterType::kDouble)
      for (const double bad : { std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity() })
      {
        why.clear();
        EXPECT_FALSE(with(bad).validate(&why)) << p.key << " = " << bad << " accepted";
        EXPECT_EQ(why.rfind(p.key + " = ", 0), 0u) << why;
      }
  }
  // The loop's stability limits are the table's: alpha < 2 refused at 2, beta up to 12.
  const auto& alpha = *pbc::findParameter(table(), "alpha_v_x");
  EXPECT_TRUE(alpha.range.contains(std::nextafter(2.0, 0.0)));
  EXPECT_FALSE(alpha.range.contains(2.0));
  EXPECT_DOUBLE_EQ(pbc::findParameter(table(), "beta_p_z")->range.highest(), 12.0);
}

TEST(ParameterTable, RulesBetweenKeysNameTheChangedKey)
{
  CompensatorConfig config;
  config.min_frequency = 5.0;
  std::string why;
  EXPECT_FALSE(config.validate(&why, { "min_frequency" }));
  EXPECT_EQ(why, "min_frequency = 5 must be below max_frequency = 2");
  config = CompensatorConfig();
  config.max_frequency = 0.01;
  EXPECT_FALSE(config.validate(&why, { "max_frequency" }));
  EXPECT_EQ(why, "max_frequency = 0.01 must be above min_frequency = 0.05");
  config = CompensatorConfig();
  config.fft_window = 10.0;
  config.fft_hop = 20.0;
  EXPECT_FALSE(config.validate(&why, { "fft_window" }));
  EXPECT_EQ(why, "fft_window = 10 must be at least fft_hop = 20");
  EXPECT_FALSE(config.validate(&why));
  EXPECT_EQ(why, "fft_hop = 20 must be at most fft_window = 10");
  config.fft_hop = 10.0;
  EXPECT_TRUE(config.validate(&why)) << "fft_hop = fft_window is allowed: " << why;

  // Compensator::setConfig knows what changed.
  pbc::Compensator compensator;
  config = CompensatorConfig();
  config.min_frequency = 5.0;
  EXPECT_FALSE(compensator.setConfig(config, &why));
  EXPECT_EQ(why, "min_frequency = 5 must be below max_frequency = 2");
  config = CompensatorConfig();
  config.max_frequency = 0.025;
  EXPECT_FALSE(compensator.setConfig(config, &why));
  EXPECT_EQ(why, "max_frequency = 0.025 must be above min_frequency = 0.05");
}

TEST(ParameterTable, NumbersPrintShortAndReadBackExactly)
{
  EXPECT_EQ(pbc::formatNumber(0.05), "0.05");
  EXPECT_EQ(pbc::formatNumber(3600.0), "3600");
  EXPECT_EQ(pbc::formatNumber(std::numeric_limits<double>::infinity()), "inf");
  for (const double v : { 0.05, 0.1, 9.80665, std::nextafter(2.0, 0.0), 1e-7, 123456789.125 })
    EXPECT_EQ(std::stod(pbc::formatNumber(v)), v) << pbc::formatNumber(v);
  EXPECT_EQ(pbc::toString(pbc::rightOpen(0.0, 2.0)), "[0, 2)");
  EXPECT_EQ(pbc::toString(pbc::atLeast(0.5)), "[0.5, inf)");
  EXPECT_EQ(pbc::toString(pbc::open(9.0, 10.5)), "(9, 10.5)");
}
