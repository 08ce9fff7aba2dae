#include "periodic_bias_compensation/ros/bag_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bag_format.h"
#include "periodic_bias_compensation/ros/bag_check.h"

namespace periodic_bias_compensation
{
namespace
{
using namespace bag_format;

ros::Time timeAt(const char* p)
{
  ros::Time t;
  t.sec = u32(p);
  t.nsec = u32(p + 4);
  return t;
}

std::string at(std::uint64_t where)
{
  return " at byte " + std::to_string(where);
}

/// The fields of a record header ("name=value", each after its u32 length), every length checked
/// against the header's. `where`: the header's place in the file, for the error.
template <typename Field>
void forEachField(std::string_view header, std::uint64_t where, Field field)
{
  std::size_t offset = 0;
  while (offset < header.size())
  {
    if (header.size() - offset < 4 || u32(header.data() + offset) > header.size() - offset - 4)
      throw BagFormatError("record header" + at(where) + " has a field running past its end");
    const std::string_view entry = header.substr(offset + 4, u32(header.data() + offset));
    offset += 4 + entry.size();
    const std::size_t equals = entry.find('=');
    if (equals != std::string_view::npos)
      field(entry.substr(0, equals), entry.substr(equals + 1));
  }
}

/// A record in `bytes` from `offset`: its header and data, both inside `bytes`. `base`: the
/// place of `bytes` in the file (or of the chunk's data, for a record inside a chunk).
struct Record
{
  std::string_view header, data;
  std::size_t end = 0;  ///< offset after it
};

Record recordAt(std::string_view bytes, std::size_t offset, std::uint64_t base)
{
  Record r;
  if (offset > bytes.size() || bytes.size() - offset < 8 || u32(bytes.data() + offset) > bytes.size() - offset - 8)
    throw BagFormatError("record" + at(base + offset) + " runs past what holds it");
  r.header = bytes.substr(offset + 4, u32(bytes.data() + offset));
  const std::size_t data_offset = offset + 8 + r.header.size();
  if (u32(bytes.data() + data_offset - 4) > bytes.size() - data_offset)
    throw BagFormatError("record data" + at(base + data_offset) + " runs past what holds it");
  r.data = bytes.substr(data_offset, u32(bytes.data() + data_offset - 4));
  r.end = data_offset + r.data.size();
  return r;
}

/// The record header's op, or 0 if it has none.
char opOf(std::string_view header, std::uint64_t where)
{
  char op = 0;
  forEachField(header, where, [&op](std::string_view name, std::string_view value) {
    if (name == "op" && value.size() == 1)
      op = value[0];
  });
  return op;
}

/// A field of fixed size (u32: 4, u64 and times: 8); BagFormatError if absent or of another size.
std::string_view fixedField(std::string_view header, std::uint64_t where, std::string_view name, std::size_t size)
{
  std::string_view found;
  bool present = false;
  forEachField(header, where, [&](std::string_view n, std::string_view value) {
    if (n == name)
    {
      found = value;
      present = true;
    }
  });
  if (!present || found.size() != size)
    throw BagFormatError("record header" + at(where) + " has no " + std::to_string(size) + "-byte field '" +
                         std::string(name) + "'");
  return found;
}
}  // namespace

BagReader::BagReader(const std::string& path) : path_(path)
{
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat status;
  if (fd_ < 0 || ::fstat(fd_, &status) != 0)
  {
    const int error = errno;
    if (fd_ >= 0)
      ::close(fd_);
    throw std::runtime_error("cannot read " + path + ": " + std::strerror(error));
  }
  file_size_ = static_cast<std::uint64_t>(status.st_size);
  try
  {
    readIndex();
  }
  catch (...)
  {
    ::close(fd_);
    throw;
  }
}

BagReader::~BagReader()
{
  ::close(fd_);
}

void BagReader::readAt(std::uint64_t offset, std::size_t size, std::string* out) const
{
  if (offset > file_size_ || size > file_size_ - offset)
    throw BagFormatError("the file ends" + at(file_size_) + ", inside the " + std::to_string(size) + " bytes" +
                         at(offset));
  out->resize(size);
  std::size_t done = 0;
  while (done < size)
  {
    const ssize_t n = ::pread(fd_, &(*out)[done], size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      throw std::runtime_error("cannot read " + path_ + ": " + std::strerror(errno));
    if (n == 0)
      throw BagFormatError("the file ends" + at(offset + done) + ", before the index says it does");
    done += static_cast<std::size_t>(n);
  }
}

void BagReader::readIndex()
{
  std::string bytes;
  readAt(0, kMagic.size() + 4, &bytes);
  if (std::string_view(bytes).substr(0, kMagic.size()) != kMagic)
    throw BagFormatError("the file does not start with '#ROSBAG V2.0'");
  // The file header record: where the index starts and what it holds.
  readAt(kMagic.size(), 4 + u32(bytes.data() + kMagic.size()) + 4, &bytes);
  const std::string_view file_header = std::string_view(bytes).substr(4, bytes.size() - 8);
  if (opOf(file_header, kMagic.size()) != kOpFileHeader)
    throw BagFormatError("the file does not begin with a file header record");
  index_position_ = u64(fixedField(file_header, kMagic.size(), "index_pos", 8).data());
  // rosbag decrypts the chunks of an encrypted bag with its plugin: not read here.
  bool encrypted = false;
  forEachField(file_header, kMagic.size(), [&encrypted](std::string_view name, std::string_view value) {
    encrypted = encrypted || (name == "encryptor" && !value.empty() && value != "rosbag/NoEncryptor");
  });
  const std::uint32_t connection_count = u32(fixedField(file_header, kMagic.size(), "conn_count", 4).data());
  const std::uint32_t chunk_count = u32(fixedField(file_header, kMagic.size(), "chunk_count", 4).data());
  if (index_position_ == 0 || index_position_ > file_size_)
    throw BagFormatError("the file header's index position " + std::to_string(index_position_) +
                         " is not inside the file (a bag cut off while recording has no index)");
  std::string index;
  readAt(index_position_, file_size_ - index_position_, &index);
  std::size_t offset = 0;
  // The connection records, then the chunk info records.
  const auto nextRecord = [&index, &offset, this](char op, const char* what, std::uint64_t* where) {
    *where = index_position_ + offset;
    const Record record = recordAt(index, offset, index_position_);
    offset = record.end;
    if (opOf(record.header, *where) != op)
      throw BagFormatError("record" + at(*where) + " is not the " + what + " record the file header announces");
    return record;
  };
  std::map<std::uint32_t, std::size_t> connection_of;  // id -> index in connections_
  for (std::uint32_t k = 0; k < connection_count; ++k)
  {
    std::uint64_t where = 0;
    const Record record = nextRecord(kOpConnection, "connection", &where);
    Connection c;
    c.id = u32(fixedField(record.header, where, "conn", 4).data());
    forEachField(record.header, where, [&c](std::string_view name, std::string_view value) {
      if (name == "topic")
        c.topic.assign(value);
    });
    forEachField(record.data, where, [&c](std::string_view name, std::string_view value) {
      c.header.emplace(std::string(name), std::string(value));
    });
    connection_of.emplace(c.id, connections_.size());
    connections_.push_back(std::move(c));
  }
  for (std::uint32_t k = 0; k < chunk_count; ++k)
  {
    std::uint64_t where = 0;
    const Record record = nextRecord(kOpChunkInfo, "chunk info", &where);
    ChunkInfo chunk;
    chunk.position = u64(fixedField(record.header, where, "chunk_pos", 8).data());
    chunk.start = timeAt(fixedField(record.header, where, "start_time", 8).data());
    chunk.end = timeAt(fixedField(record.header, where, "end_time", 8).data());
    const std::uint32_t count = u32(fixedField(record.header, where, "count", 4).data());
    if (record.data.size() != 8ULL * count)
      throw BagFormatError("chunk info record" + at(where) + " holds " + std::to_string(record.data.size()) +
                           " bytes for " + std::to_string(count) + " connections");
    for (std::uint32_t i = 0; i < count; ++i)
    {
      const std::uint32_t id = u32(record.data.data() + 8 * i);
      chunk.connections.push_back(id);
      const auto c = connection_of.find(id);
      if (c != connection_of.end())
        connections_[c->second].messages += u32(record.data.data() + 8 * i + 4);
    }
    begin_ = chunks_.empty() ? chunk.start : std::min(begin_, chunk.start);
    end_ = std::max(end_, chunk.end);
    chunks_.push_back(std::move(chunk));
  }
  // Where each chunk's bytes end (the next chunk in the file, or the index), and in which order
  // they are opened: by start time, ties in the order of their info records.
  for (const ChunkInfo& c : chunks_)
  {
    if (c.position >= index_position_)
      throw BagFormatError("a chunk info record points at byte " + std::to_string(c.position) + ", past the index");
    positions_.push_back(c.position);
  }
  std::sort(positions_.begin(), positions_.end());
  order_.resize(chunks_.size());
  for (std::size_t k = 0; k < chunks_.size(); ++k)
    order_[k] = k;
  std::stable_sort(order_.begin(), order_.end(),
                   [this](std::size_t a, std::size_t b) { return chunks_[a].start < chunks_[b].start; });
  // How many chunks hold one time between them at most (each is read whole and kept while a
  // message of it is still to come).
  std::vector<std::pair<ros::Time, int>> edges;  // +1 at a start, -1 after an end
  for (const ChunkInfo& c : chunks_)
  {
    edges.emplace_back(c.start, 1);
    edges.emplace_back(c.end, -1);
  }
  std::sort(edges.begin(), edges.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (a.first == b.first && a.second > b.second);  // starts first: closed
  });
  int open = 0, most = 0;
  for (const auto& edge : edges)
    most = std::max(most, open += edge.second);
  usable_ = !encrypted && most <= kMaxOpenChunks;
}

void BagReader::select(const std::vector<std::uint32_t>& ids)
{
  selected_ = ids;
  std::sort(selected_.begin(), selected_.end());
  next_chunk_ = 0;
  for (std::unique_ptr<Cursor>& cursor : open_)
    spare_.push_back(std::move(cursor));
  open_.clear();
  skipUnselected();
}

void BagReader::skipUnselected()
{
  while (next_chunk_ < order_.size() &&
         std::none_of(chunks_[order_[next_chunk_]].connections.begin(), chunks_[order_[next_chunk_]].connections.end(),
                      [this](std::uint32_t id) { return std::binary_search(selected_.begin(), selected_.end(), id); }))
    ++next_chunk_;
}

bool BagReader::next(std::vector<Message>* messages)
{
  messages->clear();
  if (!usable_)
    return false;
  // Chunks all of whose messages were given in the last call: their buffers serve again.
  for (auto cursor = open_.begin(); cursor != open_.end();)
  {
    if ((*cursor)->next == (*cursor)->messages.size())
    {
      spare_.push_back(std::move(*cursor));
      cursor = open_.erase(cursor);
    }
    else
      ++cursor;
  }
  while (true)
  {
    // The earliest message of the open chunks; of equal times, the one of the chunk whose info
    // record comes first (as rosbag orders a connection's messages), then its place in the chunk.
    Cursor* first = nullptr;
    for (const std::unique_ptr<Cursor>& cursor : open_)
    {
      if (cursor->next == cursor->messages.size())
        continue;
      const ros::Time& time = cursor->messages[cursor->next].time;
      if (!first || time < first->messages[first->next].time ||
          (time == first->messages[first->next].time && cursor->chunk < first->chunk))
        first = cursor.get();
    }
    // A chunk that starts no later than that message may hold an earlier one, or one of the same
    // time that comes first: it is opened first.
    if (next_chunk_ < order_.size() &&
        (!first || chunks_[order_[next_chunk_]].start <= first->messages[first->next].time))
    {
      openChunk(order_[next_chunk_++]);
      skipUnselected();
      continue;
    }
    if (!first)
      return !messages->empty();  // every chunk read
    messages->push_back(first->messages[first->next++]);
    // A chunk's worth at a time: the buffers of a chunk given whole are released at the next call.
    if (first->next == first->messages.size())
      return true;
  }
}

void BagReader::openChunk(std::size_t k)
{
  const ChunkInfo& chunk = chunks_[k];
  std::unique_ptr<Cursor> cursor;
  if (spare_.empty())
    cursor = std::make_unique<Cursor>();
  else
  {
    cursor = std::move(spare_.back());
    spare_.pop_back();
  }
  cursor->messages.clear();
  cursor->next = 0;
  std::string& record = cursor->record;
  std::string& plain = cursor->plain;
  // The chunk record's header, then its data and the index records after it (up to the next
  // chunk, or the index) in one read.
  readAt(chunk.position, 4, &header_);
  readAt(chunk.position + 4, std::size_t{ u32(header_.data()) } + 4, &header_);
  const std::string_view header = std::string_view(header_).substr(0, header_.size() - 4);
  if (opOf(header, chunk.position) != kOpChunk)
    throw BagFormatError("chunk info points" + at(chunk.position) + ", where no chunk starts");
  std::string compression;
  forEachField(header, chunk.position, [&compression](std::string_view name, std::string_view value) {
    if (name == "compression")
      compression.assign(value);
  });
  const std::uint32_t declared = u32(fixedField(header, chunk.position, "size", 4).data());
  const std::uint64_t data_position = chunk.position + 4 + header_.size();
  const std::uint32_t data_length = u32(header_.data() + header_.size() - 4);
  const auto later = std::upper_bound(positions_.begin(), positions_.end(), chunk.position);
  const std::uint64_t region_end = later != positions_.end() ? *later : index_position_;
  if (data_position > region_end || data_length > region_end - data_position)
    throw BagFormatError("chunk" + at(chunk.position) + " runs into the record after it");
  readAt(data_position, region_end - data_position, &record);
  std::string_view data = std::string_view(record).substr(0, data_length);
  if (compression != "none")
  {
    if (compression != "lz4" && compression != "bz2")
      throw BagFormatError("chunk" + at(chunk.position) + " has unknown compression '" + compression + "'");
    const std::string why = decompressChunk(compression, data, declared, chunk.position, &plain);
    if (!why.empty())
      throw BagFormatError(why);
    data = plain;
  }
  // One index record per connection of the chunk follows it (what rosbag reads at open).
  entries_.clear();
  const std::string_view after = std::string_view(record).substr(data_length);
  std::size_t offset = 0;
  for (std::size_t i = 0; i < chunk.connections.size(); ++i)
  {
    const std::uint64_t where = data_position + data_length + offset;
    const Record index = recordAt(after, offset, data_position + data_length);
    offset = index.end;
    if (opOf(index.header, where) != kOpIndexData || u32(fixedField(index.header, where, "ver", 4).data()) != 1)
      throw BagFormatError("record" + at(where) + " is not the version 1 index record its chunk info announces");
    const std::uint32_t connection = u32(fixedField(index.header, where, "conn", 4).data());
    const std::uint32_t count = u32(fixedField(index.header, where, "count", 4).data());
    if (index.data.size() != 12ULL * count)
      throw BagFormatError("index record" + at(where) + " holds " + std::to_string(index.data.size()) + " bytes for " +
                           std::to_string(count) + " entries");
    if (!std::binary_search(selected_.begin(), selected_.end(), connection))
      continue;
    for (std::uint32_t e = 0; e < count; ++e)
    {
      const char* entry = index.data.data() + 12 * e;
      entries_.push_back(Entry{ timeAt(entry), u32(entry + 8), connection });
    }
  }
  // By time, ties in file order (the order of each connection's own entries is kept).
  const auto earlier = [](const Entry& a, const Entry& b) {
    return a.time < b.time || (a.time == b.time && a.offset < b.offset);
  };
  if (!std::is_sorted(entries_.begin(), entries_.end(), earlier))
    std::stable_sort(entries_.begin(), entries_.end(), earlier);
  for (const Entry& entry : entries_)
  {
    const std::uint64_t where = data_position;  // the chunk's data (offsets count in it uncompressed)
    const Record message = recordAt(data, entry.offset, where);
    if (opOf(message.header, where + entry.offset) != kOpMessage)
      throw BagFormatError("index entry of connection " + std::to_string(entry.connection) + " points at offset " +
                           std::to_string(entry.offset) + " of the chunk" + at(chunk.position) +
                           ", where no message starts");
    cursor->messages.push_back(Message{ entry.connection, entry.time,
                                        reinterpret_cast<const std::uint8_t*>(message.data.data()),
                                        static_cast<std::uint32_t>(message.data.size()) });
  }
  cursor->chunk = k;
  open_.push_back(std::move(cursor));
}
}  // namespace periodic_bias_compensation
