// Speed of the estimation core (Google Benchmark): ns per sample, against the floor of merely
// reading the same samples. Inputs come from the simulator (paper bench and a moored ship in sea
// state 4), made once before timing.
#include <benchmark/benchmark.h>

#include <map>
#include <string>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/frequency_tracker.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/tools/core_sample.h"

namespace pbc = periodic_bias_compensation;
namespace sim = periodic_bias_compensation::sim;

namespace
{
const std::vector<pbc::ImuSample>& samples(const std::string& scenario_name)
{
  static std::map<std::string, std::vector<pbc::ImuSample>> cache;
  auto it = cache.find(scenario_name);
  if (it != cache.end())
    return it->second;
  const sim::Scenario scenario = sim::loadScenario(std::string(PBC_SCENARIO_DIR) + "/" + scenario_name + ".yaml");
  sim::Simulator simulator(scenario, 1);
  std::vector<pbc::ImuSample> out;
  sim::Sample s;
  while (simulator.next(&s))
  {
    if (s.dropped)
      continue;
    out.push_back(pbc::toImuSample(s));
  }
  return cache.emplace(scenario_name, std::move(out)).first->second;
}

/// The floor: touch every field a compensator reads, with the same loop structure.
void readFloor(benchmark::State& state, const std::string& scenario)
{
  const auto& data = samples(scenario);
  for (auto _ : state)
  {
    double sum = 0.0;
    for (const auto& s : data)
      sum += s.t + s.specific_force.sum() + s.angular_rate.sum() + s.orientation.w();
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * data.size());
}

void compensate(benchmark::State& state, const std::string& scenario, pbc::Mode mode)
{
  const auto& data = samples(scenario);
  pbc::CompensatorConfig config;
  config.mode = mode;
  for (auto _ : state)
  {
    pbc::Compensator compensator(config);
    // Designs in the call, as the offline tools run them: the time of one thread holds them all.
    compensator.setBackgroundDesigns(false);
    pbc::CompensatorOutput out;
    for (const auto& s : data)
      compensator.addSample(s, &out);
    benchmark::DoNotOptimize(out.position_filtered.x());
  }
  state.SetItemsProcessed(state.iterations() * data.size());
}

/// One FFT analysis of a full 60 s window (the default fft_window) of 100 Hz data (the cost paid
/// every fft_hop per axis), decimated by the argument: 1 (the whole 6000 samples) or 10 (what the
/// compensator does at 100 Hz with max_frequency 2 Hz: 600 samples).
void fftAnalysis(benchmark::State& state)
{
  pbc::FrequencyTracker tracker(6000, 100.0, static_cast<int>(state.range(0)));
  for (int k = 0; k < 6000; ++k)
    tracker.push(std::sin(0.03 * k) + 0.01 * (k % 7), k / 100.0);
  for (auto _ : state)
    benchmark::DoNotOptimize(tracker.analyse(0.05, 2.0, 30.0).frequency);
  state.SetItemsProcessed(state.iterations());
}
}  // namespace

BENCHMARK_CAPTURE(readFloor, paper_bench, std::string("paper_bench"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(compensate, paper_bench_default, std::string("paper_bench"), pbc::Mode::kDefault)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(compensate, paper_bench_paper, std::string("paper_bench"), pbc::Mode::kPaper)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(readFloor, moored_sea_state_4, std::string("moored_sea_state_4"))->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(compensate, moored_sea_state_4_default, std::string("moored_sea_state_4"), pbc::Mode::kDefault)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(compensate, moored_sea_state_4_paper, std::string("moored_sea_state_4"), pbc::Mode::kPaper)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(fftAnalysis)->Arg(1)->Arg(10)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
