// BagWriter without a master: a bag written past the page cache (direct I/O, in aligned blocks
// with an unaligned tail) holds the same bytes as one written with ordinary writes, and rosbag
// reads back every message, its connection, time and bytes, whatever the file's length against
// the block size.
#include <cstdint>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <std_msgs/String.h>

#include "periodic_bias_compensation/ros/bag_writer.h"

using periodic_bias_compensation::BagWriter;

namespace
{
struct Written
{
  std::uint32_t connection;
  ros::Time time;
  std::vector<std::uint8_t> bytes;  ///< a serialised std_msgs/String
};

/// `count` strings of 0 .. `max_length` pseudo-random characters on two topics.
std::vector<Written> messages(int count, std::size_t max_length, unsigned seed)
{
  std::mt19937 random(seed);
  std::uniform_int_distribution<std::size_t> length(0, max_length);
  std::uniform_int_distribution<int> character('a', 'z');
  std::vector<Written> out;
  for (int i = 0; i < count; ++i)
  {
    std_msgs::String message;
    message.data.resize(length(random));
    for (char& c : message.data)
    {
      c = static_cast<char>(character(random));
    }
    Written w{ static_cast<std::uint32_t>(i % 2), ros::Time(1000, 0) + ros::Duration(0.01 * i), {} };
    w.bytes.resize(ros::serialization::serializationLength(message));
    ros::serialization::OStream stream(w.bytes.data(), static_cast<std::uint32_t>(w.bytes.size()));
    ros::serialization::serialize(stream, message);
    out.push_back(std::move(w));
  }
  return out;
}

/// Writes `written` to `path`; returns whether the file was written past the page cache.
bool writeBag(const std::string& path, const std::vector<Written>& written, bool background, bool direct_io)
{
  BagWriter out(path, BagWriter::Compression::kNone, background, BagWriter::kDefaultChunkThreshold, direct_io);
  const std::uint32_t a = out.addConnection<std_msgs::String>("/a");
  const std::uint32_t b = out.addConnection<std_msgs::String>("/b");
  for (const Written& w : written)
  {
    out.write(w.connection == 0 ? a : b, w.time, w.bytes.data(), static_cast<std::uint32_t>(w.bytes.size()));
  }
  out.close();
  return out.directIo();
}

std::vector<char> fileBytes(const std::string& path)
{
  std::ifstream file(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

/// Every message read back by rosbag, in order, as written.
void expectReadBack(const std::string& path, const std::vector<Written>& written)
{
  rosbag::Bag bag;
  bag.open(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  ASSERT_EQ(view.size(), written.size());
  std::size_t i = 0;
  for (const rosbag::MessageInstance& m : view)
  {
    const Written& w = written[i++];
    EXPECT_EQ(m.getTopic(), w.connection == 0 ? "/a" : "/b");
    EXPECT_EQ(m.getTime(), w.time);
    std::vector<std::uint8_t> bytes(m.size());
    ros::serialization::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
    m.write(stream);
    ASSERT_EQ(bytes, w.bytes) << "message " << i - 1;
  }
}

std::string tempPath(const std::string& name)
{
  return ::testing::TempDir() + "bag_writer_" + name + ".bag";
}

/// Whether the file system of `path` opens files for direct I/O.
bool allowsDirectIo(const std::string& path)
{
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_DIRECT, 0600);
  if (fd < 0)
  {
    return false;
  }
  ::close(fd);
  std::remove(path.c_str());
  return true;
}
}  // namespace

TEST(BagWriter, DirectAndOrdinaryWritesGiveTheSameBag)
{
  // From one message (the file shorter than a block) to several blocks and a tail; the lengths
  // vary so that neither the chunks nor the file end on a block boundary.
  for (const int count : { 1, 40, 9000, 21000 })
  {
    const std::vector<Written> written = messages(count, 1500, static_cast<unsigned>(count));
    for (const bool background : { false, true })
    {
      const std::string direct = tempPath("direct"), ordinary = tempPath("ordinary");
      const bool was_direct = writeBag(direct, written, background, true);
      EXPECT_EQ(was_direct, allowsDirectIo(tempPath("probe")));
      EXPECT_FALSE(writeBag(ordinary, written, background, false));
      SCOPED_TRACE(std::to_string(count) + " messages, " + (background ? "writer thread" : "one thread") +
                   (was_direct ? ", direct I/O" : ", direct I/O refused by the file system"));
      const std::vector<char> bytes = fileBytes(direct);
      EXPECT_EQ(bytes, fileBytes(ordinary));
      if (count == 21000)
      {
        EXPECT_GT(bytes.size(), 3 * BagWriter::kBlockSize);
        EXPECT_NE(bytes.size() % 4096, 0u);
      }
      expectReadBack(direct, written);
      std::remove(direct.c_str());
      std::remove(ordinary.c_str());
    }
  }
}

TEST(BagWriter, UnwritableFileIsAnErrorNamingIt)
{
  const std::string path = "/nonexistent-directory/out.bag";
  try
  {
    BagWriter out(path, BagWriter::Compression::kNone);
    FAIL() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

int main(int argc, char** argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
