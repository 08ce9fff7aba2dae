// core_latency: the time of each Compensator::addSample call, samples fed at their own pace (or
// a multiple of it), the spectral designs on the core's design thread or in the sample's call.
// What the nodelet's callback pays for the core, without the transport. Run by scripts/bench.py,
// not a test.
//
//   core_latency --scenario FILE.yaml --duration S [--rate HZ] [--speed X]
//                [--designs background|calling] [--calls-csv FILE]
//
// The scenario (its own seed, at its own rate or HZ) is simulated for S seconds first; then sample k is given at
// start + (t_k - t_0) / X of the steady clock (X = 1: the IMU's own pace) and its call timed.
// Output: one line of key=value pairs on stdout (call times in us; max_at_s is the data time of
// the slowest call from the first sample, `slowest` the five slowest as data time:us). --calls-csv
// writes every call as data time from the first sample [s] and call time [us], to find what
// recurs in the slow ones.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/core_sample.h"

namespace pbc = periodic_bias_compensation;
namespace sim = periodic_bias_compensation::sim;
using Clock = std::chrono::steady_clock;

namespace
{
struct Options
{
  std::string scenario;
  double duration = 0.0;
  double rate = 0.0;  ///< 0: the scenario's
  double speed = 1.0;
  std::string designs = "background";
  std::string calls_csv;
};

const char* kUsage =
    "usage: core_latency --scenario FILE.yaml --duration S [--rate HZ] [--speed X]\n"
    "                    [--designs background|calling] [--calls-csv FILE]\n";

std::optional<Options> parseOptions(int argc, char** argv)
{
  Options o;
  pbc::CommandLine cli(kUsage);
  cli.text("--scenario", &o.scenario)
      .number("--duration", &o.duration)
      .number("--rate", &o.rate)
      .number("--speed", &o.speed)
      .text("--designs", &o.designs)
      .text("--calls-csv", &o.calls_csv);
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if (o.scenario.empty() || !(o.duration > 0.0) || !(o.speed > 0.0))
    throw pbc::UsageError("--scenario, --duration > 0 and --speed > 0 are required");
  if (!(o.rate >= 0.0 && o.rate <= 10000.0))
    throw pbc::UsageError("--rate is 0 (the scenario's) to 10000 Hz");
  if (o.designs != "background" && o.designs != "calling")
    throw pbc::UsageError("--designs is background or calling");
  return o;
}
}  // namespace

int main(int argc, char** argv)
{
  Options options;
  try
  {
    const std::optional<Options> parsed = parseOptions(argc, argv);
    if (!parsed)
      return 0;
    options = *parsed;
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "core_latency: " << e.what() << "\n" << kUsage;
    return 2;
  }
  try
  {
    sim::Scenario scenario = sim::loadScenario(options.scenario);
    scenario.duration = options.duration;
    if (options.rate > 0.0)
      scenario.rate = options.rate;
    sim::Simulator simulator(scenario, scenario.seed);
    std::vector<pbc::ImuSample> samples;
    sim::Sample s;
    while (simulator.next(&s))
      if (!s.dropped)
        samples.push_back(pbc::toImuSample(s));
    if (samples.empty())
      throw std::runtime_error("the scenario gave no sample");

    pbc::Compensator compensator;
    compensator.setBackgroundDesigns(options.designs == "background");
    pbc::CompensatorOutput out;
    std::vector<double> call_us(samples.size());
    double checksum = 0.0;
    const Clock::time_point start = Clock::now();
    const double t0 = samples.front().t;
    for (std::size_t k = 0; k < samples.size(); ++k)
    {
      std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                                std::chrono::duration<double>((samples[k].t - t0) / options.speed)));
      const Clock::time_point before = Clock::now();
      compensator.addSample(samples[k], &out);
      call_us[k] = std::chrono::duration<double, std::micro>(Clock::now() - before).count();
      checksum += out.position_filtered.sum() + out.position_wave.sum();
    }
    if (!options.calls_csv.empty())
    {
      std::ofstream csv(options.calls_csv);
      csv.precision(9);
      csv << "t_s,call_us\n";
      for (std::size_t k = 0; k < samples.size(); ++k)
        csv << samples[k].t - t0 << ',' << call_us[k] << '\n';
      if (!csv)
        throw std::runtime_error("cannot write " + options.calls_csv);
    }
    // The calls by time, slowest first: the quantiles, and the five slowest as data time:us.
    std::vector<std::size_t> order(call_us.size());
    for (std::size_t k = 0; k < order.size(); ++k)
      order[k] = k;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return call_us[a] > call_us[b]; });
    auto quantile = [&](double q) {
      const std::size_t rank = static_cast<std::size_t>(q * static_cast<double>(order.size() - 1));
      return call_us[order[order.size() - 1 - rank]];
    };
    double total = 0.0;
    long over_200 = 0, over_1000 = 0;
    for (double us : call_us)
    {
      total += us;
      over_200 += us > 200.0;
      over_1000 += us > 1000.0;
    }
    std::string slowest_calls;
    for (std::size_t i = 0; i < std::min<std::size_t>(5, order.size()); ++i)
    {
      char entry[64];
      std::snprintf(entry, sizeof entry, "%s%.2f:%.0f", i ? "," : "", samples[order[i]].t - t0, call_us[order[i]]);
      slowest_calls += entry;
    }
    std::printf(
        "designs=%s rate=%g samples=%zu speed=%g mean_us=%.2f p50_us=%.2f p99_us=%.2f p999_us=%.1f max_us=%.1f "
        "max_at_s=%.2f over_200us=%ld over_1ms=%ld slowest=%s checksum=%.17g\n",
        options.designs.c_str(), scenario.rate, samples.size(), options.speed, total / samples.size(), quantile(0.5),
        quantile(0.99), quantile(0.999), call_us[order.front()], samples[order.front()].t - t0, over_200, over_1000,
        slowest_calls.c_str(), checksum);
    return 0;
  }
  catch (const std::exception& e)
  {
    std::cerr << "core_latency: " << e.what() << "\n";
    return 1;
  }
}
