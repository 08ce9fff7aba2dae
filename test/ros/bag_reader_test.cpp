// BagReader without a master: on bags written by rosbag itself (uncompressed, LZ4, BZ2, small
// chunks, several topics, times tied across topics and out of order inside a chunk and across
// chunks, a bag written topic after topic) it gives the messages of the selected connections
// exactly as rosbag::View gives them: each topic's sequence of times and bytes the same, and the
// whole in time order. More overlapping chunks than it holds are said (usable), and a cut or
// garbled file throws BagFormatError.
#include <cstdint>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/String.h>

#include "../common/test_size.h"
#include "periodic_bias_compensation/ros/bag_reader.h"

using periodic_bias_compensation::BagFormatError;
using periodic_bias_compensation::BagReader;

namespace
{
const std::vector<std::string> kTopics = { "/a", "/b", "/c" };

/// A temporary file, removed at the end of the test.
struct TempBag
{
  std::string path = ::testing::TempDir() + "bag_reader_" + std::to_string(::getpid()) + "_" +
                     ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".bag";
  ~TempBag()
  {
    std::remove(path.c_str());
  }
};

/// Strings of pseudo-random length on kTopics, the times (from 1000 s) of `times` in the order
/// written, chunks of `chunk_threshold` bytes.
void writeBag(const std::string& path, rosbag::compression::CompressionType compression, std::uint32_t chunk_threshold,
              const std::vector<ros::Time>& times, unsigned seed)
{
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::size_t> length(0, 300);
  std::uniform_int_distribution<std::size_t> topic(0, kTopics.size() - 1);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(compression);
  bag.setChunkThreshold(chunk_threshold);
  for (std::size_t i = 0; i < times.size(); ++i)
  {
    std_msgs::String message;
    message.data.assign(length(random), static_cast<char>('a' + i % 26));
    bag.write(kTopics[topic(random)], times[i], message);
  }
  bag.close();
}

/// Times rising by 10 ms, each repeated (ties across topics); with `back_steps`, every 7th is
/// 20 ms back in time (out of order inside its chunk, if the chunks are large).
std::vector<ros::Time> recordedTimes(int count, bool back_steps = false)
{
  std::vector<ros::Time> times;
  for (int i = 0; i < count; ++i)
  {
    const double t = 1000.0 + 0.01 * (i / 2) - (back_steps && i % 7 == 0 ? 0.02 : 0.0);
    times.push_back(ros::Time(t));
  }
  return times;
}

struct Read
{
  std::string topic;
  ros::Time time;
  std::vector<std::uint8_t> bytes;
};

/// rosbag::View over the connections of `topics`.
std::vector<Read> readWithView(const std::string& path, const std::vector<std::string>& topics)
{
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<Read> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topics)))
  {
    Read r{ m.getTopic(), m.getTime(), std::vector<std::uint8_t>(m.size()) };
    ros::serialization::OStream stream(r.bytes.data(), static_cast<std::uint32_t>(r.bytes.size()));
    m.write(stream);
    out.push_back(std::move(r));
  }
  return out;
}

/// BagReader over the connections of `topics`; *chunks: how many times next() gave messages.
std::vector<Read> readWithReader(const std::string& path, const std::vector<std::string>& topics, int* chunks = nullptr)
{
  BagReader reader(path);
  EXPECT_TRUE(reader.usable());
  std::map<std::uint32_t, std::string> topic_of;
  std::vector<std::uint32_t> ids;
  for (const BagReader::Connection& c : reader.connections())
  {
    topic_of[c.id] = c.topic;
    if (std::find(topics.begin(), topics.end(), c.topic) != topics.end())
      ids.push_back(c.id);
  }
  reader.select(ids);
  std::vector<Read> out;
  std::vector<BagReader::Message> messages;
  int given = 0;
  while (reader.next(&messages))
  {
    ++given;
    for (const BagReader::Message& m : messages)
      out.push_back(Read{ topic_of.at(m.connection), m.time, std::vector<std::uint8_t>(m.data, m.data + m.size) });
  }
  if (chunks)
    *chunks = given;
  return out;
}

std::map<std::string, std::vector<std::pair<ros::Time, std::vector<std::uint8_t>>>> byTopic(
    const std::vector<Read>& read)
{
  std::map<std::string, std::vector<std::pair<ros::Time, std::vector<std::uint8_t>>>> out;
  for (const Read& r : read)
    out[r.topic].emplace_back(r.time, r.bytes);
  return out;
}

/// How many messages *reader gives of all its connections.
std::size_t countAll(BagReader* reader)
{
  std::vector<std::uint32_t> ids;
  for (const BagReader::Connection& c : reader->connections())
    ids.push_back(c.id);
  reader->select(ids);
  std::vector<BagReader::Message> messages;
  std::size_t read = 0;
  while (reader->next(&messages))
    read += messages.size();
  return read;
}

void expectAsView(const std::string& path, const std::vector<std::string>& topics)
{
  const std::vector<Read> view = readWithView(path, topics);
  const std::vector<Read> reader = readWithReader(path, topics);
  ASSERT_EQ(reader.size(), view.size());
  EXPECT_TRUE(byTopic(reader) == byTopic(view)) << "a topic's messages differ from rosbag::View's";
  for (std::size_t i = 0; i < reader.size(); ++i)
  {
    // Ties between topics are the only freedom: rosbag leaves them to its heap.
    EXPECT_EQ(reader[i].time, view[i].time) << "message " << i;
  }
}
}  // namespace

TEST(BagReader, GivesWhatRosbagViewGives)
{
  constexpr int kMessages = periodic_bias_compensation::test::kSanitized ? 600 : 3000;
  for (const auto compression :
       { rosbag::compression::Uncompressed, rosbag::compression::LZ4, rosbag::compression::BZ2 })
  {
    // Many small chunks and one large one; times rising, or every 7th 20 ms back (across the
    // small chunks' boundaries too, which then overlap in time). Under the sanitizers a fifth of
    // the messages (still many small chunks): rosbag::View decompresses a chunk for every
    // message it reads, and each decompression's large buffer is a fresh mapping under ASan.
    for (const std::uint32_t threshold : { 1024u, 4096u * 1024u })
    {
      for (const bool back_steps : { false, true })
      {
        SCOPED_TRACE("compression " + std::to_string(compression) + ", chunks of " + std::to_string(threshold) +
                     (back_steps ? ", steps back" : ""));
        TempBag bag;
        writeBag(bag.path, compression, threshold, recordedTimes(kMessages, back_steps), 7 + threshold);
        expectAsView(bag.path, kTopics);
        expectAsView(bag.path, { "/b" });
        expectAsView(bag.path, { "/a", "/c" });
      }
    }
  }
}

TEST(BagReader, MergesABagWrittenTopicAfterTopic)
{
  // As a conversion from files per sensor writes it: every chunk of /a, then every one of /b and
  // /c, so that three chunks cover each time.
  TempBag bag;
  {
    rosbag::Bag out(bag.path, rosbag::bagmode::Write);
    out.setChunkThreshold(2048);
    const std::vector<ros::Time> times = recordedTimes(2000);
    for (const std::string& topic : kTopics)
    {
      for (std::size_t i = 0; i < times.size(); i += 2)
      {
        std_msgs::String message;
        message.data = topic + std::to_string(i);
        out.write(topic, times[i], message);
      }
    }
  }
  int chunks = 0;
  EXPECT_EQ(readWithReader(bag.path, kTopics, &chunks).size(), 3000u);
  EXPECT_GT(chunks, 30);
  expectAsView(bag.path, kTopics);
  expectAsView(bag.path, { "/c", "/a" });
}

TEST(BagReader, SkipsChunksWithoutTheSelectedConnections)
{
  // /c only in the last second: the chunks before hold none of it.
  TempBag bag;
  {
    rosbag::Bag out(bag.path, rosbag::bagmode::Write);
    out.setChunkThreshold(1024);
    std_msgs::String message;
    message.data.assign(200, 'x');
    for (int i = 0; i < 200; ++i)
      out.write(i < 180 ? "/a" : "/c", ros::Time(1000.0 + 0.01 * i), message);
  }
  int chunks = 0;
  const std::vector<Read> read = readWithReader(bag.path, { "/c" }, &chunks);
  EXPECT_EQ(read.size(), 20u);
  EXPECT_LE(chunks, 6);  // 20 messages of about 230 bytes in chunks of 1 kB
  expectAsView(bag.path, { "/c" });
}

TEST(BagReader, SaysWhenMoreChunksOverlapThanItHolds)
{
  // One message per chunk, all at the same time: every chunk covers it.
  for (const int chunks : { BagReader::kMaxOpenChunks, BagReader::kMaxOpenChunks + 1 })
  {
    TempBag bag;
    {
      rosbag::Bag out(bag.path, rosbag::bagmode::Write);
      out.setChunkThreshold(1);
      std_msgs::String message;
      for (int i = 0; i < chunks; ++i)
        out.write("/a", ros::Time(1000.0), message);
    }
    BagReader reader(bag.path);
    EXPECT_EQ(reader.usable(), chunks <= BagReader::kMaxOpenChunks) << chunks << " chunks";
    EXPECT_EQ(countAll(&reader), reader.usable() ? static_cast<std::size_t>(chunks) : 0u);
  }
}

TEST(BagReader, ThrowsOnACutOrGarbledFile)
{
  TempBag bag;
  writeBag(bag.path, rosbag::compression::Uncompressed, 4096, recordedTimes(300), 5);
  std::ifstream in(bag.path, std::ios::binary);
  const std::string original((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto readAll = [&bag](const std::string& bytes) {
    {
      std::ofstream out(bag.path, std::ios::binary | std::ios::trunc);
      out << bytes;
    }
    BagReader reader(bag.path);
    return countAll(&reader);
  };
  EXPECT_EQ(readAll(original), 300u);
  // Cut anywhere: the index is gone or points past the end.
  for (const std::size_t keep : { std::size_t{ 10 }, std::size_t{ 4200 }, original.size() / 2, original.size() - 5 })
    EXPECT_THROW(readAll(original.substr(0, keep)), BagFormatError) << "cut to " << keep << " bytes";
  // Four bytes set to 0xff every 61 bytes across the file, one place at a time (record and field
  // lengths, header fields, index entries, message data): it either reads a bag or throws
  // BagFormatError, and reads nothing outside its buffers (the sanitizer build runs this too).
  int thrown = 0;
  for (std::size_t at = 13; at + 4 <= original.size(); at += 61)
  {
    std::string garbled = original;
    for (int i = 0; i < 4; ++i)
      garbled[at + i] = static_cast<char>(0xff);
    try
    {
      readAll(garbled);
    }
    catch (const BagFormatError&)
    {
      ++thrown;
    }
  }
  EXPECT_GT(thrown, 0);
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
