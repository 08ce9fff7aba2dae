// diagnose_gap: where the sim-to-real gap lies, which unmodelled effect causes it, and how far it
// shrinks once that effect is added (measured on the withheld part of the recording).
//
//   diagnose_gap --real REAL.bag --sim SCENARIO.yaml --out DIR [--imu-topic imu/data]
//                [--truth-topic ground_truth/odometry] [--temperature-topic imu/temperature]
//   diagnose_gap --real-csv FILE --columns t=COL,ax=COL,ay=COL,az=COL,gx=COL,gy=COL,gz=COL
//                [--accel-scale K] [--gyro-scale K] [--time-scale K] [--rate HZ] [--skip-lines N]
//                [--ned] --sim SCENARIO.yaml --out DIR
//   common: [--ensemble N] [--fit-fraction F] [--threads N] [--no-plots] [--max-duration S]
//           [--truth-smooth S] [--no-truth]
//
// Truth: in a bag, nav_msgs/Odometry on --truth-topic (used when present; an explicit
// --truth-topic without messages is an error); in a CSV, columns px,py,pz (world, z up, times
// --truth-position-scale) and qw,qx,qy,qz (body -> world). A CSV's columns roll,pitch,yaw are the
// sensor's reported orientation (z-y-x angles [rad]); --ned: the file's axes are x forward, y right,
// z down and its angles against north-east-down (turned into REP-103/REP-145 on reading). The report then compares real minus
// the ideal IMU driven by that truth with the same residual of every simulated run.
// COL is a column name of the CSV header or a 0-based index, optionally prefixed with '-' to
// negate it; without a t column the time is k / rate. Scales convert to SI (e.g. --accel-scale
// 9.80665 for g, --gyro-scale 0.0174532925 for deg/s). Writes DIR/report.json, DIR/report.md,
// DIR/*.csv and (with python3-matplotlib) DIR/*.png, each renamed into place when complete and
// never over an input (tools/output_file.h); prints a one-screen summary.
// Exit status: 0 done, 1 error, 2 wrong command line.
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/exception.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/Temperature.h>
#include <nlohmann/json.hpp>

#include "periodic_bias_compensation/gap/csv.h"
#include "periodic_bias_compensation/gap/gap.h"
#include "periodic_bias_compensation/ros/bag_check.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace fs = std::filesystem;
namespace gap = periodic_bias_compensation::gap;
namespace sim = periodic_bias_compensation::sim;

namespace
{
const char* const kUsage =
    "usage: diagnose_gap (--real REAL.bag | --real-csv FILE --columns t=C,ax=C,...,gz=C) --sim SCENARIO.yaml --out "
    "DIR\n"
    "         [--imu-topic imu/data] [--truth-topic ground_truth/odometry] [--temperature-topic imu/temperature]\n"
    "         [--accel-scale K] [--gyro-scale K] [--time-scale K] [--rate HZ] [--skip-lines N] [--ned]\n"
    "         [--ensemble N] [--fit-fraction F] [--threads N] [--max-duration S] [--steps N] [--no-plots]\n"
    "         [--truth-smooth S] [--no-truth] [--truth-position-scale K] (CSV truth columns px,py,pz,qw,qx,qy,qz)\n";

using periodic_bias_compensation::UsageError;

/// The files diagnose_gap writes in --out (the plots aside).
const char* const kReportFiles[] = { "report.json", "fitted_scenario.yaml", "psd.csv",   "allan.csv",
                                     "drift.csv",   "features.csv",         "truth.csv", "motion.csv",
                                     "report.md" };

struct Options
{
  std::string real, real_csv, columns, scenario, out;
  std::string imu_topic = "imu/data";
  std::string truth_topic = "ground_truth/odometry";
  bool truth_topic_given = false;
  bool use_truth = true;
  double truth_position_scale = 1.0;
  std::string temperature_topic = "imu/temperature";
  double accel_scale = 1.0, gyro_scale = 1.0, time_scale = 1.0, rate = 0.0, max_duration = 0.0;
  int skip_lines = 0;
  bool ned = false;
  int steps = 5;
  bool plots = true;
  gap::DiagnoseOptions diag;
};

std::string absoluteTopic(const std::string& t)
{
  return (!t.empty() && t.front() == '/') ? t : "/" + t;
}

gap::Recording readBagUnchecked(const Options& o)
{
  rosbag::Bag bag(o.real, rosbag::bagmode::Read);
  gap::Recording r;
  r.source = o.real;
  std::vector<std::array<double, 6>> rows;
  std::vector<std::pair<double, double>> temps;
  bool orientation_ok = true;
  const std::string imu = absoluteTopic(o.imu_topic), temp = absoluteTopic(o.temperature_topic);
  rosbag::View view(bag);
  for (const rosbag::MessageInstance& m : view)
  {
    const std::string topic = absoluteTopic(m.getTopic());
    if (topic == imu)
    {
      const auto msg = m.instantiate<sensor_msgs::Imu>();
      if (!msg)
      {
        throw std::runtime_error("topic " + o.imu_topic + " is not sensor_msgs/Imu");
      }
      r.stamp.push_back(msg->header.stamp.toSec());
      rows.push_back({ msg->linear_acceleration.x, msg->linear_acceleration.y, msg->linear_acceleration.z,
                       msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z });
      const auto& q = msg->orientation;
      const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
      orientation_ok = orientation_ok && msg->orientation_covariance[0] >= 0 && std::abs(norm - 1.0) < 1e-3;
      r.orientation.emplace_back(q.w, q.x, q.y, q.z);
    }
    else if (o.use_truth && topic == absoluteTopic(o.truth_topic))
    {
      const auto msg = m.instantiate<nav_msgs::Odometry>();
      if (!msg)
      {
        throw std::runtime_error("topic " + o.truth_topic + " is not nav_msgs/Odometry");
      }
      const auto& p = msg->pose.pose;
      const auto& tw = msg->twist.twist;
      r.truth.stamp.push_back(msg->header.stamp.toSec());
      r.truth.position.emplace_back(p.position.x, p.position.y, p.position.z);
      r.truth.orientation.emplace_back(
          Eigen::Quaterniond(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z).normalized());
      r.truth.velocity.emplace_back(tw.linear.x, tw.linear.y, tw.linear.z);
      r.truth.angular_velocity.emplace_back(tw.angular.x, tw.angular.y, tw.angular.z);
      r.truth.has_twist = true;
    }
    else if (topic == temp)
    {
      const auto msg = m.instantiate<sensor_msgs::Temperature>();
      if (msg)
      {
        temps.push_back({ msg->header.stamp.toSec(), msg->temperature });
      }
    }
  }
  if (rows.empty())
  {
    throw std::runtime_error("no messages on " + o.imu_topic + " in " + o.real);
  }
  if (o.use_truth && o.truth_topic_given && r.truth.size() < 3)
  {
    throw std::runtime_error("no nav_msgs/Odometry on " + o.truth_topic + " in " + o.real);
  }
  r.data.resize(rows.size(), gap::kChannels);
  for (std::size_t i = 0; i < rows.size(); ++i)
  {
    for (int c = 0; c < gap::kChannels; ++c)
    {
      r.data(i, c) = rows[i][c];
    }
  }
  r.has_orientation = orientation_ok;
  if (!orientation_ok)
  {
    r.orientation.clear();
  }
  if (!temps.empty())
  {
    std::sort(temps.begin(), temps.end());
    r.has_temperature = true;
    std::size_t j = 0;
    for (double t : r.stamp)
    {
      while (j + 1 < temps.size() && temps[j + 1].first <= t)
      {
        ++j;
      }
      r.temperature.push_back(temps[j].second);
    }
  }
  return r;
}

/// The recording of --real; a bag that is missing, empty, cut off or corrupt is a
/// std::runtime_error that names it (ros/bag_check.h), never rosbag's text alone.
gap::Recording readBag(const Options& o)
{
  const std::string problem = periodic_bias_compensation::bagFileProblem(o.real);
  if (!problem.empty())
  {
    throw std::runtime_error(problem);
  }
  try
  {
    return readBagUnchecked(o);
  }
  catch (const rosbag::BagException& e)
  {
    throw std::runtime_error(periodic_bias_compensation::corruptBagMessage(o.real, e.what()));
  }
  catch (const ros::Exception& e)
  {
    throw std::runtime_error(periodic_bias_compensation::corruptBagMessage(o.real, e.what()));
  }
}

gap::Recording readCsv(const Options& o)
{
  gap::CsvOptions csv;
  csv.path = o.real_csv;
  csv.columns = o.columns;
  csv.skip_lines = o.skip_lines;
  csv.accel_scale = o.accel_scale;
  csv.gyro_scale = o.gyro_scale;
  csv.time_scale = o.time_scale;
  csv.truth_position_scale = o.truth_position_scale;
  csv.rate = o.rate;
  csv.use_truth = o.use_truth;
  csv.ned = o.ned;
  return gap::readCsv(csv);
}

/// Stamps shifted so that the first is 1000 s (the simulator's start), rate fixed.
void normalise(gap::Recording* r, double max_duration)
{
  const double t0 = r->stamp.front();
  for (double& t : r->stamp)
  {
    t = t - t0 + 1000.0;
  }
  for (double& t : r->truth.stamp)
  {
    t = t - t0 + 1000.0;
  }
  if (max_duration > 0)
  {
    std::size_t n = 0;
    while (n < r->size() && r->stamp[n] - 1000.0 < max_duration)
    {
      ++n;
    }
    r->stamp.resize(n);
    r->data.conservativeResize(n, gap::kChannels);
    if (r->has_orientation)
    {
      r->orientation.resize(n);
    }
    if (r->has_temperature)
    {
      r->temperature.resize(n);
    }
  }
  if (r->rate <= 0)
  {
    r->rate = gap::estimateRate(*r);
  }
}

/// std::system(command). std::system ignores SIGINT while the command runs: when Ctrl-C (or
/// SIGTERM) ends the command, this process then ends by that signal too (its temporaries removed).
int runCommand(const std::string& command)
{
  const int status = std::system(command.c_str());
  for (const int signal_number : { SIGINT, SIGTERM })
  {
    if ((WIFSIGNALED(status) && WTERMSIG(status) == signal_number) ||
        (WIFEXITED(status) && WEXITSTATUS(status) == 128 + signal_number))
    {
      std::raise(signal_number);
    }
  }
  return status;
}

std::string reportMarkdown(const gap::Report& rep, const Options& o, bool plots)
{
  std::ostringstream md;
  char buf[512];
  md << "# Sim-to-real gap: " << rep.real_source << " vs " << o.scenario << "\n\n";
  std::snprintf(buf, sizeof(buf),
                "%zu samples, %.6g Hz, %.1f s; ensemble of %d simulated runs; the fit saw the first %.0f %%, the gap "
                "is measured on the last %.0f %%. Wall time %.1f s.\n\n",
                rep.samples, rep.rate, rep.duration, o.diag.ensemble, 100 * o.diag.fit_fraction,
                100 * (1 - o.diag.fit_fraction), rep.seconds);
  md << buf;
  md << "## Verdict\n\n**" << rep.verdict_effect << "** (confidence " << rep.confidence
     << ", shrink on the withheld part " << static_cast<int>(std::lround(100 * rep.shrink_withheld))
     << " %): " << rep.verdict_text << "\n\nparams: `" << rep.verdict_params.dump() << "`\n\n";
  md << "## 0. Motion (before any sensor effect)\n\n";
  const gap::MotionFit& m = rep.motion;
  if (!m.differs)
    md << "The recording's motion is the scenario's (tilt, heading, sea state within the ensemble's spread).\n\n";
  else if (m.adopted.empty())
    md << "The recording's motion **differs** from the scenario's; no fit of it brought the withheld part closer, so "
          "sensor effects below are judged against the scenario as given.\n\n";
  else
    md << "The recording's motion **differs** from the scenario's; sensor effects below are judged against the "
          "scenario with the recording's "
       << m.adopted << " (`fitted_scenario.yaml` carries it).\n\n";
  for (const std::string& finding : m.findings)
    md << "- " << finding << "\n";
  std::snprintf(
      buf, sizeof(buf),
      "%s| | roll [rad] | pitch [rad] | heave Hs [m] | peak period [s] |\n|---|---|---|---|---|\n"
      "| recording | %+.4f | %+.4f | %.3g | %.3g |\n| scenario (ensemble mean) | %+.4f | %+.4f | %.3g | %.3g |\n\n"
      "Withheld gap against the scenario as given %.3g, against the fitted one %.3g.\n\n",
      m.findings.empty() ? "" : "\n", m.real.roll, m.real.pitch, m.real.wave_height, m.real.peak_period,
      m.scenario.roll, m.scenario.pitch, m.scenario.wave_height, m.scenario.peak_period, m.gap_before, m.gap_after);
  md << buf;
  if (!m.left_out.empty())
  {
    md << "The fitted motion leaves the withheld part far beyond the ensemble's own spread (a motion the "
          "scenario's kind cannot take): its "
       << m.left_out.size()
       << " features that the motion reaches and the fit leaves departed are left out of the sensor diagnosis "
          "(`left_out` in features.csv), so that no sensor effect is credited with them; an effect that acts only "
          "there cannot be named. They include: ";
    for (std::size_t i = 0; i < std::min<std::size_t>(6, m.left_out.size()); ++i)
      md << (i ? ", " : "") << "`" << m.left_out[i] << "`";
    md << (m.left_out.size() > 6 ? ", ...\n\n" : ".\n\n");
  }
  if (plots && !rep.motion_csv.empty())
    md << "![heave spectra: recording, scenario as given, fitted](motion.png)\n\n";
  md << "## 1. Where (whole recording)\n\n";
  std::snprintf(
      buf, sizeof(buf),
      "gap %.3g; one ensemble member against the others: up to %.3g. Departures (|z| > 3), largest first:\n\n",
      rep.gap_all, rep.null_gap);
  md << buf
     << "| axis | quantity | band / tau | segment | stage | real | sim (median) | z "
        "|\n|---|---|---|---|---|---|---|---|\n";
  for (const auto& d : rep.where)
  {
    std::snprintf(buf, sizeof(buf), "| %s | %s | %s | %s | %s | %.5g | %.5g | %+.3g |\n", d.where.channel.c_str(),
                  d.where.quantity.c_str(), d.where.range.c_str(), d.where.segment.c_str(), d.where.stage.c_str(),
                  d.real, d.sim_median, d.z);
    md << buf;
  }
  md << "\nDirectly visible effects:\n\n";
  for (const auto& d : rep.direct)
  {
    md << "- " << d.effect << ": " << (d.detected ? "**yes**" : "no") << " (" << d.evidence << ")\n";
  }
  if (plots)
  {
    md << "\n![gap heat map](heatmap.png)\n\n![drift](drift.png)\n";
  }
  if (rep.has_truth)
  {
    md << "\n### Against the truth (sample by sample)\n\nReal minus the ideal IMU driven by the recording's truth "
          "(both smoothed over "
       << o.diag.truth_smooth
       << " s), per axis and time segment, against the same residual of "
          "every simulated run (its own truth). Departures (|z| > 3): "
       << rep.truth_where.size() << "\n\n"
       << "| axis | quantity | time | segment | real | sim (median) | z |\n|---|---|---|---|---|---|---|\n";
    for (const auto& d : rep.truth_where)
    {
      std::snprintf(buf, sizeof(buf), "| %s | %s | %s | %s | %.5g | %.5g | %+.3g |\n", d.where.channel.c_str(),
                    d.where.quantity.c_str(), d.where.range.c_str(), d.where.segment.c_str(), d.real, d.sim_median,
                    d.z);
      md << buf;
    }
    if (plots)
    {
      md << "\n![truth residual](truth.png)\n";
    }
  }
  md << "\n## 2. Which effect (fit on the first part, judged on the withheld part)\n\n";
  std::snprintf(buf, sizeof(buf),
                "Gap of the scenario as given on the withheld part: %.3g (typical member vs the rest: %.3g).\n\n",
                rep.gap_before, rep.null_gap_typical);
  md << buf
     << "Shrink on what it moves: the same measure over the features the candidate moves only "
        "(its ensemble median beyond "
     << gap::kMovedSpreads
     << " spreads of the base's), how much of its own departures it explains whatever else the gap holds.\n\n";
  md << "| rank | effect | gap before | gap after | shrink | shrink on what it moves (features) | fitted parameters |\n"
        "|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < rep.ranking.size(); ++i)
  {
    const auto& c = rep.ranking[i];
    std::snprintf(buf, sizeof(buf), "| %zu | %s | %.3g | %.3g | %.0f %% | %.0f %% (%d) | `", i + 1, c.effect.c_str(),
                  c.gap_before, c.gap_after, 100 * c.shrink, 100 * c.own.shrink, c.own.moved);
    md << buf << c.params.dump() << "`";
    for (const std::string& limit : c.at_limit)
    {
      md << "<br>at a search limit: " << limit;
    }
    md << " |\n";
  }
  md << "\n## 3. How far it shrinks (withheld part, the places of largest departure)\n\n";
  md << "| axis | quantity | band / tau | segment | z before | z after |\n|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < rep.where_held.size(); ++i)
  {
    const auto& d = rep.where_held[i];
    std::snprintf(buf, sizeof(buf), "| %s | %s | %s | %s | %+.3g | %s |\n", d.where.channel.c_str(),
                  d.where.quantity.c_str(), d.where.range.c_str(), d.where.segment.c_str(), d.z,
                  i < rep.where_held_after.size() ? std::to_string(rep.where_held_after[i]).c_str() : "-");
    md << buf;
  }
  if (plots)
  {
    md << "\n![spectra](spectra.png)\n\n![allan](allan.png)\n";
  }
  md << "\nMethod and limits: docs/gap.md of periodic_bias_compensation.\n";
  return md.str();
}

/// The options, or nothing after --help (a wrong command line throws).
std::optional<Options> parse(int argc, char** argv)
{
  Options o;
  periodic_bias_compensation::CommandLine cli(kUsage);
  cli.text("--real", &o.real)
      .text("--real-csv", &o.real_csv)
      .text("--columns", &o.columns)
      .text("--sim", &o.scenario)
      .text("--out", &o.out)
      .text("--imu-topic", &o.imu_topic)
      .option("--truth-topic",
              [&o](const std::string& topic) {
                o.truth_topic = topic;
                o.truth_topic_given = true;
              })
      .flag("--no-truth", &o.use_truth, false)
      .number("--truth-smooth", &o.diag.truth_smooth)
      .number("--truth-position-scale", &o.truth_position_scale)
      .text("--temperature-topic", &o.temperature_topic)
      .number("--accel-scale", &o.accel_scale)
      .number("--gyro-scale", &o.gyro_scale)
      .number("--time-scale", &o.time_scale)
      .number("--rate", &o.rate)
      .integer("--skip-lines", &o.skip_lines)
      .flag("--ned", &o.ned, true)
      .integer("--ensemble", &o.diag.ensemble)
      .number("--fit-fraction", &o.diag.fit_fraction)
      .integer("--threads", &o.diag.threads)
      .number("--max-duration", &o.max_duration)
      .flag("--no-plots", &o.plots, false)
      .integer("--steps", &o.steps);
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if ((o.real.empty() == o.real_csv.empty()) || o.scenario.empty() || o.out.empty())
  {
    throw UsageError("one of --real / --real-csv, and --sim and --out are required");
  }
  if (!o.real_csv.empty() && o.columns.empty())
  {
    throw UsageError("--real-csv needs --columns");
  }
  if (o.diag.fit_fraction <= 0.1 || o.diag.fit_fraction >= 0.9)
  {
    throw UsageError("--fit-fraction must be in (0.1, 0.9)");
  }
  periodic_bias_compensation::requireAtLeast("--ensemble", o.diag.ensemble, 1);
  periodic_bias_compensation::requireAtLeast("--threads", o.diag.threads, 1);
  periodic_bias_compensation::requireAtLeast("--steps", o.steps, 0);
  periodic_bias_compensation::requireAtLeast("--skip-lines", o.skip_lines, 0);
  std::vector<periodic_bias_compensation::NamedPath> outputs;
  for (const char* name : kReportFiles)
  {
    outputs.push_back({ "--out", (fs::path(o.out) / name).string() });
  }
  periodic_bias_compensation::refuseOverwritingInputs(
      { { "--real", o.real }, { "--real-csv", o.real_csv }, { "--sim", o.scenario } }, outputs);
  return o;
}

/// One step of the stepwise diagnosis: the effect named and the figures it was named with.
struct Step
{
  std::string effect;
  nlohmann::ordered_json params;
  double gap_before, shrink, confidence;
};

/// The steps taken and the model with every named effect.
struct Stepwise
{
  std::vector<Step> steps;
  sim::Scenario model;
};

/// Stepwise: adds the named effect to the model and diagnoses again, while an effect is named
/// (at most `steps` times; rep is the first diagnosis).
Stepwise stepwiseDiagnosis(const gap::Report& rep, const gap::Recording& real, const sim::Scenario& scenario,
                           const Options& o)
{
  Stepwise result;
  std::vector<Step>& steps = result.steps;
  sim::Scenario& model = result.model;
  model = scenario;
  model.motion = rep.motion.fitted.motion;  // the motion fitted once; effects added step by step
  const gap::Report* cur = &rep;
  gap::Report next;
  for (int k = 0; k < o.steps; ++k)
  {
    // forward selection: the verdict's effect, or failing that the best candidate if it
    // explains at least 5 % (several effects together may explain what none does alone)
    int pick = cur->best;
    if (pick < 0 && cur->verdict_effect != "no_gap" && !cur->ranking.empty() && cur->ranking[0].shrink >= 0.05)
    {
      pick = 0;
    }
    if (pick < 0)
    {
      steps.push_back({ cur->verdict_effect, nlohmann::ordered_json::object(), cur->gap_before, 0.0, 0.0 });
      break;
    }
    const gap::Candidate& c = cur->ranking[pick];
    steps.push_back({ c.effect, c.params, cur->gap_before, c.shrink, cur->confidence });
    model = gap::applyCandidate(model, c);
    if (k + 1 < o.steps)
    {
      std::fprintf(stderr, "diagnose_gap: step %d of at most %d: %s added, judging the candidates again\n", k + 2,
                   o.steps, c.effect.c_str());
      next = gap::diagnoseStep(real, model, rep, o.diag);
      cur = &next;
      std::fprintf(stderr, "diagnose_gap: step %d: verdict %s, withheld gap %.3g (%.1f s)\n", k + 2,
                   cur->verdict_effect.c_str(), cur->gap_before, cur->seconds);
    }
  }
  return result;
}

/// report.json: the report with its "stepwise" array before "seconds", indented by 2.
std::string stepwiseJson(const gap::Report& rep, const std::vector<Step>& steps)
{
  nlohmann::ordered_json stepwise = nlohmann::ordered_json::array();
  for (std::size_t i = 0; i < steps.size(); ++i)
  {
    stepwise.push_back({ { "step", i + 1 },
                         { "effect", steps[i].effect },
                         { "gap_before", gap::sixDigits(steps[i].gap_before) },
                         { "shrink", gap::sixDigits(steps[i].shrink) },
                         { "confidence", gap::sixDigits(steps[i].confidence) },
                         { "params", steps[i].params } });
  }
  nlohmann::ordered_json json = gap::reportJson(rep);
  const nlohmann::ordered_json seconds = json["seconds"];
  json.erase("seconds");
  json["stepwise"] = stepwise;
  json["seconds"] = seconds;
  // A path that is not UTF-8 (the source) gets U+FFFD for its invalid bytes.
  return json.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";
}

/// The plots of DIR (scripts/gap_plots.py); whether they were made.
bool makePlots(const gap::Report& rep, const Options& o)
{
  const std::string script = std::string(PBC_SOURCE_DIR) + "/scripts/gap_plots.py";
  const std::string cmd = "/usr/bin/python3 '" + script + "' --dir '" + o.out + "' --title '" +
                          fs::path(rep.real_source).filename().string() + " vs " + rep.scenario_name + ": " +
                          rep.verdict_effect + "' > /dev/null 2>&1";
  const bool plots = runCommand(cmd) == 0;
  if (!plots)
  {
    std::cerr << "diagnose_gap: plots not made (" << script << " with python3-matplotlib)\n";
  }
  return plots;
}

/// report.md's table of the steps.
std::string stepwiseMarkdown(const std::vector<Step>& steps)
{
  std::ostringstream sm;
  sm << "\n## Stepwise (each named effect added to the model, then diagnosed again)\n\n"
     << "| step | effect named | gap before (withheld) | shrink | confidence | parameters "
        "|\n|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < steps.size(); ++i)
  {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "| %zu | %s | %.3g | %.0f %% | %.2f | `", i + 1, steps[i].effect.c_str(),
                  steps[i].gap_before, 100 * steps[i].shrink, steps[i].confidence);
    sm << buf << steps[i].params.dump() << "` |\n";
  }
  sm << "\nThe model with every named effect: `fitted_scenario.yaml`.\n";
  return sm.str();
}

/// The summary's line of the steps.
std::string stepwiseLine(const std::vector<Step>& steps)
{
  std::ostringstream so;
  so << "STEPWISE:";
  for (std::size_t i = 0; i < steps.size(); ++i)
  {
    char buf[160];
    std::snprintf(buf, sizeof(buf), " %s%s (gap %.3g, shrink %.0f %%)", i ? "-> " : "", steps[i].effect.c_str(),
                  steps[i].gap_before, 100 * steps[i].shrink);
    so << buf;
  }
  return so.str();
}

/// Writes a file of the report to DIR.
void writeFile(const Options& o, const std::string& name, const std::string& contents)
{
  periodic_bias_compensation::writeOutputFile((fs::path(o.out) / name).string(), contents);
}

/// Writes the first diagnosis's curves to DIR (its plots' data).
void writeCurves(const gap::Report& rep, const Options& o)
{
  writeFile(o, "psd.csv", rep.psd_csv);
  writeFile(o, "allan.csv", rep.allan_csv);
  writeFile(o, "drift.csv", rep.drift_csv);
  writeFile(o, "features.csv", rep.features_csv);
  if (rep.has_truth)
  {
    writeFile(o, "truth.csv", rep.truth_csv);
  }
  if (!rep.motion_csv.empty())
  {
    writeFile(o, "motion.csv", rep.motion_csv);
  }
}

/// Writes the report's files to DIR; `plots`: whether the plots were made.
void writeReport(const gap::Report& rep, const Stepwise& s, const Options& o, bool plots)
{
  writeFile(o, "report.json", stepwiseJson(rep, s.steps));
  writeFile(o, "fitted_scenario.yaml", sim::toYaml(s.model));
  std::string md = reportMarkdown(rep, o, plots);
  md.insert(md.find("\nMethod and limits"), stepwiseMarkdown(s.steps));
  writeFile(o, "report.md", md);
}
}  // namespace

int main(int argc, char** argv)
{
  Options o;
  try
  {
    const std::optional<Options> parsed = parse(argc, argv);
    if (!parsed)
      return 0;
    o = *parsed;
  }
  catch (const std::exception& e)
  {
    std::cerr << "diagnose_gap: " << e.what() << "\n" << kUsage;
    return 2;
  }
  sim::Scenario scenario;
  gap::Recording real;
  try
  {
    scenario = sim::loadScenario(o.scenario);
    real = o.real.empty() ? readCsv(o) : readBag(o);
    // Before the diagnosis: a directory that cannot be written is said at once.
    periodic_bias_compensation::prepareOutputDirectory(o.out);
  }
  catch (const gap::CsvOptionError& e)
  {
    std::cerr << "diagnose_gap: " << e.what() << "\n" << kUsage;
    return 2;
  }
  catch (const std::exception& e)
  {
    std::cerr << "diagnose_gap: " << e.what() << "\n";
    return 1;
  }
  try
  {
    normalise(&real, o.max_duration);
    std::fprintf(stderr, "diagnose_gap: %zu samples (%.0f s) against '%s', ensemble %d: diagnosing\n", real.size(),
                 real.size() > 1 ? real.stamp.back() - real.stamp.front() : 0.0, scenario.name.c_str(),
                 o.diag.ensemble);
    const gap::Report rep = gap::diagnose(real, scenario, o.diag);
    std::fprintf(stderr, "diagnose_gap: step 1: verdict %s, withheld gap %.3g (%.1f s)\n", rep.verdict_effect.c_str(),
                 rep.gap_before, rep.seconds);
    // The plots are of the first diagnosis: drawn while the stepwise search runs.
    writeCurves(rep, o);
    std::future<bool> plots = std::async(std::launch::async, [&rep, &o]() { return o.plots && makePlots(rep, o); });
    const Stepwise s = stepwiseDiagnosis(rep, real, scenario, o);
    writeReport(rep, s, o, plots.get());
    std::cout << gap::reportSummary(rep) << stepwiseLine(s.steps) << "\nreport: " << o.out << "/report.md, " << o.out
              << "/report.json, " << o.out << "/fitted_scenario.yaml\n";
  }
  catch (const std::exception& e)
  {
    std::cerr << "diagnose_gap: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
