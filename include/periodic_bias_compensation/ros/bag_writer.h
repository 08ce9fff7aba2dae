// BagWriter: writes a rosbag (format 2.0, indexed, readable by rosbag and `rosbag info`) in one
// pass, appending to an in-memory chunk and writing each chunk with one call. rosbag::Bag::write
// seeks to the end of the file twice for every message (it may have been reading); a writer that
// never reads needs none of that, and a message already serialised in another bag is copied as
// its bytes (rosbag::MessageInstance), not deserialised. With `background`, full chunks are
// compressed and written by a thread of the writer's own while the next one fills (at most two
// chunks wait), so compression and file writes overlap the caller's work.
//
// The file is written past the page cache (O_DIRECT, in aligned blocks of kBlockSize) where the
// file system allows it: the kernel then copies nothing, and gigabytes of output do not evict
// what the machine's other programs have cached. Where it does not, the writes are ordinary ones.
//
//   BagWriter out(path, BagWriter::Compression::kNone);
//   const std::uint32_t odom = out.addConnection<nav_msgs::Odometry>("/odometry/filtered");
//   out.write(odom, stamp, message);
//   out.close();  // writes the index; without it the file is not a complete bag
//
// Errors (cannot open, write or compress) throw std::runtime_error naming the file.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/time.h>
#include <rosbag/message_instance.h>

#include "periodic_bias_compensation/common/work_thread.h"

namespace periodic_bias_compensation
{
class BagWriter
{
public:
  enum class Compression
  {
    kNone,
    kLz4,
    kBz2,
  };

  /// rosbag's own chunk size (rosbag::Bag's default chunk threshold).
  static constexpr std::uint32_t kDefaultChunkThreshold = 768 * 1024;
  /// Bytes gathered before a write past the page cache (a multiple of any device's block size).
  static constexpr std::size_t kBlockSize = 4 << 20;

  /// Creates (truncates) `path` and writes the bag's file header. `background`: chunks are
  /// compressed and written by a thread (an error there is thrown by the next write() or close()).
  /// `direct_io`: past the page cache where the file system allows it (false: ordinary writes;
  /// the file's bytes are the same either way).
  BagWriter(const std::string& path, Compression compression, bool background = false,
            std::uint32_t chunk_threshold = kDefaultChunkThreshold, bool direct_io = true);
  /// Closes the file without writing the index if close() was not called (the file is then
  /// incomplete: the caller removes it).
  ~BagWriter();
  BagWriter(const BagWriter&) = delete;
  BagWriter& operator=(const BagWriter&) = delete;

  /// A connection with its connection header (at least "type", "md5sum" and
  /// "message_definition"; "topic" is set to `topic`). Returns its id for write().
  std::uint32_t addConnection(const std::string& topic, std::map<std::string, std::string> header);

  /// A connection for messages of type M.
  template <class M>
  std::uint32_t addConnection(const std::string& topic)
  {
    return addConnection(topic, { { "type", ros::message_traits::datatype<M>() },
                                  { "md5sum", ros::message_traits::md5sum<M>() },
                                  { "message_definition", ros::message_traits::definition<M>() } });
  }

  /// Appends a message of a type with ROS serialisation.
  template <class M>
  void write(std::uint32_t connection, const ros::Time& time, const M& message)
  {
    const std::uint32_t length = ros::serialization::serializationLength(message);
    ros::serialization::OStream stream(beginMessage(connection, time, length), length);
    ros::serialization::serialize(stream, message);
    endMessage();
  }

  /// Appends a message read from another bag as its serialised bytes.
  void write(std::uint32_t connection, const ros::Time& time, const rosbag::MessageInstance& message);

  /// Appends a message already serialised (`size` bytes at `data`), copied as they are.
  void write(std::uint32_t connection, const ros::Time& time, const std::uint8_t* data, std::uint32_t size);

  /// Whether the file was written past the page cache (asked after close(); a refused direct
  /// write turns it off for the rest of the file).
  bool directIo() const
  {
    return direct_granted_;
  }

  /// Writes the last chunk, the index (connection and chunk info records) and the final file
  /// header, and closes the file.
  void close();

  static const char* toString(Compression compression);

private:
  struct IndexEntry
  {
    ros::Time time;
    std::uint32_t offset;  ///< of the message record in the uncompressed chunk
  };
  struct ChunkInfo
  {
    std::uint64_t position;
    ros::Time start, end;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> counts;  ///< connection, messages
  };
  struct Connection
  {
    std::string topic;
    std::map<std::string, std::string> header;
    bool written = false;  ///< its record is in a chunk already
  };
  struct Chunk
  {
    std::vector<std::uint8_t> data;              ///< its records, uncompressed
    std::vector<std::vector<IndexEntry>> index;  ///< per connection
    std::uint32_t messages = 0;
    ros::Time start, end;
  };

  /// Starts a message record of `length` data bytes in the chunk; returns where its data goes.
  std::uint8_t* beginMessage(std::uint32_t connection, const ros::Time& time, std::uint32_t length);
  void endMessage();
  /// Hands the open chunk on (to the thread, or stores it) and opens an empty one.
  void finishChunk();
  /// Compresses and writes a chunk and its index records (in the thread, if there is one).
  void storeChunk(Chunk* chunk);
  std::vector<std::uint8_t> fileHeader(std::uint64_t index_position) const;
  /// Appends to the file (through the block buffer while the writes are direct).
  void writeBytes(const void* data, std::size_t size);
  /// Writes the whole block buffer past the page cache (or, where refused, as ordinary writes).
  void writeBlock();
  /// Writes `size` bytes at the file's offset, all of them; throws on an error.
  void writeAll(const std::uint8_t* data, std::size_t size);
  /// Ordinary writes from now on: the file system or device refused an aligned direct one, or
  /// close() writes the unaligned tail.
  void stopDirectIo();
  [[noreturn]] void fail(const char* what) const;

  struct FreeBlock
  {
    void operator()(std::uint8_t* block) const;
  };

  std::string path_;
  int fd_ = -1;
  bool direct_ = false;                             ///< the writes are direct now
  bool direct_granted_ = false;                     ///< the file system allows them, and none was refused
  std::unique_ptr<std::uint8_t, FreeBlock> block_;  ///< kBlockSize bytes, aligned, while direct_
  std::size_t block_used_ = 0;
  Compression compression_;
  std::uint32_t chunk_threshold_;
  std::vector<Connection> connections_;
  Chunk chunk_;  ///< the open chunk
  // Written by storeChunk only (the thread's while it runs).
  std::uint64_t position_ = 0;  ///< file offset of the next byte written
  std::vector<char> compressed_;
  std::vector<ChunkInfo> chunks_;
  std::vector<std::uint8_t> record_;  ///< scratch for records
  /// With `background`: stores the full chunks (one in work, at most one waiting) and keeps them,
  /// their buffers reused.
  std::unique_ptr<WorkThread<Chunk>> thread_;
};
}  // namespace periodic_bias_compensation
