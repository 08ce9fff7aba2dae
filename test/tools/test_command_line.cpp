// The tools' command-line parser: values, flags, strict numbers, errors that name the option.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "periodic_bias_compensation/tools/command_line.h"

using periodic_bias_compensation::CommandLine;
using periodic_bias_compensation::UsageError;

namespace
{
struct Options
{
  std::string scenario;
  double settle = 20.0;
  bool settle_given = false;
  int seeds = 5;
  std::uint64_t seed = 0;
  bool quiet = false;
  bool plots = true;
};

/// Parses `args` (without the program name) into *o; returns parse()'s result.
bool parse(const std::vector<std::string>& args, Options* o)
{
  CommandLine cli("usage: tool [options]\n");
  cli.text("--scenario", &o->scenario)
      .number("--settle", &o->settle, &o->settle_given)
      .integer("--seeds", &o->seeds)
      .integer("--seed", &o->seed)
      .flag("--quiet", &o->quiet)
      .flag("--no-plots", &o->plots, false);
  std::vector<std::string> storage = { "tool" };
  storage.insert(storage.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : storage)
    argv.push_back(s.data());
  return cli.parse(static_cast<int>(argv.size()), argv.data());
}

/// The message of the UsageError that parsing `args` throws ("" if none).
std::string error(const std::vector<std::string>& args)
{
  Options o;
  try
  {
    parse(args, &o);
  }
  catch (const UsageError& e)
  {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(CommandLine, ReadsValuesAndFlags)
{
  Options o;
  ASSERT_TRUE(parse({ "--scenario", "a.yaml", "--settle", "2.5e1", "--seeds", "7", "--seed", "18446744073709551615",
                      "--quiet", "--no-plots" },
                    &o));
  EXPECT_EQ(o.scenario, "a.yaml");
  EXPECT_DOUBLE_EQ(o.settle, 25.0);
  EXPECT_TRUE(o.settle_given);
  EXPECT_EQ(o.seeds, 7);
  EXPECT_EQ(o.seed, 18446744073709551615ULL);
  EXPECT_TRUE(o.quiet);
  EXPECT_FALSE(o.plots);
}

TEST(CommandLine, DefaultsStayWhenAbsent)
{
  Options o;
  ASSERT_TRUE(parse({}, &o));
  EXPECT_DOUBLE_EQ(o.settle, 20.0);
  EXPECT_FALSE(o.settle_given);
  EXPECT_TRUE(o.plots);
}

TEST(CommandLine, HelpReturnsFalse)
{
  Options o;
  testing::internal::CaptureStdout();
  EXPECT_FALSE(parse({ "--seeds", "3", "--help" }, &o));
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "usage: tool [options]\n");
}

TEST(CommandLine, ErrorsNameTheOption)
{
  EXPECT_EQ(error({ "--sede", "3" }), "unknown option '--sede'");
  EXPECT_EQ(error({ "--scenario" }), "--scenario needs a value");
  EXPECT_EQ(error({ "--settle", "5abc" }), "--settle takes a number, got '5abc'");
  EXPECT_EQ(error({ "--settle", "nan" }), "--settle takes a number, got 'nan'");
  EXPECT_EQ(error({ "--settle", "" }), "--settle takes a number, got ''");
  EXPECT_EQ(error({ "--seeds", "2.5" }), "--seeds takes a whole number, got '2.5'");
  EXPECT_EQ(error({ "--seeds", "99999999999" }), "--seeds takes a whole number, got '99999999999'");
  EXPECT_EQ(error({ "--seed", "-1" }), "--seed takes a whole number, got '-1'");
  EXPECT_EQ(error({ "--quiet", "--seeds", "3" }), "");
}
