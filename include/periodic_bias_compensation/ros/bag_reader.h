// BagReader: reads the messages of chosen connections of an indexed rosbag (format 2.0) in time
// order, a chunk at a time, with two reads of the file per chunk, holding only the chunks that
// overlap the time it is at. rosbag::View reads the whole bag's index at open, keeps every entry
// in a tree, parses every message record's header into a map and merges the connections through a
// heap; a tool that reads a whole recording once needs none of that.
//
//   BagReader in(path);
//   if (in.usable())
//   {
//     in.select({ imu_connection_id });
//     std::vector<BagReader::Message> messages;
//     while (in.next(&messages))
//       for (const BagReader::Message& m : messages) ...  // m.data valid until the next call
//   }
//
// The order is rosbag::View's: each connection's messages sorted by time, ties in the order of
// their chunks' info records and then of their places in the chunk, and the connections merged by
// time (ties between connections in that same order, which View leaves to its heap). Every
// length and offset read from the file is checked against what holds it; a file that does not
// match them throws BagFormatError (what is wrong, and where).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
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

  /// At most this many chunks are held at once: where more overlap in time, usable() is false.
  static constexpr int kMaxOpenChunks = 64;

  /// Whether next() reads this bag: it is not encrypted (rosbag decrypts with a plugin), and no
  /// more than kMaxOpenChunks of its chunks overlap in time (each is read whole and held while a
  /// message of it is still to come; as `rosbag record` writes a bag, none overlap). Where not,
  /// next() reads nothing: rosbag's reader is needed.
  bool usable() const
  {
    return usable_;
  }

  /// The connections (by id) whose messages next() gives from here, from the first on; none
  /// before this is called.
  void select(const std::vector<std::uint32_t>& ids);

  /// The next selected messages in time order (ties as above), a chunk's worth or so; false after
  /// the last. Their data lies in the reader's buffers, valid until the next call.
  bool next(std::vector<Message>* messages);

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

  /// An open chunk: its bytes, and its selected messages in order, `next` the first not given.
  struct Cursor
  {
    std::string record, plain;  ///< as read (and the index records after it); decompressed
    std::vector<Message> messages;
    std::size_t next = 0;
    std::size_t chunk = 0;  ///< its info record's index
  };

  /// `size` bytes at `offset` of the file into *out; BagFormatError where the file ends before.
  void readAt(std::uint64_t offset, std::size_t size, std::string* out) const;
  void readIndex();
  /// Reads the chunk of info `k` and the index records after it into an open Cursor.
  void openChunk(std::size_t k);
  /// Moves next_chunk_ past chunks that hold none of the selected connections.
  void skipUnselected();

  std::string path_;
  int fd_ = -1;
  std::uint64_t file_size_ = 0;
  std::uint64_t index_position_ = 0;
  std::vector<Connection> connections_;
  std::vector<ChunkInfo> chunks_;         ///< in the order of their info records
  std::vector<std::uint64_t> positions_;  ///< the chunks' places in the file, rising
  std::vector<std::size_t> order_;        ///< chunks by start time (ties in info order)
  ros::Time begin_, end_;
  bool usable_ = false;
  std::vector<std::uint32_t> selected_;                ///< connection ids, sorted
  std::size_t next_chunk_ = 0;                         ///< in order_: the next to open
  std::vector<std::unique_ptr<Cursor>> open_, spare_;  ///< spare_: buffers to reuse
  // Buffers reused from chunk to chunk.
  std::string header_;
  std::vector<Entry> entries_;
};
}  // namespace periodic_bias_compensation
