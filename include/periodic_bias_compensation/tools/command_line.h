// Command-line options of the package's tools: "--key value" and "--flag", parsed strictly
// (a number must be a whole finite number, an unknown option or a missing value is an error
// naming it). No ROS; header-only.
//
//   CommandLine cli(kUsage);
//   cli.text("--scenario", &o.scenario).number("--settle", &o.settle).flag("--quiet", &o.quiet);
//   if (!cli.parse(argc, argv)) return 0;  // --help: usage printed
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace periodic_bias_compensation
{
/// A bad command line; what() names the option and says what is wrong.
struct UsageError : std::runtime_error
{
  using std::runtime_error::runtime_error;
};

/// Throws UsageError "NAME must be at least MIN, got VALUE" when value < minimum.
template <typename Integer>
void requireAtLeast(const std::string& name, Integer value, Integer minimum)
{
  if (value < minimum)
    throw UsageError(name + " must be at least " + std::to_string(minimum) + ", got " + std::to_string(value));
}

class CommandLine
{
public:
  explicit CommandLine(std::string usage) : usage_(std::move(usage))
  {
  }

  /// --name VALUE, handed to `handler` (which may throw UsageError).
  CommandLine& option(const std::string& name, std::function<void(const std::string&)> handler)
  {
    takes_value_[name] = std::move(handler);
    return *this;
  }
  /// --name (no value): sets *target to `value`.
  CommandLine& flag(const std::string& name, bool* target, bool value = true)
  {
    flags_[name] = [target, value] { *target = value; };
    return *this;
  }
  CommandLine& text(const std::string& name, std::string* target)
  {
    return option(name, [target](const std::string& v) { *target = v; });
  }
  /// A finite real number; `given` (if not null) is set when the option appears.
  CommandLine& number(const std::string& name, double* target, bool* given = nullptr)
  {
    return option(name, [name, target, given](const std::string& v) {
      *target = toNumber(name, v);
      if (given != nullptr)
        *given = true;
    });
  }
  /// A whole number of type Integer (int, std::int64_t, std::uint64_t, ...).
  template <typename Integer>
  CommandLine& integer(const std::string& name, Integer* target, bool* given = nullptr)
  {
    return option(name, [name, target, given](const std::string& v) {
      *target = toInteger<Integer>(name, v);
      if (given != nullptr)
        *given = true;
    });
  }

  /// Parses argv[1..]. Returns false after printing the usage for -h/--help; throws UsageError.
  bool parse(int argc, char** argv) const
  {
    for (int i = 1; i < argc; ++i)
    {
      const std::string arg = argv[i];
      if (arg == "-h" || arg == "--help")
      {
        std::cout << usage_;
        return false;
      }
      if (const auto flag = flags_.find(arg); flag != flags_.end())
      {
        flag->second();
        continue;
      }
      const auto option = takes_value_.find(arg);
      if (option == takes_value_.end())
        throw UsageError("unknown option '" + arg + "'");
      if (i + 1 >= argc)
        throw UsageError(arg + " needs a value");
      option->second(argv[++i]);
    }
    return true;
  }

  const std::string& usage() const
  {
    return usage_;
  }

  static double toNumber(const std::string& name, const std::string& text)
  {
    std::size_t used = 0;
    double value = NAN;
    try
    {
      value = std::stod(text, &used);
    }
    catch (const std::exception&)
    {
      used = 0;
    }
    if (used == 0 || used != text.size() || !std::isfinite(value))
      throw UsageError(name + " takes a number, got '" + text + "'");
    return value;
  }

  template <typename Integer>
  static Integer toInteger(const std::string& name, const std::string& text)
  {
    std::size_t used = 0;
    bool in_range = false;
    Integer value = 0;
    try
    {
      if constexpr (std::is_signed_v<Integer>)
      {
        const long long v = std::stoll(text, &used);
        in_range = v >= std::numeric_limits<Integer>::lowest() && v <= std::numeric_limits<Integer>::max();
        value = static_cast<Integer>(v);
      }
      else
      {
        const unsigned long long v = std::stoull(text, &used);
        in_range = text.find('-') == std::string::npos && v <= std::numeric_limits<Integer>::max();
        value = static_cast<Integer>(v);
      }
    }
    catch (const std::exception&)
    {
      used = 0;
    }
    if (used == 0 || used != text.size() || !in_range)
      throw UsageError(name + " takes a whole number, got '" + text + "'");
    return value;
  }

private:
  std::string usage_;
  std::map<std::string, std::function<void()>> flags_;
  std::map<std::string, std::function<void(const std::string&)>> takes_value_;
};
}  // namespace periodic_bias_compensation
