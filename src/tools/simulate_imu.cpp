// simulate_imu: runs a simulator scenario and writes a bag (and optionally a CSV) without a
// ROS master. See docs/simulator.md. Outputs are renamed into place when complete and never
// written over the scenario. Exit status: 0 success, 1 error, 2 wrong command line.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <ros/time.h>
#include <rosbag/bag.h>

#include "periodic_bias_compensation/ros/sim_messages.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace sim = periodic_bias_compensation::sim;
namespace pbc = periodic_bias_compensation;

namespace
{
const char* kUsage =
    "usage: simulate_imu --scenario FILE.yaml [--out OUT.bag] [--csv OUT.csv] [--seed N]\n"
    "                    [--duration S] [--start-time S] [--print-scenario]\n"
    "       simulate_imu --list-effects\n"
    "--print-scenario writes the scenario with every default filled in (YAML) to stdout and exits.\n"
    "Without --out and --csv the scenario is only simulated (timing).\n";

struct Options
{
  std::string scenario;
  std::string bag;
  std::string csv;
  bool has_seed = false;
  std::uint64_t seed = 0;
  bool has_duration = false;
  double duration = 0.0;
  bool has_start_time = false;
  double start_time = 0.0;
  bool list_effects = false;
  bool print_scenario = false;
};

/// The options, or nothing after --help.
std::optional<Options> parseOptions(int argc, char** argv)
{
  Options o;
  pbc::CommandLine cli(kUsage);
  cli.text("--scenario", &o.scenario)
      .text("--out", &o.bag)
      .text("--csv", &o.csv)
      .integer("--seed", &o.seed, &o.has_seed)
      .number("--duration", &o.duration, &o.has_duration)
      .number("--start-time", &o.start_time, &o.has_start_time)
      .flag("--list-effects", &o.list_effects)
      .flag("--print-scenario", &o.print_scenario);
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if (!o.list_effects && o.scenario.empty())
    throw pbc::UsageError("--scenario is required");
  pbc::refuseOverwritingInputs({ { "--scenario", o.scenario } }, { { "--out", o.bag }, { "--csv", o.csv } });
  return o;
}

void listEffects()
{
  for (const sim::EffectInfo& e : sim::effectVocabulary())
  {
    std::cout << e.name;
    for (const sim::ParamInfo& p : e.params)
    {
      std::cout << " " << p.name << "[" << p.unit << "]";
    }
    std::cout << "\n";
  }
}

void writeCsvHeader(std::ostream& out)
{
  out << "index,t,stamp,dropped,ax,ay,az,gx,gy,gz,qw,qx,qy,qz,temperature,"
         "px,py,pz,vx,vy,vz,acc_x,acc_y,acc_z,att_w,att_x,att_y,att_z,wx,wy,wz,"
         "slow_px,slow_py,slow_pz,slow_vx,slow_vy,slow_vz,wave_px,wave_py,wave_pz,wave_vx,wave_vy,wave_vz\n";
}

void writeCsvRow(std::ostream& out, const sim::Sample& s)
{
  const auto v = [&out](const sim::Vector3& x) { out << ',' << x.x() << ',' << x.y() << ',' << x.z(); };
  const auto q = [&out](const sim::Quaternion& x) {
    out << ',' << x.w() << ',' << x.x() << ',' << x.y() << ',' << x.z();
  };
  out << s.index << ',' << s.t << ',' << s.stamp << ',' << (s.dropped ? 1 : 0);
  v(s.accel);
  v(s.gyro);
  q(s.orientation);
  out << ',' << (s.has_temperature ? s.temperature : 0.0);
  const sim::Truth& t = s.truth;
  v(t.position);
  v(t.velocity);
  v(t.acceleration);
  q(t.attitude);
  v(t.angular_rate);
  v(t.slow_position);
  v(t.slow_velocity);
  v(t.wave_position);
  v(t.wave_velocity);
  out << '\n';
}

int run(const Options& o)
{
  sim::Scenario scenario = sim::loadScenario(o.scenario);
  if (o.has_duration)
  {
    scenario.duration = o.duration;
  }
  if (o.has_start_time)
  {
    scenario.start_time = o.start_time;
  }
  const std::uint64_t seed = o.has_seed ? o.seed : scenario.seed;
  sim::Simulator simulator(scenario, seed);
  if (o.print_scenario)
  {
    sim::Scenario shown = simulator.scenario();
    shown.seed = seed;
    std::cout << sim::toYaml(shown);
    return 0;
  }
  const pbc::SimMessageBuilder builder(simulator.scenario());

  // Written under temporary names, renamed when complete (tools/output_file.h).
  std::optional<pbc::OutputFile> bag_file, csv_file;
  std::unique_ptr<rosbag::Bag> bag;
  if (!o.bag.empty())
  {
    bag_file.emplace(o.bag);
    bag = std::make_unique<rosbag::Bag>(bag_file->temporary(), rosbag::bagmode::Write);
  }
  std::ofstream csv;
  if (!o.csv.empty())
  {
    csv_file.emplace(o.csv);
    csv.open(csv_file->temporary());
    csv << std::setprecision(17);
    writeCsvHeader(csv);
  }

  const auto start = std::chrono::steady_clock::now();
  sim::Sample s;
  pbc::SimMessages messages;
  std::int64_t dropped = 0;
  while (simulator.next(&s))
  {
    dropped += s.dropped ? 1 : 0;
    if (csv.is_open())
    {
      writeCsvRow(csv, s);
    }
    if (!bag)
    {
      continue;
    }
    using Topics = pbc::SimTopics;
    const ros::Time t(s.t);
    builder.build(s, &messages);
    if (messages.has_imu)
    {
      bag->write(Topics::kImu, t, messages.imu);
    }
    if (messages.has_temperature)
    {
      bag->write(Topics::kTemperature, t, messages.temperature);
    }
    bag->write(Topics::kTruth, t, messages.truth);
    bag->write(Topics::kTruthSlow, t, messages.truth_slow);
    bag->write(Topics::kTruthWave, t, messages.truth_wave);
  }
  if (bag)
  {
    bag->close();
    bag_file->commit();
  }
  if (csv.is_open())
  {
    csv.close();
    if (!csv)
    {
      throw std::runtime_error("cannot write output '" + o.csv + "' (disk full?)");
    }
    csv_file->commit();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cerr << "simulate_imu: " << simulator.sampleCount() << " samples (" << dropped << " dropped), "
            << simulator.scenario().duration << " s at " << simulator.scenario().rate << " Hz, seed " << seed << ", "
            << seconds << " s wall";
  if (bag)
  {
    std::cerr << " -> " << o.bag;
  }
  if (csv_file)
  {
    std::cerr << " -> " << o.csv;
  }
  std::cerr << "\n";
  return 0;
}
}  // namespace

int main(int argc, char** argv)
{
  try
  {
    const std::optional<Options> options = parseOptions(argc, argv);
    if (!options)
      return 0;
    const Options& o = *options;
    if (o.list_effects)
    {
      listEffects();
      return 0;
    }
    ros::Time::init();
    return run(o);
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "simulate_imu: " << e.what() << "\n" << kUsage;
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "simulate_imu: " << e.what() << "\n";
    return 1;
  }
}
