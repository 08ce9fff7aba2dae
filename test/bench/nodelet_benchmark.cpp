// nodelet_benchmark: input rate, drops and latency of the compensator, in the same nodelet
// manager as a publisher (intra-process, zero-copy shared pointers) or as a separate process
// (compensator_node over TCP, started by the caller). Run by scripts/bench.py, not a test.
//
//   nodelet_benchmark --transport intra|tcp --scenario FILE.yaml --rate HZ --duration S
//                     [--closed-loop] [--stream] [--rss-csv FILE] [--rss-every N]
//                     [--latency-csv FILE]
//                     [--nodelet compensator|madgwick|relay] [--manager-queues]
//                     [--realtime-priority P] [--cpu N] [--cpu-wakeup-latency S]
//
// This program is the nodelet manager: a nodelet::Loader holding BenchSource (below) and, for
// `intra`, the compensator nodelet loaded through pluginlib as `nodelet load` would. BenchSource
// publishes imu/data from the scenario simulated at HZ, stamped t0 + k / HZ, and subscribes
// odometry/filtered, whose stamp is the input's: k gives the publish time kept here (latency =
// output received - input published, steady clock) and the drops (inputs without an output).
// Paced (default): inputs at HZ for S seconds. --closed-loop: as fast as the compensator takes
// them, at most kInFlight unanswered (its queue holds 1000), for S seconds of data. Samples are
// simulated once (up to kCachedSamples, then replayed with new stamps) unless --stream
// simulates each one (long runs; with --rss-csv the process RSS is written every N outputs).
// --latency-csv writes each answered input's k and latency [us] (the first kRing inputs), to
// find what recurs in the slow ones.
// --nodelet madgwick measures imu_tools' Madgwick filter nodelet (imu_filter_madgwick/
// ImuFilterNodelet, built outside this repository, found through ROS_PACKAGE_PATH) in the same
// harness, intra-process only: BenchSource then publishes imu/data_raw and times its imu/data.
// --nodelet relay measures the harness itself: a nodelet (Relay, below) that subscribes and
// publishes as the compensator's does and answers each imu/data with an odometry/filtered
// carrying its stamp and nothing else, intra-process only. Its latency and CPU time are what
// the manager's threads and queues cost with no estimator at all.
// The compensator and the relay serve imu/data on a thread of their own (the compensator's
// ~imu_thread, its default); --manager-queues puts it on the manager's queues instead. The
// harness receives the answers on a thread of its own in every case.
// --realtime-priority P schedules the threads a sample passes through at SCHED_FIFO priority P:
// the harness's publisher and receiver and the measured nodelet's own imu/data thread (the
// compensator's ~imu_thread_priority); not the manager's queues (so not with --manager-queues
// or Madgwick's nodelet). Refused (no CAP_SYS_NICE): an error, nothing measured. --cpu N runs
// every thread of the process on CPU N (with --realtime-priority: a thread woken by another is
// woken on its CPU, not on an idle one that has to come out of its idle state first).
// --cpu-wakeup-latency S holds a request that no CPU take longer than S seconds to come out of idle
// for the whole run (the compensator's ~cpu_wakeup_latency, asked by the harness for whichever
// nodelet is measured; 0: idle CPUs poll). Refused (no write access to /dev/cpu_dma_latency): an
// error, nothing measured.
// Output: one line of key=value pairs on stdout.
#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <future>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <nodelet/loader.h>
#include <nodelet/nodelet.h>
#include <pthread.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>
#include <unistd.h>
#include <pluginlib/class_loader.hpp>

#include "latency_settings.h"
#include "periodic_bias_compensation/ros/callback_thread.h"
#include "periodic_bias_compensation/ros/compensator_ros.h"
#include "periodic_bias_compensation/ros/cpu_wakeup_latency.h"
#include "periodic_bias_compensation/ros/sim_messages.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/tools/command_line.h"

namespace pbc = periodic_bias_compensation;
namespace sim = periodic_bias_compensation::sim;
using Clock = std::chrono::steady_clock;

namespace
{
constexpr std::int64_t kInFlight = 500;              ///< closed loop: unanswered inputs at most
constexpr std::size_t kCachedSamples = 60000;        ///< samples simulated once and replayed
constexpr std::size_t kRing = std::size_t(1) << 20;  ///< publish times kept (ring, by k)
constexpr std::uint32_t kStampSec = 1700000000;      ///< t0 [s], a Unix-like time

struct Options
{
  std::string transport;
  std::string scenario;
  double rate = 0.0;      ///< [Hz]
  double duration = 0.0;  ///< [s] of data
  bool closed_loop = false;
  bool stream = false;
  std::string rss_csv;
  std::int64_t rss_every = 6000;
  std::string latency_csv;
  std::string nodelet = "compensator";  ///< the nodelet measured: compensator, madgwick or relay
  bool manager_queues = false;          ///< the measured nodelet's imu/data on the manager's queues
  std::int64_t realtime_priority = 0;   ///< SCHED_FIFO priority of the sample's threads; 0: ordinary
  std::int64_t cpu = -1;                ///< the one CPU of every thread; -1: any
  double cpu_wakeup_latency = -1.0;     ///< [s] asked of every CPU for the run; < 0: no request
};

/// Ends the process where a thread was not made real-time (`granted` false, `why` from
/// setRealtimePriority): after the probe in main() was granted that is unexpected, and a
/// nodelet's onInit() has no way to fail its load.
void requireRealtime(bool granted, const std::string& why)
{
  if (granted)
    return;
  std::cerr << "nodelet_benchmark: " << why << std::endl;
  std::_Exit(1);
}

/// The nodelet measured: its plugin type and the topics it reads and answers on.
struct Measured
{
  const char* type;
  const char* input;
  const char* output;
};
const Measured kCompensator{ "periodic_bias_compensation/CompensatorNodelet", "imu/data", "odometry/filtered" };
const Measured kMadgwick{ "imu_filter_madgwick/ImuFilterNodelet", "imu/data_raw", "imu/data" };
const Measured kRelay{ "bench/Relay", "imu/data", "odometry/filtered" };

const Measured& measured(const Options& o)
{
  if (o.nodelet == "madgwick")
    return kMadgwick;
  return o.nodelet == "relay" ? kRelay : kCompensator;
}

/// The harness's floor: the compensator nodelet's subscription and publisher (queues, transport
/// hints, a shared pointer published from the callback) with an empty odometry as the answer.
class Relay : public nodelet::Nodelet
{
public:
  Relay(bool manager_queues, int realtime_priority)
    : manager_queues_(manager_queues), realtime_priority_(realtime_priority)
  {
  }

  ~Relay() override
  {
    sub_.shutdown();  // before its thread goes
  }

private:
  void onInit() override
  {
    ros::NodeHandle nh = getNodeHandle();
    pub_ = nh.advertise<nav_msgs::Odometry>(kRelay.output, pbc::CompensatorRos::kOutputQueue);
    ros::SubscribeOptions options;
    options.init<sensor_msgs::Imu>(kRelay.input, pbc::CompensatorRos::kImuQueue,
                                   [this](const sensor_msgs::Imu::ConstPtr& imu) { imuCallback(imu); });
    options.transport_hints = pbc::CompensatorRos::imuTransport();
    if (!manager_queues_)
    {
      thread_ = std::make_unique<pbc::CallbackThread>("relay");
      options.callback_queue = thread_->queue();
      if (realtime_priority_ > 0)
      {
        std::string why;
        requireRealtime(thread_->setRealtimePriority(realtime_priority_, &why), why);
      }
    }
    sub_ = nh.subscribe(options);
  }

  void imuCallback(const sensor_msgs::Imu::ConstPtr& imu)
  {
    auto odometry = boost::make_shared<nav_msgs::Odometry>();
    odometry->header = imu->header;
    pub_.publish(odometry);
  }

  bool manager_queues_;
  int realtime_priority_;
  std::unique_ptr<pbc::CallbackThread> thread_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
};

/// Latency histogram with constant memory: bins of 1/100 decade from 1 ns to 100 s.
class Histogram
{
public:
  void add(double seconds)
  {
    const double ns = std::max(seconds * 1e9, 1.0);
    ++bins_[std::min<std::size_t>(kBins - 1, static_cast<std::size_t>(std::log10(ns) * 100.0))];
    ++count_;
  }
  /// Upper edge of the bin holding quantile q [s] (resolution 2.3 %); NaN when empty.
  double quantile(double q) const
  {
    std::uint64_t seen = 0;
    const auto target = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(count_)));
    for (std::size_t i = 0; i < kBins; ++i)
    {
      seen += bins_[i];
      if (count_ > 0 && seen >= std::max<std::uint64_t>(target, 1))
      {
        return std::pow(10.0, static_cast<double>(i + 1) / 100.0) * 1e-9;
      }
    }
    return std::nan("");
  }

private:
  static constexpr std::size_t kBins = 1100;
  std::array<std::uint64_t, kBins> bins_{};
  std::uint64_t count_ = 0;
};

/// CPU time on `clock` [s]: CLOCK_PROCESS_CPUTIME_ID (every thread), CLOCK_THREAD_CPUTIME_ID (the
/// caller's thread) or a thread's clock (pthread_getcpuclockid).
double cpuSeconds(clockid_t clock)
{
  timespec t{};
  clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

long rssKilobytes()
{
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

/// The scenario's IMU messages at `rate`, frame base_link (identity mounting, no tf needed).
/// Highest rate the simulator accepts (sim::validate) [Hz].
constexpr double kMaxSimulatedRate = 1e5;

class SampleSource
{
public:
  explicit SampleSource(const Options& o) : stream_(o.stream)
  {
    sim::Scenario scenario = sim::loadScenario(o.scenario);
    // The simulator takes at most kMaxSimulatedRate; above it (a paced run at a fraction of an
    // idle machine's closed-loop rate) the same samples go out faster, stamped at the asked rate.
    scenario.rate = std::min(o.rate, kMaxSimulatedRate);
    scenario.duration = o.duration;
    simulator_ = std::make_unique<sim::Simulator>(scenario, scenario.seed);
    builder_ = std::make_unique<pbc::SimMessageBuilder>(simulator_->scenario());
    if (!stream_)
    {
      sensor_msgs::Imu imu;
      while (cache_.size() < kCachedSamples && simulate(&imu))
      {
        cache_.push_back(imu);
      }
      if (cache_.empty())
      {
        throw std::runtime_error("the scenario gave no IMU sample");
      }
    }
  }

  /// Message k (stamp set by the caller); false when a streamed scenario is over.
  bool get(std::int64_t k, sensor_msgs::Imu* imu)
  {
    if (!stream_)
    {
      *imu = cache_[static_cast<std::size_t>(k) % cache_.size()];
      return true;
    }
    return simulate(imu);
  }

private:
  bool simulate(sensor_msgs::Imu* imu)
  {
    sim::Sample sample;
    while (simulator_->next(&sample))
    {
      builder_->build(sample, &messages_);
      if (messages_.has_imu)
      {
        *imu = messages_.imu;
        imu->header.frame_id = "base_link";
        return true;
      }
    }
    return false;
  }

  bool stream_;
  std::unique_ptr<sim::Simulator> simulator_;
  std::unique_ptr<pbc::SimMessageBuilder> builder_;
  pbc::SimMessages messages_;
  std::vector<sensor_msgs::Imu> cache_;
};

/// Publisher of the measured nodelet's input and receiver of its output (imu/data and
/// odometry/filtered for the compensator), as a nodelet of the same manager.
class BenchSource : public nodelet::Nodelet
{
public:
  explicit BenchSource(const Options& o) : options_(o), published_(kRing)
  {
  }

  ~BenchSource() override
  {
    stop_ = true;
    if (thread_.joinable())
    {
      thread_.join();
    }
  }

  /// Waits until every input was sent and answered (or nothing came back for 3 s), then prints.
  void finish()
  {
    thread_.join();
    std::int64_t last = -1;
    auto last_change = Clock::now();
    while (Clock::now() - last_change < std::chrono::seconds(3))
    {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (received_ >= sent_)
        {
          break;
        }
        if (received_ != last)
        {
          last = received_;
          last_change = Clock::now();
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    // Everything sent was answered (or given up): the process's CPU time per input since the
    // first, and the same without the harness's two threads (the publisher, which replays cached
    // messages, and the receiver): the nodelet measured, its manager and roscpp's threads.
    const double messages = static_cast<double>(std::max<std::int64_t>(sent_, 1));
    const double process_cpu = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_start_;
    const double harness_cpu = publisher_cpu_ + cpuSeconds(receiver_clock_) - receiver_cpu_start_;
    sub_.shutdown();  // before the manager's callback queues go
    pub_.shutdown();
    std::lock_guard<std::mutex> lock(mutex_);
    const double wall = std::chrono::duration<double>(end_ - start_).count();
    std::cout << "transport=" << options_.transport << " mode=" << (options_.closed_loop ? "closed" : "paced")
              << " rate=" << options_.rate << " sent=" << sent_ << " received=" << received_
              << " dropped=" << sent_ - received_ << " send_wall_s=" << wall
              << " input_rate=" << static_cast<double>(sent_) / wall << " p50_us=" << latency_.quantile(0.5) * 1e6
              << " p99_us=" << latency_.quantile(0.99) * 1e6 << " p999_us=" << latency_.quantile(0.999) * 1e6
              << " max_us=" << max_latency_ * 1e6 << " max_at_s=" << max_at_
              << " cpu_us_per_msg=" << process_cpu / messages * 1e6
              << " nodelet_cpu_us_per_msg=" << (process_cpu - harness_cpu) / messages * 1e6
              << " rss_kb=" << rssKilobytes() << " nodelet=" << options_.nodelet
              << " queues=" << (options_.manager_queues || options_.nodelet == "madgwick" ? "manager" : "own")
              << " realtime_priority=" << options_.realtime_priority << " cpu=" << options_.cpu
              << " cpu_wakeup_latency=" << options_.cpu_wakeup_latency << std::endl;
    if (!options_.rss_csv.empty())
    {
      std::ofstream csv(options_.rss_csv);
      csv << "data_hours,outputs,rss_kb,wall_s\n";
      for (const auto& r : rss_)
      {
        csv << r.data_hours << ',' << r.outputs << ',' << r.rss_kb << ',' << r.wall_s << '\n';
      }
    }
    if (!options_.latency_csv.empty())
    {
      std::ofstream csv(options_.latency_csv);
      csv << "k,latency_us\n";
      for (const auto& [k, latency] : latencies_)
        csv << k << ',' << latency * 1e6 << '\n';
      if (!csv)
        std::cerr << "nodelet_benchmark: cannot write " << options_.latency_csv << std::endl;
    }
  }

private:
  struct RssRow
  {
    double data_hours;
    std::int64_t outputs;
    long rss_kb;
    double wall_s;
  };

  void onInit() override
  {
    source_ = std::make_unique<SampleSource>(options_);
    ros::NodeHandle nh = getNodeHandle();
    const Measured& m = measured(options_);
    pub_ = nh.advertise<sensor_msgs::Imu>(m.input, 1000);
    ros::SubscribeOptions subscription;
    if (options_.nodelet == "madgwick")
      subscription.init<sensor_msgs::Imu>(m.output, 10000,
                                          [this](const sensor_msgs::Imu::ConstPtr& msg) { outputCallback(msg); });
    else
      subscription.init<nav_msgs::Odometry>(m.output, 10000,
                                            [this](const nav_msgs::Odometry::ConstPtr& msg) { outputCallback(msg); });
    subscription.transport_hints = ros::TransportHints().tcpNoDelay();
    subscription.callback_queue = receiver_.queue();
    sub_ = nh.subscribe(subscription);
    std::promise<clockid_t> receiver_clock;
    receiver_.post([&receiver_clock] {
      clockid_t clock{};
      pthread_getcpuclockid(pthread_self(), &clock);
      receiver_clock.set_value(clock);
    });
    receiver_clock_ = receiver_clock.get_future().get();
    thread_ = std::thread([this] { run(); });
    if (options_.realtime_priority > 0)
    {
      const int priority = static_cast<int>(options_.realtime_priority);
      std::string why;
      requireRealtime(receiver_.setRealtimePriority(priority, &why), why);
      requireRealtime(pbc::setRealtimePriority(thread_.native_handle(), priority, &why), why);
    }
  }

  ros::Time stampOf(std::int64_t k) const
  {
    return ros::Time(kStampSec, 0) + ros::Duration(static_cast<double>(k) / options_.rate);
  }

  void run()
  {
    while (!stop_ && (pub_.getNumSubscribers() == 0 || sub_.getNumPublishers() == 0))
    {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));  // connections settle
    const auto count = static_cast<std::int64_t>(std::llround(options_.duration * options_.rate));
    start_ = Clock::now();
    cpu_start_ = cpuSeconds(CLOCK_PROCESS_CPUTIME_ID);
    receiver_cpu_start_ = cpuSeconds(receiver_clock_);
    const double publisher_cpu_start = cpuSeconds(CLOCK_THREAD_CPUTIME_ID);
    std::int64_t lost = 0;  // closed loop: inputs given up after a second without an answer
    for (std::int64_t k = 0; k < count && !stop_; ++k)
    {
      auto imu = boost::make_shared<sensor_msgs::Imu>();
      if (!source_->get(k, imu.get()))
      {
        break;
      }
      imu->header.stamp = stampOf(k);
      if (options_.closed_loop)
      {
        std::unique_lock<std::mutex> lock(mutex_);
        if (!answered_.wait_for(lock, std::chrono::seconds(1), [&] { return sent_ - received_ - lost < kInFlight; }))
        {
          lost = sent_ - received_;
        }
      }
      else
      {
        std::this_thread::sleep_until(start_ +
                                      std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 * k / options_.rate)));
      }
      {
        std::lock_guard<std::mutex> lock(mutex_);
        published_[static_cast<std::size_t>(k) % kRing] = Clock::now();
        ++sent_;
      }
      pub_.publish(imu);  // zero-copy to a subscriber in this process
    }
    std::lock_guard<std::mutex> lock(mutex_);
    end_ = Clock::now();
    publisher_cpu_ = cpuSeconds(CLOCK_THREAD_CPUTIME_ID) - publisher_cpu_start;
  }

  /// An output (its stamp is its input's).
  template <typename Message>
  void outputCallback(const boost::shared_ptr<const Message>& msg)
  {
    const auto now = Clock::now();
    const auto k =
        static_cast<std::int64_t>(std::llround((msg->header.stamp - ros::Time(kStampSec, 0)).toSec() * options_.rate));
    std::lock_guard<std::mutex> lock(mutex_);
    if (k >= 0 && k < sent_ && sent_ - k <= static_cast<std::int64_t>(kRing))
    {
      const double latency =
          std::chrono::duration<double>(now - published_[static_cast<std::size_t>(k) % kRing]).count();
      latency_.add(latency);
      if (!options_.latency_csv.empty() && k < static_cast<std::int64_t>(kRing))
        latencies_.emplace_back(k, latency);
      if (latency > max_latency_)
      {
        max_latency_ = latency;
        max_at_ = static_cast<double>(k) / options_.rate;
      }
    }
    ++received_;
    if (options_.rss_every > 0 && received_ % options_.rss_every == 0 && !options_.rss_csv.empty())
    {
      rss_.push_back({ static_cast<double>(k) / options_.rate / 3600.0, received_, rssKilobytes(),
                       std::chrono::duration<double>(now - start_).count() });
      if (rss_.size() % 60 == 0)
      {
        std::cerr << "[nodelet_benchmark] " << rss_.back().data_hours << " h of data, RSS " << rss_.back().rss_kb
                  << " kB" << std::endl;
      }
    }
    answered_.notify_one();
  }

  Options options_;
  std::unique_ptr<SampleSource> source_;
  pbc::CallbackThread receiver_{
    "bench_receiver"
  };  ///< serves sub_: the answers cost one thread wake-up, as a consumer's may
  ros::Publisher pub_;
  ros::Subscriber sub_;
  std::thread thread_;
  std::atomic<bool> stop_{ false };

  std::mutex mutex_;                          ///< guards everything below
  std::vector<Clock::time_point> published_;  ///< by k, in a ring
  std::condition_variable answered_;
  std::int64_t sent_ = 0;
  std::int64_t received_ = 0;
  Clock::time_point start_, end_;
  double cpu_start_ = 0.0;           ///< the process's CPU time when the first input was sent [s]
  clockid_t receiver_clock_{};       ///< the CPU clock of receiver_'s thread
  double receiver_cpu_start_ = 0.0;  ///< its CPU time when the first input was sent [s]
  double publisher_cpu_ = 0.0;       ///< CPU time of the publishing thread, first input to last [s]
  Histogram latency_;
  double max_latency_ = 0.0;
  double max_at_ = 0.0;  ///< data time of the slowest output [s]
  std::vector<RssRow> rss_;
  std::vector<std::pair<std::int64_t, double>> latencies_;  ///< k, latency [s] (--latency-csv)
};

const char* kUsage =
    "usage: nodelet_benchmark --transport intra|tcp --scenario FILE.yaml --rate HZ --duration S\n"
    "                         [--closed-loop] [--stream] [--rss-csv FILE] [--rss-every N]\n"
    "                         [--latency-csv FILE]\n"
    "                         [--nodelet compensator|madgwick|relay] [--manager-queues]\n"
    "                         [--realtime-priority P] [--cpu N] [--cpu-wakeup-latency S]\n";

/// The options, or nothing after --help.
std::optional<Options> parseOptions(int argc, char** argv)
{
  Options o;
  pbc::CommandLine cli(kUsage);
  cli.text("--transport", &o.transport)
      .text("--scenario", &o.scenario)
      .number("--rate", &o.rate)
      .number("--duration", &o.duration)
      .flag("--closed-loop", &o.closed_loop)
      .flag("--stream", &o.stream)
      .text("--rss-csv", &o.rss_csv)
      .integer("--rss-every", &o.rss_every)
      .text("--latency-csv", &o.latency_csv)
      .text("--nodelet", &o.nodelet)
      .flag("--manager-queues", &o.manager_queues)
      .integer("--realtime-priority", &o.realtime_priority)
      .integer("--cpu", &o.cpu)
      .number("--cpu-wakeup-latency", &o.cpu_wakeup_latency);
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if ((o.transport != "intra" && o.transport != "tcp") || o.scenario.empty() || !(o.rate > 0.0) || !(o.duration > 0.0))
    throw pbc::UsageError("--transport intra|tcp, --scenario, --rate > 0 and --duration > 0 are required");
  if (o.nodelet != "compensator" && ((o.nodelet != "madgwick" && o.nodelet != "relay") || o.transport != "intra"))
    throw pbc::UsageError("--nodelet is compensator, madgwick or relay (the last two with --transport intra only)");
  if (o.manager_queues && (o.nodelet == "madgwick" || o.transport != "intra"))
    throw pbc::UsageError(
        "--manager-queues is for the compensator or the relay with --transport intra (Madgwick's "
        "nodelet is always on them)");
  if (o.realtime_priority < 0 || o.realtime_priority > 99 ||
      (o.realtime_priority > 0 && (o.manager_queues || o.nodelet == "madgwick" || o.transport != "intra")))
    throw pbc::UsageError(
        "--realtime-priority is 0-99, for a nodelet on a thread of its own with --transport intra (the "
        "compensator's or the relay's)");
  if (o.cpu < -1)
    throw pbc::UsageError("--cpu is a CPU number (0, 1, ...)");
  return o;
}
}  // namespace

int main(int argc, char** argv)
{
  ros::init(argc, argv, "nodelet_benchmark");
  Options options;
  pbc::CpuWakeupLatencyRequest wakeup_latency;  // held until the process ends
  try
  {
    const std::optional<Options> parsed = parseOptions(argc, argv);
    if (!parsed)
      return 0;
    options = *parsed;
    // The priority is asked for here, before anything is loaded, so that a refusal is an error
    // rather than a nodelet's onInit() failing; the main thread then runs as an ordinary one.
    pbc::applyLatencySettings(options.cpu_wakeup_latency, options.cpu, options.realtime_priority, &wakeup_latency);
    if (options.realtime_priority > 0)
    {
      const sched_param ordinary{};
      pthread_setschedparam(pthread_self(), SCHED_OTHER, &ordinary);
    }
  }
  catch (const pbc::UsageError& e)
  {
    std::cerr << "nodelet_benchmark: " << e.what() << "\n" << kUsage;
    return 2;
  }
  try
  {
    auto source = boost::make_shared<BenchSource>(options);
    pluginlib::ClassLoader<nodelet::Nodelet> plugins("nodelet", "nodelet::Nodelet");
    nodelet::Loader manager([&](const std::string& type) -> boost::shared_ptr<nodelet::Nodelet> {
      if (type == "bench/BenchSource")
      {
        return source;
      }
      if (type == kRelay.type)
      {
        return boost::make_shared<Relay>(options.manager_queues, static_cast<int>(options.realtime_priority));
      }
      return plugins.createInstance(type);
    });
    const nodelet::M_string no_remappings;
    const nodelet::V_string no_argv;
    if (options.nodelet == "madgwick")
    {
      // Accelerometer and gyro only, no TF: its imu/data (orientation added) is the answer.
      ros::param::set("/madgwick/use_mag", false);
      ros::param::set("/madgwick/publish_tf", false);
      ros::param::set("/madgwick/world_frame", std::string("enu"));
    }
    // The compensator's imu/data on a thread of its own (its default) or on the manager's queues
    // (the parameter is removed again at the end: a compensator_node started later reads its own).
    if (options.transport == "intra")
    {
      ros::param::set("/compensator/imu_thread", !options.manager_queues);
      ros::param::set("/compensator/imu_thread_priority", static_cast<int>(options.realtime_priority));
    }
    const Measured& m = measured(options);
    if (options.transport == "intra" && !manager.load("/" + options.nodelet, m.type, no_remappings, no_argv))
    {
      throw std::runtime_error(std::string("the nodelet ") + m.type + " did not load");
    }
    if (!manager.load("/bench_source", "bench/BenchSource", no_remappings, no_argv))
    {
      throw std::runtime_error("the benchmark source did not load");
    }
    source->finish();
    manager.clear();
    ros::param::del("/compensator/imu_thread");
    ros::param::del("/compensator/imu_thread_priority");
  }
  catch (const std::exception& e)
  {
    std::cerr << "nodelet_benchmark: " << e.what() << std::endl;
    return 1;
  }
  return 0;
}
