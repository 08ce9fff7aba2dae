// BagReader: reads the messages of chosen connections of an indexed rosbag (format 2.0) in time
// order, one chunk at a time, with two reads of the file per chunk. rosbag::View parses every
// message record's header into a map, keeps every index entry of the bag in a tree and merges
// the connections through a heap; a tool that reads a whole recording once needs none of that
// when the recording's chunks follow one another in time (as `rosbag record` writes them).
//
//   BagReader in(path);
//   if (in.chunksInTimeOrder())
//   {
//     in.select({ imu_connection_id });
//     std::vector<BagReader::Message> messages;
//     while (in.nextChunk(&messages))
//       for (const BagReader::Message& m : messages) ...  // m.data valid until the next call
//   }
//
// The order is rosbag::View's: each connection's messages sorted by time, ties in file order,
// and the connections merged by time (ties between connections in file order, which View leaves
// to its heap). Every length and offset read from the file is checked against what holds it;
// a file that does not match them throws BagFormatError (what is wrong, and where).
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <ros/time.h>

namespace periodic_bias_compensation
{
/// The bag's structure is not what its own records say (truncated, corrupt, not a 2.0 bag).
class BagFormatError : public std::runtime_error
{
public:
  using std::runtime_error::runtime_error;
};

class BagReader
{
public:
  struct Connection
  {
    std::uint32_t id = 0;
    std::string topic;                          ///< as in its record
    std::map<std::string, std::string> header;  ///< its connection header (type, md5sum, ...)
    std::uint64_t messages = 0;                 ///< in the bag, as its chunk info records count them
  };
  struct Message
  {
    std::uint32_t connection = 0;  ///< id
    ros::Time time;                ///< in the bag (its index entry's, as rosbag gives it)
    const std::uint8_t* data = nullptr;
    std::uint32_t size = 0;
  };

  /// Opens `path` and reads its index: the file header, connection and chunk info records.
  /// Throws BagFormatError where they do not fit the file, std::runtime_error if it cannot be read.
  explicit BagReader(const std::string& path);
  ~BagReader();
  BagReader(const BagReader&) = delete;
  BagReader& operator=(const BagReader&) = delete;

  const std::vector<Connection>& connections() const
  {
    return connections_;
  }

  /// The earliest and latest message time, as the chunk info records say.
  ros::Time beginTime() const
  {
    return begin_;
  }
  ros::Time endTime() const
  {
    return end_;
  }

  /// Whether reading the chunks in file order gives the messages in time order: the chunks lie
  /// in the file in the order of their info records, and none starts before one before it ends;
  /// and the bag is not encrypted. Where not, nextChunk() reads nothing (a reader that merges
  /// the chunks is needed: rosbag's).
  bool chunksInTimeOrder() const
  {
    return in_time_order_;
  }

  /// The connections (by id) whose messages nextChunk() gives from here, from the first chunk on;
  /// none before this is called.
  void select(const std::vector<std::uint32_t>& ids);

  /// The selected messages of the next chunk holding any, in time order (ties in file order);
  /// false after the last. Their data lies in the reader's buffer, valid until the next call.
  bool nextChunk(std::vector<Message>* messages);

private:
  struct ChunkInfo
  {
    std::uint64_t position = 0;
    ros::Time start, end;
    std::vector<std::uint32_t> connections;  ///< those it holds messages of (one index record each)
  };
  struct Entry
  {
    ros::Time time;
    std::uint32_t offset;  ///< of the message record in the chunk's uncompressed data
    std::uint32_t connection;
  };

  /// `size` bytes at `offset` of the file into *out; BagFormatError where the file ends before.
  void readAt(std::uint64_t offset, std::size_t size, std::string* out) const;
  void readIndex();
  /// Reads the chunk of info `k` and the index records after it; its selected messages into
  /// *messages.
  void readChunk(std::size_t k, std::vector<Message>* messages);

  std::string path_;
  int fd_ = -1;
  std::uint64_t file_size_ = 0;
  std::uint64_t index_position_ = 0;
  std::vector<Connection> connections_;
  std::vector<ChunkInfo> chunks_;
  ros::Time begin_, end_;
  bool in_time_order_ = false;
  std::vector<std::uint32_t> selected_;  ///< connection ids, sorted
  std::size_t next_chunk_ = 0;
  // Buffers reused from chunk to chunk.
  std::string header_, record_, plain_;
  std::vector<Entry> entries_;
};
}  // namespace periodic_bias_compensation
