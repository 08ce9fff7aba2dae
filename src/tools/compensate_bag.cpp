// compensate_bag: runs the compensator over a bag at full speed, without a ROS master, and writes
// the same outputs as the node (odometry/filtered, odometry/wave, bias_state) to a new bag,
// copying ground_truth/* through (as their bytes, not deserialised). The IMU's mounting comes
// from the bag's /tf_static or /tf, looked up as the node does (ros/mounting.h).
//
//   compensate_bag --in IN.bag --out OUT.bag [--mode paper|default] [--params FILE.yaml]
//                  [--imu-topic imu/data] [--outputs filtered,wave,bias,ground_truth]
//                  [--compression none|lz4|bz2]
//
// IN is read (by ros/bag_reader.h, chunk after chunk; through rosbag::View where that reader
// cannot: an encrypted bag, or one with more than 64 chunks overlapping in time) and deserialised by a thread of its own, a few hundred messages
// ahead of the core, and OUT's chunks are written by another (ros/bag_writer.h): on a machine
// with a free core the run takes about as long as its slowest part instead of the sum of all
// three.
//
// The outputs are written to temporary files next to them and renamed when complete, so a
// failure or a signal never leaves a partial OUT behind; an input is never overwritten
// (tools/output_file.h). Exit status: 0 success, 1 error, 2 wrong command line.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <future>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <ros/exception.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>
#include <boost/make_shared.hpp>

#include "periodic_bias_compensation/common/work_thread.h"
#include "periodic_bias_compensation/core/calibration_file.h"
#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/gain_tuning.h"
#include "periodic_bias_compensation/ros/bag_check.h"
#include "periodic_bias_compensation/ros/bag_reader.h"
#include "periodic_bias_compensation/ros/bag_writer.h"
#include "periodic_bias_compensation/ros/conversions.h"
#include "periodic_bias_compensation/ros/mounting.h"
#include "periodic_bias_compensation/ros/parameters.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace fs = std::filesystem;
using namespace periodic_bias_compensation;

namespace
{
const char* const kUsage =
    "usage: compensate_bag --in IN.bag --out OUT.bag [--mode paper|default] [--params FILE.yaml]\n"
    "                      [--imu-topic imu/data] [--tune-gains GAINS.yaml]\n"
    "                      [--outputs filtered,wave,bias,ground_truth] [--compression none|lz4|bz2]\n"
    "Runs the bias compensator over IN.bag and writes odometry/filtered, odometry/wave and\n"
    "bias_state (plus ground_truth/* copied through) to OUT.bag. --params takes a YAML file with\n"
    "the keys of config/compensator.yaml; --mode overrides its 'mode'. The IMU's mounting on\n"
    "base_frame is looked up in IN.bag's /tf_static (then /tf), as the node looks it up in tf2.\n"
    "--outputs: which of them to write, comma-separated (default: all four).\n"
    "--compression: of OUT.bag's chunks (default: none, the fastest; lz4 writes about a fifth of\n"
    "the bytes, bz2 the fewest and is the slowest).\n"
    "--tune-gains also tunes paper mode's alpha/beta on IN.bag, which must be recorded while the\n"
    "vessel holds its station (moored, at anchor, on a bench: its slow motion is taken as zero),\n"
    "and writes them to GAINS.yaml as parameters (give it to --params or the node's rosparams).\n";

/// What OUT.bag holds (--outputs).
struct Outputs
{
  bool filtered = true;      ///< /odometry/filtered
  bool wave = true;          ///< /odometry/wave
  bool bias = true;          ///< /bias_state
  bool ground_truth = true;  ///< ground_truth/* copied from IN
};

struct Options
{
  std::string in;
  std::string out;
  std::string mode;
  std::string params;
  std::string imu_topic = "imu/data";
  std::string tune_gains;
  Outputs outputs;
  BagWriter::Compression compression = BagWriter::Compression::kNone;
};

/// "filtered,wave": the outputs named; an unknown or missing name is a UsageError.
Outputs parseOutputs(const std::string& list)
{
  Outputs outputs{ false, false, false, false };
  const std::map<std::string, bool*> names{ { "filtered", &outputs.filtered },
                                            { "wave", &outputs.wave },
                                            { "bias", &outputs.bias },
                                            { "ground_truth", &outputs.ground_truth } };
  std::size_t begin = 0;
  while (true)
  {
    const std::size_t end = std::min(list.find(',', begin), list.size());
    const std::string name = list.substr(begin, end - begin);
    const auto known = names.find(name);
    if (known == names.end())
    {
      throw UsageError("--outputs: unknown output '" + name + "' in '" + list +
                       "' (known: filtered, wave, bias, ground_truth)");
    }
    *known->second = true;
    if (end == list.size())
    {
      return outputs;
    }
    begin = end + 1;
  }
}

BagWriter::Compression parseCompression(const std::string& name)
{
  for (const BagWriter::Compression c :
       { BagWriter::Compression::kNone, BagWriter::Compression::kLz4, BagWriter::Compression::kBz2 })
  {
    if (name == BagWriter::toString(c))
    {
      return c;
    }
  }
  throw UsageError("--compression must be 'none', 'lz4' or 'bz2', got '" + name + "'");
}

/// The options, or nothing after --help. A wrong command line throws UsageError (exit status 2).
std::optional<Options> parseArguments(int argc, char** argv)
{
  Options options;
  CommandLine cli(kUsage);
  cli.text("--in", &options.in)
      .text("--out", &options.out)
      .text("--mode", &options.mode)
      .text("--params", &options.params)
      .text("--imu-topic", &options.imu_topic)
      .text("--tune-gains", &options.tune_gains)
      .option("--outputs", [&](const std::string& v) { options.outputs = parseOutputs(v); })
      .option("--compression", [&](const std::string& v) { options.compression = parseCompression(v); });
  if (!cli.parse(argc, argv))
    return std::nullopt;
  if (options.in.empty() || options.out.empty())
  {
    throw UsageError("--in and --out are required");
  }
  refuseOverwritingInputs({ { "--in", options.in }, { "--params", options.params } },
                          { { "--out", options.out }, { "--tune-gains", options.tune_gains } });
  return options;
}

/// "imu/data" and "/imu/data" name the same topic in a bag written without a namespace.
std::string absoluteTopic(const std::string& topic)
{
  return (!topic.empty() && topic.front() == '/') ? topic : "/" + topic;
}

bool isGroundTruth(const std::string& topic)
{
  return absoluteTopic(topic).rfind("/ground_truth/", 0) == 0;
}

Parameters loadParameters(const Options& options)
{
  Parameters params;
  std::string why;
  if (!options.params.empty())
  {
    if (!readParameters(YamlParameterSource(options.params), &params, &why))
    {
      throw std::runtime_error(options.params + ": " + why);
    }
  }
  if (!options.mode.empty())
  {
    if (!modeFromString(options.mode, &params.core.mode))
    {
      throw UsageError("--mode must be 'paper' or 'default', got '" + options.mode + "'");
    }
  }
  return params;
}

/// Consecutive messages of IN as the reading thread hands them on: an IMU message deserialised,
/// any other as its serialised bytes (copied out: rosbag reuses its read buffer).
struct ReadBatch
{
  struct Message
  {
    ros::Time time;                  ///< in the bag
    std::size_t connection = 0;      ///< index in the caller's table of IN's connections
    sensor_msgs::Imu::ConstPtr imu;  ///< set for an IMU message; else its bytes are in `bytes`
    std::size_t offset = 0;          ///< of its bytes in `bytes`
    std::uint32_t size = 0;
  };
  std::vector<Message> messages;
  std::vector<std::uint8_t> bytes;  ///< the first `used` hold the messages' bytes
  std::size_t used = 0;
  std::exception_ptr error;  ///< what stopped the reading, after `messages`
  bool last = false;         ///< no batch follows

  /// Room for `size` more bytes. `bytes` only grows, so that a batch used again is not filled
  /// with zeros again (as resizing it from empty each time would).
  std::uint8_t* addBytes(std::size_t size)
  {
    if (bytes.size() < used + size)
    {
      bytes.resize(std::max(2 * bytes.size(), used + size));
    }
    std::uint8_t* room = bytes.data() + used;
    used += size;
    return room;
  }
};

/// Reads IN in a thread of its own, a few batches ahead of the caller, so that reading and
/// deserialising overlap the core and the writing instead of adding to them: each batch handed to
/// the thread comes back filled with the next messages. The source is used by that thread alone
/// until the ReadAhead is destroyed. An exception while reading comes with the batch of the
/// messages read before it, so the caller throws it after handling those, where a single loop
/// would have thrown it.
class ReadAhead
{
public:
  /// Messages in a batch: a batch amortises the hand-over, which wakes a thread (and the woken
  /// thread may take the waking one's core for a while). Eight of them in flight hold a few MB.
  static constexpr std::size_t kBatchMessages = 1024;
  /// Adds the next messages of the source to the batch, up to kBatchMessages (in the reading
  /// thread); returns whether the source has ended.
  using Fill = std::function<bool(ReadBatch*)>;

  explicit ReadAhead(Fill source)
    : fill_(std::move(source)),
      thread_(
          kBatches, [this](Batch& batch) { fill(batch.get()); }, true)
  {
    for (int i = 0; i < kBatches; ++i)
    {
      thread_.hand(std::make_unique<ReadBatch>());
    }
  }

  /// The next batch, once read; give it back with recycle() when done with it.
  std::unique_ptr<ReadBatch> next()
  {
    return thread_.waitDone();
  }

  /// Hands a batch back to be filled again (from any thread the caller's work runs in, one at a
  /// time: the writing thread's).
  void recycle(std::unique_ptr<ReadBatch> batch)
  {
    batch->messages.clear();
    batch->used = 0;
    thread_.hand(std::move(batch));
  }

private:
  using Batch = std::unique_ptr<ReadBatch>;
  // Batches in flight (read ahead, in the core, waiting to be written) bound the memory.
  static constexpr int kBatches = 8;

  /// The next messages of the source into `batch` (in the reading thread); after the last, none.
  void fill(ReadBatch* batch)
  {
    if (ended_)
    {
      return;
    }
    try
    {
      ended_ = fill_(batch);
    }
    catch (...)
    {
      batch->error = std::current_exception();
      ended_ = true;
    }
    batch->last = ended_;
  }

  Fill fill_;
  bool ended_ = false;        ///< the reading thread's
  WorkThread<Batch> thread_;  ///< last: started once the rest is built
};

/// A batch the core has been through: the messages read and the outputs of those that produced
/// one (the message's index in the batch, the core's output).
struct CoreBatch
{
  std::unique_ptr<ReadBatch> read;
  std::vector<std::pair<std::size_t, CompensatorOutput>> outputs;
};

/// IN is truncated or corrupt (`what`: as rosbag says it), after `received` IMU messages.
std::string corruptInputMessage(const Options& options, const std::string& what, std::uint64_t received)
{
  return corruptBagMessage(options.in, what) + " Nothing was written to " + options.out +
         (received > 0 ? " (" + std::to_string(received) + " IMU messages had been read)" : std::string());
}

/// IN, open: read by BagReader where it can (BagReader::usable: `stream`), else by rosbag
/// (`bag`).
///
/// rosbag reads IN only once the whole-file check (bagFileProblem) has passed: it trusts the
/// file's lengths and offsets. rosbag::Bag::open reads only the records around the chunks, which
/// bagOpenProblem checks first without reading the chunks, so rosbag opens the bag (and, before
/// that, the bag's constructor loads rosbag's encryption plugins, a walk of the ROS package path)
/// while the whole-file check runs in a thread. BagReader checks every length and offset it
/// reads itself: it reads the messages while the whole-file check runs (`check`), and the run
/// takes that check's result before the output is kept (BagCompensator::run), so a bag it
/// refuses is refused with the same message either way, and leaves no output.
struct Input
{
  std::unique_ptr<BagReader> stream;
  std::unique_ptr<rosbag::Bag> bag;
  std::future<std::string> check;  ///< with `stream`: the whole-file check, maybe still running
};

/// Writes the outputs of one bag; the caller owns the temporary file.
class BagCompensator
{
public:
  BagCompensator(const Options& options, const Parameters& params)
    : options_(options),
      params_(params),
      compensator_(params.core),
      mode_(compensator_.config().mode),
      frame_filter_(params.ros.imu_frame)
  {
    // Designs stay on the core's design thread, as in the node (the same outputs either way):
    // here the samples reach a design's due sample before the thread has made it, and the sample
    // that waits makes the other axes' queued designs meanwhile, so two designs are made at once.
    // Same rule as the node: an existing file is loaded (and must be valid), a missing one
    // means calibrating from the data.
    const std::string& file = params_.ros.calibration_file;
    if (!file.empty() && fs::exists(file))
    {
      Vector3 bias;
      std::string why;
      bool loaded = false;
      try
      {
        loaded = loadCalibration(file, &bias, &why);
      }
      catch (const std::exception& e)
      {
        // Some malformed files make the YAML parser throw instead of returning false.
        why = "'" + file + "' is not a calibration file (" + e.what() + ")";
      }
      if (!loaded)
      {
        throw std::runtime_error("parameter 'calibration_file': " + why);
      }
      if (!compensator_.setConstantBias(bias))
      {
        throw std::runtime_error("parameter 'calibration_file': '" + file + "' holds a non-finite constant bias");
      }
      loaded_bias_ = bias;
    }
    else if (!file.empty())
    {
      std::fprintf(stderr, "compensate_bag: calibration file %s does not exist: calibrating from the data\n",
                   file.c_str());
    }
  }

  /// Runs over the input, writing OUT to `temp_path`; a truncated or corrupt input
  /// (rosbag::BagException, BagFormatError, a message that does not deserialise, the whole-file
  /// check's finding) becomes one std::runtime_error that says so and what to do.
  void run(Input* in, const std::string& temp_path)
  {
    try
    {
      runUnchecked(in, temp_path);
    }
    catch (const rosbag::BagException& e)
    {
      throw std::runtime_error(corruptMessage(in, e.what()));
    }
    catch (const ros::Exception& e)
    {
      throw std::runtime_error(corruptMessage(in, e.what()));
    }
    catch (const BagFormatError& e)
    {
      throw std::runtime_error(corruptMessage(in, e.what()));
    }
    catch (...)
    {
      const std::string check = takeCheck(in);
      if (!check.empty())
      {
        throw std::runtime_error(check);
      }
      throw;
    }
    // Read by BagReader: the output is kept only if the whole-file check passes, as when the
    // check ran first.
    const std::string check = takeCheck(in);
    if (!check.empty())
    {
      throw std::runtime_error(check);
    }
  }

  /// What the whole-file check found in IN, once it has run, if it runs beside the reading.
  static std::string takeCheck(Input* in)
  {
    return in->check.valid() ? in->check.get() : std::string();
  }

  /// What IN's reading stopped on, or what the whole-file check found in IN if it did (said first,
  /// as when the check ran first).
  std::string corruptMessage(Input* in, const std::string& what) const
  {
    const std::string check = takeCheck(in);
    return check.empty() ? corruptInputMessage(options_, what, received_) : check;
  }

  /// IN is open (openInput): rosbag's has passed the whole-file check.
  void runUnchecked(Input* input, const std::string& temp_path)
  {
    const std::string imu_topic = absoluteTopic(options_.imu_topic);
    // IN's connections that have messages, with their times.
    std::vector<SourceConnection> all;
    ros::Time begin, end;
    if (input->stream)
    {
      for (const BagReader::Connection& c : input->stream->connections())
      {
        if (c.messages > 0)
        {
          all.push_back(SourceConnection{ c.id, c.topic, &c.header, headerField(c.header, "type"),
                                          headerField(c.header, "md5sum") });
        }
      }
      begin = input->stream->beginTime();
      end = input->stream->endTime();
    }
    else
    {
      rosbag::View view(*input->bag);
      for (const rosbag::ConnectionInfo* c : view.getConnections())
      {
        all.push_back(SourceConnection{ c->id, c->topic, c->header.get(), c->datatype, c->md5sum });
      }
      begin = view.getBeginTime();
      end = view.getEndTime();
    }
    std::set<std::string> topics;
    bool has_imu = false;
    for (const SourceConnection& c : all)
    {
      topics.insert(c.topic);
      has_imu = has_imu || absoluteTopic(c.topic) == imu_topic;
    }
    if (!has_imu)
    {
      std::string list;
      for (const std::string& t : topics)
      {
        list += (list.empty() ? "" : ", ") + t;
      }
      throw std::runtime_error("no topic '" + options_.imu_topic + "' in " + options_.in +
                               " (topics: " + (list.empty() ? "none" : list) + ")");
    }

    resolveMounting(input, all, imu_topic);

    // What each connection of IN is to this tool: only those used are read.
    std::vector<InputConnection> connections;
    for (const SourceConnection& c : all)
    {
      const std::string topic = absoluteTopic(c.topic);
      const Role role = topic == imu_topic                                      ? Role::kImu
                        : options_.outputs.ground_truth && isGroundTruth(topic) ? Role::kCopy
                                                                                : Role::kSkip;
      connections.push_back(InputConnection{ c, role, topic });
    }
    // Compression and file writes in a thread of the writer: they overlap the core.
    BagWriter out(temp_path, options_.compression, true);
    const double span = std::max((end - begin).toSec(), 1e-9);
    if (input->stream)
    {
      std::vector<std::uint32_t> used;
      for (const InputConnection& c : connections)
      {
        if (c.role != Role::kSkip)
        {
          used.push_back(c.source.id);
        }
      }
      input->stream->select(used);
      processAll(streamFill(input->stream.get(), connections), connections, begin, span, &out);
    }
    else
    {
      rosbag::View view(*input->bag, [&connections](const rosbag::ConnectionInfo* c) {
        return std::any_of(connections.begin(), connections.end(),
                           [c](const InputConnection& i) { return i.source.id == c->id && i.role != Role::kSkip; });
      });
      processAll(viewFill(&view, connections), connections, begin, span, &out);
    }
    out.close();
    // The last line stays: the whole bag was read.
    reportProgress(span, span);
  }

  /// --tune-gains: paper mode's gains tuned on the samples of this bag (tunePaperGains), as the
  /// parameter file to write (YAML).
  std::string tuneGains() const
  {
    if (tuning_samples_.size() < 2)
    {
      throw std::runtime_error("--tune-gains: the bag has fewer than 2 usable IMU samples");
    }
    CompensatorConfig base = params_.core;
    base.mode = Mode::kPaper;
    // Scored once the calibration window is over and the loop has had 10 s to settle.
    const double settle = base.calibration_duration + 10.0;
    if (tuning_samples_.back().t - tuning_samples_.front().t < settle + 30.0)
    {
      throw std::runtime_error("--tune-gains: the bag is too short to tune on (needs " +
                               std::to_string(static_cast<int>(settle + 30.0)) + " s of IMU data)");
    }
    auto last_report = std::chrono::steady_clock::now();
    const GainTuningResult tuning =
        tunePaperGains(tuning_samples_, base, loaded_bias_, settle, {}, 2, [&](int done, int total) {
          const auto now = std::chrono::steady_clock::now();
          if (done == total || now - last_report > std::chrono::seconds(2))
          {
            last_report = now;
            std::fprintf(stderr, "compensate_bag: tuning gains, run %d of %d\n", done, total);
          }
        });
    char summary[256];
    std::snprintf(summary, sizeof summary,
                  "paper-mode gains tuned by compensate_bag on %s; RMS of the slow motion after %.0f s "
                  "[m, x y z]: %.4f %.4f %.4f with the gains given, %.4f %.4f %.4f with these",
                  options_.in.c_str(), settle, tuning.score_start[0], tuning.score_start[1], tuning.score_start[2],
                  tuning.score[0], tuning.score[1], tuning.score[2]);
    std::fprintf(stderr, "compensate_bag: %s\n", summary);
    return gainsToYaml(tuning.gains, summary) + "mode: paper\n";
  }

  void printSummary() const
  {
    const CompensatorCounters& c = compensator_.counters();
    std::fprintf(stderr,
                 "compensate_bag: %" PRIu64 " IMU messages, %" PRIu64 " accepted, rejected: %" PRIu64
                 " non-finite, %" PRIu64 " bad quaternion, %" PRIu64 " duplicate stamp, %" PRIu64
                 " wrong frame, %" PRIu64 " out of range; resets: %" PRIu64 " backwards, %" PRIu64 " gaps; %" PRIu64
                 " non-finite outputs not written\n",
                 received_, c.accepted, c.rejected_non_finite, c.rejected_bad_quaternion, c.rejected_duplicate,
                 wrong_frame_, out_of_range_, c.resets_backwards, c.gap_resets, nonfinite_outputs_);
  }

private:
  /// What compensate_bag does with the messages of a connection of IN.
  enum class Role
  {
    kSkip,
    kImu,   ///< compensated
    kCopy,  ///< ground_truth/*, copied through
  };
  /// A connection of IN, as its connection record says (rosbag's or BagReader's).
  struct SourceConnection
  {
    std::uint32_t id;
    std::string topic;            ///< as recorded
    const ros::M_string* header;  ///< its connection header, owned by the source
    std::string type, md5sum;
  };
  struct InputConnection
  {
    SourceConnection source;
    Role role;
    std::string topic;  ///< with its leading '/', as the outputs are named
  };

  static std::string headerField(const ros::M_string& header, const std::string& name)
  {
    const auto field = header.find(name);
    return field == header.end() ? std::string() : field->second;
  }

  /// A message of type M from its serialised bytes; none if its connection is of another type
  /// (its md5sum is not M's, as rosbag::MessageInstance::instantiate decides).
  template <class M>
  static boost::shared_ptr<M> deserializeAs(const SourceConnection& connection, const std::uint8_t* data,
                                            std::uint32_t size)
  {
    if (connection.md5sum != ros::message_traits::md5sum<M>())
    {
      return nullptr;
    }
    auto message = boost::make_shared<M>();
    ros::serialization::IStream stream(const_cast<std::uint8_t*>(data), size);
    ros::serialization::deserialize(stream, *message);
    return message;
  }

  /// A message rosbag reads (MessageInstance::write reads it from the bag) as its bytes.
  static void copyBytes(const rosbag::MessageInstance& m, std::vector<std::uint8_t>* bytes)
  {
    bytes->resize(m.size());
    ros::serialization::OStream stream(bytes->data(), m.size());
    m.write(stream);
  }

  /// In the reading thread: adds a message of connections[connection] to *batch, deserialised if
  /// it is an IMU message, else as a copy of its bytes.
  static void addMessage(const InputConnection& connection, std::size_t index, const ros::Time& time,
                         const std::uint8_t* data, std::uint32_t size, ReadBatch* batch)
  {
    ReadBatch::Message message;
    message.time = time;
    message.connection = index;
    if (connection.role == Role::kImu)
    {
      message.imu = deserializeAs<sensor_msgs::Imu>(connection.source, data, size);
      if (!message.imu)
      {
        throw std::runtime_error("topic '" + connection.source.topic + "' holds " + connection.source.type +
                                 ", not sensor_msgs/Imu");
      }
    }
    else
    {
      message.offset = batch->used;
      message.size = size;
      std::copy(data, data + size, batch->addBytes(size));
    }
    batch->messages.push_back(std::move(message));
  }

  /// The messages of `view` (rosbag's), for ReadAhead. Each finds its connection by its connection
  /// header (the same object for all messages of a connection; the previous message's first).
  static ReadAhead::Fill viewFill(rosbag::View* view, const std::vector<InputConnection>& connections)
  {
    struct Position
    {
      std::optional<rosbag::View::iterator> next, end;
      std::size_t last = 0;
      std::vector<std::uint8_t> bytes;
    };
    return [view, &connections, at = std::make_shared<Position>()](ReadBatch* batch) {
      if (!at->next)
      {
        at->next = view->begin();
        at->end = view->end();
      }
      rosbag::View::iterator& position = *at->next;
      for (; position != *at->end && batch->messages.size() < ReadAhead::kBatchMessages; ++position)
      {
        const rosbag::MessageInstance& m = *position;
        const ros::M_string* header = m.getConnectionHeader().get();
        std::size_t& last = at->last;
        if (connections[last].source.header != header)
        {
          last = std::find_if(connections.begin(), connections.end(),
                              [header](const InputConnection& c) { return c.source.header == header; }) -
                 connections.begin();
          if (last == connections.size())
          {
            throw std::runtime_error("a message of topic '" + m.getTopic() + "' has no connection record");
          }
        }
        // Its bytes, then handled as BagReader's.
        copyBytes(m, &at->bytes);
        addMessage(connections[last], last, m.getTime(), at->bytes.data(), m.size(), batch);
      }
      return position == *at->end;
    };
  }

  /// The selected messages of `stream` (BagReader::usable), for ReadAhead.
  static ReadAhead::Fill streamFill(BagReader* stream, const std::vector<InputConnection>& connections)
  {
    struct Position
    {
      std::vector<BagReader::Message> chunk;
      std::size_t next = 0;
      std::size_t last = 0;
    };
    return [stream, &connections, at = std::make_shared<Position>()](ReadBatch* batch) {
      while (batch->messages.size() < ReadAhead::kBatchMessages)
      {
        if (at->next == at->chunk.size())
        {
          at->next = 0;
          if (!stream->next(&at->chunk))
          {
            return true;
          }
        }
        const BagReader::Message& m = at->chunk[at->next++];
        if (connections[at->last].source.id != m.connection)
        {
          // Selected from `connections`: found.
          at->last = std::find_if(connections.begin(), connections.end(),
                                  [&m](const InputConnection& c) { return c.source.id == m.connection; }) -
                     connections.begin();
        }
        addMessage(connections[at->last], at->last, m.time, m.data, m.size, batch);
      }
      return false;
    };
  }

  /// Compensates the messages of `source` (those of `connections` not skipped) in bag order into
  /// *out, copying ground_truth/* through: they are read ahead by a thread (ReadAhead), run
  /// through the core in this one, and their outputs built and written by another (WorkThread).
  /// Says how far it is on stderr every 2 s or so (`begin`, `span`: the bag's).
  void processAll(ReadAhead::Fill source, const std::vector<InputConnection>& connections, const ros::Time& begin,
                  double span, BagWriter* out)
  {
    ReadAhead reader(std::move(source));
    std::vector<std::optional<std::uint32_t>> copies(connections.size());  // OUT's connection, for kCopy
    // The outputs of the batches the core has been through are built and written, with the
    // messages copied through, in a thread of their own and in bag order, so that building,
    // serialising and copying overlap the core's next batch; each batch goes back to the reader
    // once written. Two wait at most.
    WorkThread<CoreBatch> writer(2, [this, &connections, &copies, out, &reader](CoreBatch& done) {
      auto next_output = done.outputs.begin();
      for (std::size_t i = 0; i < done.read->messages.size(); ++i)
      {
        const ReadBatch::Message& m = done.read->messages[i];
        if (m.imu)
        {
          if (next_output != done.outputs.end() && next_output->first == i)
          {
            writeOutputs(next_output->second, *m.imu, m.time, out);
            ++next_output;
          }
          continue;
        }
        std::optional<std::uint32_t>& copy = copies[m.connection];
        if (!copy)
        {
          copy = out->addConnection(connections[m.connection].topic, *connections[m.connection].source.header);
        }
        out->write(*copy, m.time, done.read->bytes.data() + m.offset, m.size);
      }
      reader.recycle(std::move(done.read));
    });
    auto last_report = std::chrono::steady_clock::now();
    std::uint64_t messages = 0;
    while (true)
    {
      CoreBatch batch{ reader.next(), {} };
      const ReadBatch& read = *batch.read;
      for (std::size_t i = 0; i < read.messages.size(); ++i)
      {
        const ReadBatch::Message& m = read.messages[i];
        if (m.imu)
        {
          CompensatorOutput result;
          if (process(*m.imu, &result))
          {
            batch.outputs.emplace_back(i, result);
          }
        }
        if (++messages % 256 == 0)
        {
          const auto now = std::chrono::steady_clock::now();
          if (now - last_report > std::chrono::seconds(2))
          {
            last_report = now;
            reportProgress((m.time - begin).toSec(), span);
          }
        }
      }
      if (read.error)
      {
        std::rethrow_exception(read.error);
      }
      const bool last = read.last;
      writer.hand(std::move(batch));
      if (last)
      {
        writer.finish();
        return;
      }
    }
  }

  /// Calls visit(time, connection, data, size) for the messages of `topic` in IN (with or without
  /// its leading '/') up to bag time `until`, in time order, while it returns true.
  using Visit = std::function<bool(const ros::Time&, const SourceConnection&, const std::uint8_t*, std::uint32_t)>;
  static void forEachMessage(Input* in, const std::vector<SourceConnection>& all, const std::string& topic,
                             const ros::Time& until, const Visit& visit)
  {
    std::vector<const SourceConnection*> of_topic;
    for (const SourceConnection& c : all)
    {
      if (absoluteTopic(c.topic) == topic)
      {
        of_topic.push_back(&c);
      }
    }
    if (in->stream)
    {
      std::vector<std::uint32_t> ids;
      for (const SourceConnection* c : of_topic)
      {
        ids.push_back(c->id);
      }
      in->stream->select(ids);
      std::vector<BagReader::Message> messages;
      while (in->stream->next(&messages))
      {
        for (const BagReader::Message& m : messages)
        {
          const auto c = std::find_if(of_topic.begin(), of_topic.end(),
                                      [&m](const SourceConnection* c) { return c->id == m.connection; });
          if (m.time > until || !visit(m.time, **c, m.data, m.size))
          {
            return;
          }
        }
      }
      return;
    }
    rosbag::View view(
        *in->bag, [&topic](const rosbag::ConnectionInfo* c) { return absoluteTopic(c->topic) == topic; }, ros::TIME_MIN,
        until);
    std::vector<std::uint8_t> bytes;
    for (const rosbag::MessageInstance& m : view)
    {
      const ros::M_string* header = m.getConnectionHeader().get();
      const auto c = std::find_if(of_topic.begin(), of_topic.end(),
                                  [header](const SourceConnection* c) { return c->header == header; });
      if (c == of_topic.end())
      {
        throw std::runtime_error("a message of topic '" + m.getTopic() + "' has no connection record");
      }
      copyBytes(m, &bytes);
      if (!visit(m.getTime(), **c, bytes.data(), m.size()))
      {
        return;
      }
    }
  }

  /// Adds the transforms of IN's `topic` (tf2_msgs/TFMessage) up to bag time `until` to *tf.
  /// @return how many were added
  static int addTransforms(Input* in, const std::vector<SourceConnection>& all, const std::string& topic,
                           const ros::Time& until, tf2::BufferCore* tf)
  {
    int added = 0;
    forEachMessage(in, all, topic, until,
                   [&](const ros::Time&, const SourceConnection& c, const std::uint8_t* data, std::uint32_t size) {
                     const tf2_msgs::TFMessage::ConstPtr message = deserializeAs<tf2_msgs::TFMessage>(c, data, size);
                     if (!message)
                     {
                       std::fprintf(stderr,
                                    "compensate_bag: %s holds %s, not tf2_msgs/TFMessage: not used for the mounting\n",
                                    topic.c_str(), c.type.c_str());
                       return false;
                     }
                     for (const geometry_msgs::TransformStamped& transform : message->transforms)
                     {
                       added += tf->setTransform(transform, "bag " + topic, topic == "/tf_static") ? 1 : 0;
                     }
                     return true;
                   });
    return added;
  }

  /// The IMU's mounting, decided once before the messages are processed, as the node does on its
  /// first message (lookupMounting) from the bag's /tf_static and, failing that, its /tf up to
  /// mount_timeout after the first IMU message. Nothing is dropped meanwhile: the bag holds
  /// them all already. Said on stderr.
  void resolveMounting(Input* in, const std::vector<SourceConnection>& all, const std::string& imu_topic)
  {
    sensor_msgs::Imu::ConstPtr message;
    ros::Time first;
    forEachMessage(in, all, imu_topic, ros::TIME_MAX,
                   [&](const ros::Time& time, const SourceConnection& c, const std::uint8_t* data, std::uint32_t size) {
                     message = deserializeAs<sensor_msgs::Imu>(c, data, size);
                     first = time;
                     return false;
                   });
    if (!message)
    {
      return;  // no message, or not sensor_msgs/Imu: the main loop says so
    }
    const std::string frame = params_.ros.imu_frame.empty() ? message->header.frame_id : params_.ros.imu_frame;
    const std::string& base = params_.ros.base_frame;
    tf2::BufferCore tf;
    MountingLookup lookup = lookupMounting(tf, frame, params_.ros);
    std::string source = "/tf_static";
    int transforms = 0;
    if (lookup.source == MountingSource::kMissing)
    {
      transforms += addTransforms(in, all, source, ros::TIME_MAX, &tf);
      lookup = lookupMounting(tf, frame, params_.ros);
    }
    if (lookup.source == MountingSource::kMissing)
    {
      source = "/tf";
      transforms += addTransforms(in, all, source, first + ros::Duration(params_.ros.mount_timeout), &tf);
      lookup = lookupMounting(tf, frame, params_.ros);
    }
    mounting_ = lookup.mounting;
    switch (lookup.source)
    {
      case MountingSource::kNotNeeded:
        std::fprintf(stderr, "compensate_bag: mounting: %s\n",
                     frame == base ? ("the IMU's frame is " + base + ": none needed").c_str()
                                   : ("identity_mounting: " + frame + " taken as aligned with " + base).c_str());
        break;
      case MountingSource::kTransform:
        std::fprintf(stderr, "compensate_bag: mounting: %s -> %s from %s, %s\n", frame.c_str(), base.c_str(),
                     source.c_str(), describeMounting(mounting_).c_str());
        break;
      case MountingSource::kMissing:
        std::fprintf(stderr, "compensate_bag: no %s -> %s transform in the bag: taken as aligned%s\n", frame.c_str(),
                     base.c_str(), transforms > 0 ? (" (tf2: " + lookup.why + ")").c_str() : "");
        break;
    }
  }

  static void reportProgress(double done, double span)
  {
    std::fprintf(stderr, "compensate_bag: %3.0f%% (%.1f of %.1f s)\n", 100.0 * done / span, done, span);
  }

  /// OUT's connection for one output, added when its first message is written.
  template <class M>
  void writeOutput(BagWriter* out, std::optional<std::uint32_t>* connection, const std::string& topic,
                   const ros::Time& time, const M& message)
  {
    if (!*connection)
    {
      *connection = out->addConnection<M>(topic);
    }
    out->write(**connection, time, message);
  }

  /// One IMU message through the core (in the calling thread); true when it produced outputs, in
  /// *result.
  bool process(const sensor_msgs::Imu& imu, CompensatorOutput* result)
  {
    ++received_;
    if (!frame_filter_.accept(imu.header.frame_id))
    {
      ++wrong_frame_;
      return false;
    }
    const ImuSample sample = toImuSample(imu, mounting_);
    if (!plausible(sample))
    {
      ++out_of_range_;
      return false;
    }
    if (!options_.tune_gains.empty())
    {
      tuning_samples_.push_back(sample);
    }
    const SampleStatus status = compensator_.addSample(sample, result);
    const ForceUnits units = compensator_.forceUnits();
    if (units != units_)
    {
      units_ = units;
      char text[240];
      std::snprintf(text, sizeof text, "%s: mean specific force %.3f against gravity %.3f m/s^2 at t = %.3f s: %s",
                    options_.imu_topic.c_str(), compensator_.meanSpecificForce(), compensator_.config().gravity,
                    sample.t, toString(units).c_str());
      // Data in g would give outputs ten times too small: refused. Otherwise only said.
      if (units == ForceUnits::kLooksLikeG)
        throw std::runtime_error(std::string(text) + " (REP-145 asks for m/s^2); nothing written");
      if (units == ForceUnits::kImplausible)
        std::fprintf(stderr, "compensate_bag: warning: %s\n", text);
    }
    if (!producedOutput(status))
    {
      return false;
    }
    frame_filter_.learn(imu.header.frame_id);
    return true;
  }

  /// The outputs of one IMU message, built and written to *out (in the writing thread: reads
  /// only what stays the same while the core runs).
  void writeOutputs(const CompensatorOutput& result, const sensor_msgs::Imu& imu, const ros::Time& bag_time,
                    BagWriter* out)
  {
    // Only the outputs written are built (and must be finite).
    const Outputs& outputs = options_.outputs;
    const OdometryFrames frames{ params_.ros.odom_frame, params_.ros.base_frame };
    std::optional<nav_msgs::Odometry> filtered, wave;
    std::optional<BiasState> bias;
    if (outputs.filtered)
      filtered = toOdometry(result, OdometryKind::kFiltered, imu, mounting_, frames, imu.header.stamp);
    if (outputs.wave)
      wave = toOdometry(result, OdometryKind::kWave, imu, mounting_, frames, imu.header.stamp);
    if (outputs.bias)
      bias = toBiasState(result, mode_, params_.ros.odom_frame, imu.header.stamp);
    if ((filtered && !allFinite(*filtered)) || (wave && !allFinite(*wave)) || (bias && !allFinite(*bias)))
    {
      ++nonfinite_outputs_;
      return;
    }
    if (filtered)
      writeOutput(out, &filtered_connection_, "/odometry/filtered", bag_time, *filtered);
    if (wave)
      writeOutput(out, &wave_connection_, "/odometry/wave", bag_time, *wave);
    if (bias)
      writeOutput(out, &bias_connection_, "/bias_state", bag_time, *bias);
  }

  const Options& options_;
  const Parameters& params_;
  Compensator compensator_;
  const Mode mode_;                        ///< the compensator's, read by the writing thread
  std::optional<Vector3> loaded_bias_;     ///< from calibration_file, if one was loaded
  std::vector<ImuSample> tuning_samples_;  ///< the samples given to the core, kept for --tune-gains
  FrameFilter frame_filter_;
  Mounting mounting_;
  std::uint64_t received_ = 0;
  std::uint64_t wrong_frame_ = 0;
  std::uint64_t out_of_range_ = 0;
  std::uint64_t nonfinite_outputs_ = 0;      ///< the writing thread's (processAll)
  ForceUnits units_ = ForceUnits::kUnknown;  ///< the last units reported
  std::optional<std::uint32_t> filtered_connection_, wave_connection_, bias_connection_;  ///< in OUT
};

Input openInput(const Options& options)
{
  Input input;
  input.check = std::async(std::launch::async, bagFileProblem, options.in);
  try
  {
    input.stream = std::make_unique<BagReader>(options.in);
    if (input.stream->usable())
    {
      return input;
    }
  }
  catch (const std::exception&)
  {
    // Not for BagReader (missing, unindexed, not a bag): the checks below say what it is.
  }
  input.stream.reset();
  input.bag = std::make_unique<rosbag::Bag>();
  const std::string open_problem = bagOpenProblem(options.in);
  std::string open_error;
  if (open_problem.empty())
  {
    try
    {
      input.bag->open(options.in, rosbag::bagmode::Read);
    }
    catch (const rosbag::BagException& e)
    {
      open_error = e.what();
    }
  }
  const std::string why = input.check.get();
  if (!why.empty())
  {
    throw std::runtime_error(why);
  }
  if (!open_problem.empty())
  {
    throw std::runtime_error(open_problem);  // not expected: bagFileProblem checks all it does
  }
  if (!open_error.empty())
  {
    throw std::runtime_error(corruptInputMessage(options, open_error, 0));
  }
  return input;
}
}  // namespace

/// The whole tool; main() only calls it. Also called in-process by the bag fuzz harness
/// (test/fuzz/fuzz_bag.cpp), which compiles this file with PBC_COMPENSATE_BAG_NO_MAIN.
int compensateBagMain(int argc, char** argv)
{
  Options options;
  try
  {
    const std::optional<Options> parsed = parseArguments(argc, argv);
    if (!parsed)
      return 0;
    options = *parsed;
    Input in = openInput(options);
    const Parameters params = loadParameters(options);
    // Both outputs are created (as temporaries) before the bag is read: one that cannot be
    // written is said at once.
    OutputFile out(options.out);
    std::optional<OutputFile> gains;
    if (!options.tune_gains.empty())
    {
      gains.emplace(options.tune_gains);
    }
    BagCompensator compensator(options, params);
    compensator.run(&in, out.temporary());
    const std::string tuned = gains ? compensator.tuneGains() : std::string();
    out.commit();
    compensator.printSummary();
    std::fprintf(stderr, "compensate_bag: wrote %s\n", options.out.c_str());
    if (gains)
    {
      gains->commit(tuned);
      std::fprintf(stderr, "compensate_bag: wrote %s\n", options.tune_gains.c_str());
    }
    return 0;
  }
  catch (const UsageError& e)
  {
    std::fprintf(stderr, "compensate_bag: %s\n%s", e.what(), kUsage);
    return 2;
  }
  catch (const std::exception& e)
  {
    std::fprintf(stderr, "compensate_bag: error: %s\n", e.what());
    return 1;
  }
}

#ifndef PBC_COMPENSATE_BAG_NO_MAIN
int main(int argc, char** argv)
{
  return compensateBagMain(argc, argv);
}
#endif
