#include "periodic_bias_compensation/ros/bag_writer.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <unistd.h>

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include "bag_format.h"

namespace periodic_bias_compensation
{
namespace
{
using namespace bag_format;
// Record sizes of the rosbag 2.0 format (rosbag/constants.h).
constexpr std::uint32_t kFileHeaderLength = 4096;  ///< header + padding of the file header record
constexpr std::uint32_t kIndexVersion = 1, kChunkInfoVersion = 1;
constexpr int kLz4BlockSizeId = 6;  ///< as rosbag's LZ4 stream
constexpr int kBz2BlockSize = 9, kBz2WorkFactor = 30;
/// Alignment of a direct write's buffer, offset and length: the page size, a multiple of every
/// device's logical block size.
constexpr std::size_t kDirectAlignment = 4096;
static_assert(BagWriter::kBlockSize % kDirectAlignment == 0);

void appendU32(std::vector<std::uint8_t>* out, std::uint32_t value)
{
  for (int i = 0; i < 4; ++i)
  {
    out->push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
}

void putU32(std::uint8_t* out, std::uint32_t value)
{
  for (int i = 0; i < 4; ++i)
  {
    out[i] = static_cast<std::uint8_t>(value >> (8 * i));
  }
}

void putTime(std::uint8_t* out, const ros::Time& time)
{
  putU32(out, time.sec);
  putU32(out + 4, time.nsec);
}

/// One "name=value" field of a record header.
void appendField(std::vector<std::uint8_t>* out, const std::string& name, const void* value, std::size_t size)
{
  appendU32(out, static_cast<std::uint32_t>(name.size() + 1 + size));
  out->insert(out->end(), name.begin(), name.end());
  out->push_back('=');
  const auto* bytes = static_cast<const std::uint8_t*>(value);
  out->insert(out->end(), bytes, bytes + size);
}

void appendField(std::vector<std::uint8_t>* out, const std::string& name, std::uint32_t value)
{
  std::uint8_t bytes[4];
  putU32(bytes, value);
  appendField(out, name, bytes, 4);
}

void appendField(std::vector<std::uint8_t>* out, const std::string& name, std::uint64_t value)
{
  std::uint8_t bytes[8];
  putU32(bytes, static_cast<std::uint32_t>(value));
  putU32(bytes + 4, static_cast<std::uint32_t>(value >> 32));
  appendField(out, name, bytes, 8);
}

void appendField(std::vector<std::uint8_t>* out, const std::string& name, const ros::Time& value)
{
  std::uint8_t bytes[8];
  putTime(bytes, value);
  appendField(out, name, bytes, 8);
}

void appendOp(std::vector<std::uint8_t>* out, std::uint8_t op)
{
  appendField(out, "op", &op, 1);
}

/// A header of "name=value" fields in name order, as ros::Header::write writes a connection header.
void appendHeader(std::vector<std::uint8_t>* out, const std::map<std::string, std::string>& fields)
{
  for (const auto& [name, value] : fields)
  {
    appendField(out, name, value.data(), value.size());
  }
}

/// A connection record (op, conn, topic; its data the connection header).
void appendConnectionRecord(std::vector<std::uint8_t>* out, std::uint32_t id, const std::string& topic,
                            const std::map<std::string, std::string>& header)
{
  std::vector<std::uint8_t> fields;
  appendField(&fields, "conn", id);
  appendOp(&fields, kOpConnection);
  appendField(&fields, "topic", topic.data(), topic.size());
  std::vector<std::uint8_t> data;
  appendHeader(&data, header);
  appendU32(out, static_cast<std::uint32_t>(fields.size()));
  out->insert(out->end(), fields.begin(), fields.end());
  appendU32(out, static_cast<std::uint32_t>(data.size()));
  out->insert(out->end(), data.begin(), data.end());
}

/// Size of a message record's header: fields conn (4 bytes), op (1), time (8).
constexpr std::uint32_t kMessageHeaderLength = (4 + 5 + 4) + (4 + 3 + 1) + (4 + 5 + 8);
}  // namespace

BagWriter::BagWriter(const std::string& path, Compression compression, bool background, std::uint32_t chunk_threshold,
                     bool direct_io)
  : path_(path), compression_(compression), chunk_threshold_(std::max<std::uint32_t>(chunk_threshold, 1))
{
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd_ < 0)
  {
    throw std::runtime_error("cannot create " + path + ": " + std::strerror(errno));
  }
  // File systems without direct I/O (tmpfs before Linux 6.6, some network ones) refuse the flag.
  void* block = nullptr;
  const int flags = ::fcntl(fd_, F_GETFL);
  if (direct_io && flags >= 0 && ::posix_memalign(&block, kDirectAlignment, kBlockSize) == 0)
  {
    block_.reset(static_cast<std::uint8_t*>(block));
    direct_ = direct_granted_ = ::fcntl(fd_, F_SETFL, flags | O_DIRECT) == 0;
    if (!direct_)
    {
      block_.reset();
    }
  }
  chunk_.data.reserve(chunk_threshold_ + 64 * 1024);
  writeBytes(kMagic.data(), kMagic.size());
  const std::vector<std::uint8_t> header = fileHeader(0);
  writeBytes(header.data(), header.size());
  if (background)
  {
    thread_ = std::make_unique<WorkThread<Chunk>>(
        1, [this](Chunk& chunk) { storeChunk(&chunk); }, true);
  }
}

BagWriter::~BagWriter()
{
  thread_.reset();  // what waits is dropped: the file is incomplete without close() anyway
  if (fd_ >= 0)
  {
    ::close(fd_);
  }
}

void BagWriter::FreeBlock::operator()(std::uint8_t* block) const
{
  std::free(block);
}

const char* BagWriter::toString(Compression compression)
{
  switch (compression)
  {
    case Compression::kNone:
      return "none";
    case Compression::kLz4:
      return "lz4";
    case Compression::kBz2:
      return "bz2";
  }
  return "none";
}

std::uint32_t BagWriter::addConnection(const std::string& topic, std::map<std::string, std::string> header)
{
  header["topic"] = topic;
  connections_.push_back(Connection{ topic, std::move(header), false });
  return static_cast<std::uint32_t>(connections_.size() - 1);
}

std::uint8_t* BagWriter::beginMessage(std::uint32_t connection, const ros::Time& time, std::uint32_t length)
{
  if (connection >= connections_.size())
  {
    throw std::logic_error("BagWriter: unknown connection " + std::to_string(connection));
  }
  Connection& c = connections_[connection];
  if (!c.written)
  {
    // The first message of a connection follows its record, as rosbag writes it (rosbag
    // reindex finds connections there).
    appendConnectionRecord(&chunk_.data, connection, c.topic, c.header);
    c.written = true;
  }
  chunk_.start = chunk_.messages == 0 ? time : std::min(chunk_.start, time);
  chunk_.end = chunk_.messages == 0 ? time : std::max(chunk_.end, time);
  ++chunk_.messages;
  const std::size_t offset = chunk_.data.size();
  if (chunk_.index.size() <= connection)
  {
    chunk_.index.resize(connections_.size());
  }
  chunk_.index[connection].push_back(IndexEntry{ time, static_cast<std::uint32_t>(offset) });

  chunk_.data.resize(offset + 4 + kMessageHeaderLength + 4 + length);
  std::uint8_t* p = chunk_.data.data() + offset;
  putU32(p, kMessageHeaderLength);
  p += 4;
  putU32(p, 5 + 4);
  std::memcpy(p + 4, "conn=", 5);
  putU32(p + 9, connection);
  p += 13;
  putU32(p, 3 + 1);
  std::memcpy(p + 4, "op=", 3);
  p[7] = kOpMessage;
  p += 8;
  putU32(p, 5 + 8);
  std::memcpy(p + 4, "time=", 5);
  putTime(p + 9, time);
  p += 17;
  putU32(p, length);
  return p + 4;
}

void BagWriter::endMessage()
{
  if (chunk_.data.size() >= chunk_threshold_)
  {
    finishChunk();
  }
}

void BagWriter::write(std::uint32_t connection, const ros::Time& time, const rosbag::MessageInstance& message)
{
  const std::uint32_t length = message.size();
  ros::serialization::OStream stream(beginMessage(connection, time, length), length);
  message.write(stream);
  endMessage();
}

void BagWriter::write(std::uint32_t connection, const ros::Time& time, const std::uint8_t* data, std::uint32_t size)
{
  std::uint8_t* target = beginMessage(connection, time, size);
  if (size > 0)
  {
    std::memcpy(target, data, size);
  }
  endMessage();
}

void BagWriter::finishChunk()
{
  if (chunk_.messages == 0)
  {
    return;
  }
  if (!thread_)
  {
    storeChunk(&chunk_);
    return;
  }
  thread_->hand(std::move(chunk_));
  if (std::optional<Chunk> stored = thread_->takeDone())
  {
    chunk_ = std::move(*stored);
  }
  else
  {
    chunk_ = Chunk();
    chunk_.data.reserve(chunk_threshold_ + 64 * 1024);
  }
}

void BagWriter::storeChunk(Chunk* chunk)
{
  const auto size = static_cast<unsigned int>(chunk->data.size());
  const char* data = reinterpret_cast<const char*>(chunk->data.data());
  unsigned int data_size = size;
  if (compression_ == Compression::kLz4)
  {
    compressed_.resize(size + size / 255 + 4096);
    data_size = static_cast<unsigned int>(compressed_.size());
    if (roslz4_buffToBuffCompress(reinterpret_cast<char*>(chunk->data.data()), size, compressed_.data(), &data_size,
                                  kLz4BlockSizeId) != ROSLZ4_OK)
    {
      throw std::runtime_error("cannot write " + path_ + ": LZ4 compression failed");
    }
    data = compressed_.data();
  }
  else if (compression_ == Compression::kBz2)
  {
    compressed_.resize(size + size / 100 + 4096);
    data_size = static_cast<unsigned int>(compressed_.size());
    if (BZ2_bzBuffToBuffCompress(compressed_.data(), &data_size, reinterpret_cast<char*>(chunk->data.data()), size,
                                 kBz2BlockSize, 0, kBz2WorkFactor) != BZ_OK)
    {
      throw std::runtime_error("cannot write " + path_ + ": BZ2 compression failed");
    }
    data = compressed_.data();
  }

  ChunkInfo info{ position_, chunk->start, chunk->end, {} };
  std::vector<std::uint8_t> header;
  const std::string compression = toString(compression_);
  appendField(&header, "compression", compression.data(), compression.size());
  appendOp(&header, kOpChunk);
  appendField(&header, "size", static_cast<std::uint32_t>(size));
  record_.clear();
  appendU32(&record_, static_cast<std::uint32_t>(header.size()));
  record_.insert(record_.end(), header.begin(), header.end());
  appendU32(&record_, data_size);
  writeBytes(record_.data(), record_.size());
  writeBytes(data, data_size);

  // One index record per connection in the chunk: time and offset of each of its messages.
  record_.clear();
  for (std::uint32_t id = 0; id < chunk->index.size(); ++id)
  {
    std::vector<IndexEntry>& entries = chunk->index[id];
    if (entries.empty())
    {
      continue;
    }
    info.counts.emplace_back(id, static_cast<std::uint32_t>(entries.size()));
    header.clear();
    appendField(&header, "conn", id);
    appendField(&header, "count", static_cast<std::uint32_t>(entries.size()));
    appendOp(&header, kOpIndexData);
    appendField(&header, "ver", kIndexVersion);
    appendU32(&record_, static_cast<std::uint32_t>(header.size()));
    record_.insert(record_.end(), header.begin(), header.end());
    appendU32(&record_, static_cast<std::uint32_t>(12 * entries.size()));
    for (const IndexEntry& e : entries)
    {
      appendU32(&record_, e.time.sec);
      appendU32(&record_, e.time.nsec);
      appendU32(&record_, e.offset);
    }
    entries.clear();
  }
  writeBytes(record_.data(), record_.size());
  chunks_.push_back(std::move(info));
  chunk->data.clear();
  chunk->messages = 0;
}

std::vector<std::uint8_t> BagWriter::fileHeader(std::uint64_t index_position) const
{
  std::vector<std::uint8_t> header;
  appendField(&header, "chunk_count", static_cast<std::uint32_t>(chunks_.size()));
  appendField(&header, "conn_count", static_cast<std::uint32_t>(connections_.size()));
  appendField(&header, "index_pos", index_position);
  appendOp(&header, kOpFileHeader);
  std::vector<std::uint8_t> record;
  appendU32(&record, static_cast<std::uint32_t>(header.size()));
  record.insert(record.end(), header.begin(), header.end());
  const std::uint32_t padding = kFileHeaderLength - static_cast<std::uint32_t>(header.size());
  appendU32(&record, padding);
  record.resize(record.size() + padding, ' ');
  return record;
}

void BagWriter::close()
{
  if (fd_ < 0)
  {
    return;
  }
  finishChunk();
  if (thread_)
  {
    thread_->finish();
  }
  const std::uint64_t index_position = position_;
  std::vector<std::uint8_t> records;
  for (std::uint32_t id = 0; id < connections_.size(); ++id)
  {
    appendConnectionRecord(&records, id, connections_[id].topic, connections_[id].header);
  }
  for (const ChunkInfo& chunk : chunks_)
  {
    std::vector<std::uint8_t> header;
    appendField(&header, "chunk_pos", chunk.position);
    appendField(&header, "count", static_cast<std::uint32_t>(chunk.counts.size()));
    appendField(&header, "end_time", chunk.end);
    appendOp(&header, kOpChunkInfo);
    appendField(&header, "start_time", chunk.start);
    appendField(&header, "ver", kChunkInfoVersion);
    appendU32(&records, static_cast<std::uint32_t>(header.size()));
    records.insert(records.end(), header.begin(), header.end());
    appendU32(&records, static_cast<std::uint32_t>(8 * chunk.counts.size()));
    for (const auto& [id, count] : chunk.counts)
    {
      appendU32(&records, id);
      appendU32(&records, count);
    }
  }
  writeBytes(records.data(), records.size());
  // The whole blocks past the page cache, the tail (not a whole block) and the final file header
  // (over the first one) as ordinary writes.
  if (direct_)
  {
    const std::size_t whole = block_used_ - block_used_ % kDirectAlignment;
    const std::size_t tail = block_used_ - whole;
    block_used_ = whole;
    if (whole > 0)
    {
      writeBlock();
    }
    stopDirectIo();
    writeAll(block_.get() + whole, tail);
  }
  const std::vector<std::uint8_t> header = fileHeader(index_position);
  const ssize_t written = ::pwrite(fd_, header.data(), header.size(), static_cast<off_t>(kMagic.size()));
  if (written != static_cast<ssize_t>(header.size()))
  {
    if (written >= 0)
    {
      errno = EIO;  // a short write of 4 kB where the file already holds them
    }
    fail("write");
  }
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0)
  {
    fail("write");
  }
}

void BagWriter::writeBytes(const void* data, std::size_t size)
{
  position_ += size;
  const auto* bytes = static_cast<const std::uint8_t*>(data);
  while (direct_ && size > 0)
  {
    const std::size_t n = std::min(size, kBlockSize - block_used_);
    std::memcpy(block_.get() + block_used_, bytes, n);
    block_used_ += n;
    bytes += n;
    size -= n;
    if (block_used_ == kBlockSize)
    {
      writeBlock();
    }
  }
  writeAll(bytes, size);
}

void BagWriter::writeBlock()
{
  const std::uint8_t* data = block_.get();
  std::size_t size = block_used_;
  block_used_ = 0;
  while (direct_ && size > 0)
  {
    const ssize_t written = ::write(fd_, data, size);
    if (written > 0)
    {
      data += written;
      size -= static_cast<std::size_t>(written);
    }
    else if (written < 0 && errno == EINVAL)
    {
      // Refused by the device or file system, or a short write left the offset unaligned.
      stopDirectIo();
      direct_granted_ = false;
    }
    else if (written == 0 || errno != EINTR)
    {
      break;  // writeAll() says why
    }
  }
  writeAll(data, size);
}

void BagWriter::writeAll(const std::uint8_t* data, std::size_t size)
{
  while (size > 0)
  {
    const ssize_t written = ::write(fd_, data, size);
    if (written < 0 && errno == EINTR)
    {
      continue;
    }
    if (written <= 0)
    {
      if (written == 0)
      {
        errno = EIO;  // no progress and no error: not to loop forever
      }
      fail("write");
    }
    data += written;
    size -= static_cast<std::size_t>(written);
  }
}

void BagWriter::stopDirectIo()
{
  if (!direct_)
  {
    return;
  }
  direct_ = false;
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags < 0 || ::fcntl(fd_, F_SETFL, flags & ~O_DIRECT) != 0)
  {
    fail("write");
  }
}

void BagWriter::fail(const char* what) const
{
  throw std::runtime_error(std::string("cannot ") + what + " " + path_ + ": " + std::strerror(errno));
}
}  // namespace periodic_bias_compensation
