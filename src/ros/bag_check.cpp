#include "periodic_bias_compensation/ros/bag_check.h"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include <bzlib.h>
#include <roslz4/lz4s.h>

#include "bag_format.h"

namespace periodic_bias_compensation
{
namespace
{
using namespace bag_format;

/// The fields of a record header that the structure check uses (raw values; empty if absent).
struct RecordFields
{
  std::string op, compression, conn, count, ver, size;
  std::string index_pos, conn_count, chunk_count, chunk_pos;  ///< file header, chunk info
};

/// Little-endian u64 of an 8-byte field, or nothing.
std::optional<std::uint64_t> u64(const std::string& field)
{
  if (field.size() != 8)
  {
    return std::nullopt;
  }
  return bag_format::u64(field.data());
}

/// Where rosbag goes by offsets it reads from the file: the file header's index_pos must be the
/// start of conn_count connection records followed by chunk_count chunk info records (read at
/// open), and each chunk info's chunk_pos the start of a chunk record (read when iterating).
/// `records`: offset and op of every top-level record, in file order.
std::string checkOffsets(const RecordFields& file_header, const std::vector<std::pair<std::uint64_t, char>>& records,
                         const std::vector<std::pair<std::uint64_t, std::uint64_t>>& chunk_positions)
{
  const std::optional<std::uint64_t> index_pos = u64(file_header.index_pos);
  if (!index_pos || *index_pos == 0)
  {
    return std::string();  // no index: rosbag refuses the bag itself ("unindexed")
  }
  const auto start = std::find_if(records.begin(), records.end(), [&](const auto& r) { return r.first == *index_pos; });
  if (start == records.end())
  {
    return "the file header's index position " + std::to_string(*index_pos) + " is not the start of a record";
  }
  const std::uint32_t connections = file_header.conn_count.size() == 4 ? u32(file_header.conn_count.data()) : 0;
  const std::uint32_t chunks = file_header.chunk_count.size() == 4 ? u32(file_header.chunk_count.data()) : 0;
  auto next = start;
  for (std::uint64_t k = 0; k < std::uint64_t{ connections } + chunks; ++k, ++next)
  {
    const char expected = k < connections ? kOpConnection : kOpChunkInfo;
    if (next == records.end() || next->second != expected)
    {
      return "the file header announces " + std::to_string(connections) + " connection and " + std::to_string(chunks) +
             " chunk info records at byte " + std::to_string(*index_pos) + ", which the file does not hold";
    }
  }
  for (const auto& chunk_info : chunk_positions)
  {
    const std::uint64_t chunk_pos = chunk_info.second;
    if (std::none_of(records.begin(), records.end(),
                     [&](const auto& r) { return r.first == chunk_pos && r.second == kOpChunk; }))
    {
      return "chunk info record at byte " + std::to_string(chunk_info.first) + " points at byte " +
             std::to_string(chunk_pos) + ", where no chunk starts";
    }
  }
  return std::string();
}

/// Checks that every field of a record header lies inside it and picks out RecordFields.
/// @return an empty string, or what is wrong
std::string checkHeader(std::string_view header, std::uint64_t where, RecordFields* fields)
{
  std::size_t offset = 0;
  while (offset < header.size())
  {
    if (header.size() - offset < 4)
    {
      return "record header at byte " + std::to_string(where) + " ends inside a field length";
    }
    const std::uint32_t length = u32(header.data() + offset);
    offset += 4;
    if (length > header.size() - offset)
    {
      return "record header at byte " + std::to_string(where) + " has a field of " + std::to_string(length) +
             " bytes in a header of " + std::to_string(header.size());
    }
    const std::string_view field = header.substr(offset, length);
    offset += length;
    const std::size_t equals = field.find('=');
    const std::string_view name = field.substr(0, equals),
                           value = equals == std::string_view::npos ? std::string_view() : field.substr(equals + 1);
    for (auto [key, target] : { std::pair{ std::string_view("op"), &fields->op },
                                { "compression", &fields->compression },
                                { "conn", &fields->conn },
                                { "count", &fields->count },
                                { "ver", &fields->ver },
                                { "size", &fields->size },
                                { "index_pos", &fields->index_pos },
                                { "conn_count", &fields->conn_count },
                                { "chunk_count", &fields->chunk_count },
                                { "chunk_pos", &fields->chunk_pos } })
    {
      if (name == key)
      {
        target->assign(value);
      }
    }
  }
  return std::string();
}

/// One record at `offset` of `data` (a chunk read into memory): header and data inside `data`.
/// On success sets *fields, *data_begin, *next (offset of the following record).
std::string checkRecord(const std::string& data, std::size_t offset, std::uint64_t base, RecordFields* fields,
                        std::size_t* data_begin, std::size_t* next)
{
  const std::uint32_t header_length = u32(data.data() + offset);
  if (header_length > data.size() - offset - 4)
  {
    return "record at byte " + std::to_string(base + offset) + " inside a chunk runs past the chunk";
  }
  const std::string why = checkHeader(std::string_view(data).substr(offset + 4, header_length), base + offset, fields);
  if (!why.empty())
  {
    return why;
  }
  std::size_t position = offset + 4 + header_length;
  if (data.size() - position < 4)
  {
    return "record at byte " + std::to_string(base + position) + " inside a chunk has no data length";
  }
  const std::uint32_t data_length = u32(data.data() + position);
  position += 4;
  if (data_length > data.size() - position)
  {
    return "record data at byte " + std::to_string(base + position) + " inside a chunk runs past the chunk";
  }
  *data_begin = position;
  *next = position + data_length;
  return std::string();
}

/// What the index records after a chunk may point at.
struct ChunkLayout
{
  bool present = false;
  bool walked = false;  ///< records walked (decompressed first if need be): every record start is known
  std::uint64_t uncompressed_size = 0;
  std::vector<std::pair<std::uint32_t, std::string>> messages;  ///< offset of each message record (rising), its conn
};

/// The records of an uncompressed chunk; connection records' data is a header too.
std::string walkChunk(const std::string& data, std::uint64_t base, ChunkLayout* layout)
{
  std::size_t offset = 0;
  while (data.size() - offset >= 4)
  {
    RecordFields fields;
    std::size_t data_begin = 0, next = 0;
    std::string why = checkRecord(data, offset, base, &fields, &data_begin, &next);
    if (why.empty() && fields.op == std::string(1, kOpConnection))
    {
      RecordFields unused;
      why = checkHeader(std::string_view(data).substr(data_begin, next - data_begin), base + data_begin, &unused);
    }
    if (!why.empty())
    {
      return why;
    }
    if (fields.op == std::string(1, kOpMessage))
    {
      layout->messages.emplace_back(static_cast<std::uint32_t>(offset), fields.conn);
    }
    offset = next;
  }
  return offset == data.size() ? std::string() : "chunk ends inside a record length";
}

/// An index data record (version 1: count entries of time and offset into the chunk before it).
/// rosbag reads a message at each offset without checking it (readHeaderFromBuffer; finding F10).
std::string checkIndex(const RecordFields& fields, const std::string& data, std::uint64_t where,
                       const ChunkLayout& chunk)
{
  const std::string at = "index record at byte " + std::to_string(where);
  if (fields.ver.size() != 4 || u32(fields.ver.data()) != 1 || fields.count.size() != 4 || fields.conn.size() != 4)
  {
    return at + " is not a version 1 index with a count and a connection";
  }
  const std::uint64_t count = u32(fields.count.data());
  if (data.size() != 12 * count)
  {
    return at + " holds " + std::to_string(data.size()) + " bytes for " + std::to_string(count) + " entries";
  }
  if (!chunk.present)
  {
    return at + " follows no chunk";
  }
  for (std::uint64_t i = 0; i < count; ++i)
  {
    const std::uint32_t offset = u32(data.data() + 12 * i + 8);
    const auto message = std::lower_bound(chunk.messages.begin(), chunk.messages.end(), offset,
                                          [](const auto& m, std::uint32_t o) { return m.first < o; });
    const bool points_at_message =
        chunk.walked ? message != chunk.messages.end() && message->first == offset && message->second == fields.conn
                     : offset + 8ULL <= chunk.uncompressed_size;
    if (!points_at_message)
    {
      return at + ": entry " + std::to_string(i) + " points at offset " + std::to_string(offset) +
             (chunk.walked ? ", where the chunk has no message of that connection"
                           : ", beyond the chunk's " + std::to_string(chunk.uncompressed_size) + " bytes");
    }
  }
  return std::string();
}

/// checkBagStructure; without `read_chunks`, the chunks' contents are skipped (not walked, not
/// decompressed; index entries only checked against the chunk's size).
std::string checkStructure(const std::string& path, bool read_chunks)
{
  std::ifstream file(path, std::ios::binary);
  const std::string kMagic(bag_format::kMagic);
  std::string magic(kMagic.size(), '\0');
  if (!file.read(&magic[0], static_cast<std::streamsize>(magic.size())) || magic != kMagic)
  {
    // Only format 2.0 (every rosbag since 2010): rosbag's 1.2 reader and its handling of a
    // garbled version line parse records unchecked (fuzz_bag found out-of-bounds reads in both).
    std::string shown;
    for (char c : magic)
    {
      shown += (c >= 32 && c < 127) ? c : '?';
    }
    return "the file does not start with '#ROSBAG V2.0' (it starts with '" + shown + "')";
  }
  file.seekg(0, std::ios::end);
  const std::uint64_t size = static_cast<std::uint64_t>(file.tellg());
  std::uint64_t position = kMagic.size();
  ChunkLayout chunk;
  RecordFields file_header;
  std::vector<std::pair<std::uint64_t, char>> records;                   // offset, op
  std::vector<std::pair<std::uint64_t, std::uint64_t>> chunk_positions;  // chunk info offset, chunk_pos
  char length[4];
  while (position + 4 <= size)
  {
    file.seekg(static_cast<std::streamoff>(position));
    file.read(length, 4);
    const std::uint32_t header_length = u32(length);
    if (header_length > size - position - 4)
    {
      // Cut off (or a corrupt length). Said here: rosbag would first allocate the length the
      // record claims (up to 4 GB) before finding that the file ends.
      return "record at byte " + std::to_string(position) + " declares a " + std::to_string(header_length) +
             "-byte header but the file ends " + std::to_string(size - position - 4) + " bytes later";
    }
    std::string header(header_length, '\0');
    file.read(&header[0], header_length);
    RecordFields fields;
    std::string why = checkHeader(header, position, &fields);
    if (!why.empty())
    {
      return why;
    }
    const std::uint64_t record = position;
    position += 4 + header_length;
    if (position + 4 > size)
    {
      return "the file ends inside the record before byte " + std::to_string(position + 4);
    }
    file.read(length, 4);
    const std::uint32_t data_length = u32(length);
    position += 4;
    if (data_length > size - position)
    {
      return "record data at byte " + std::to_string(position) + " declares " + std::to_string(data_length) +
             " bytes but the file ends " + std::to_string(size - position) + " bytes later";
    }
    const char op = fields.op.size() == 1 ? fields.op[0] : '\0';
    records.emplace_back(record, op);
    if (op == kOpFileHeader && records.size() == 1)
    {
      file_header = fields;
    }
    else if (op == kOpChunkInfo)
    {
      chunk_positions.emplace_back(record, u64(fields.chunk_pos).value_or(0));
    }
    const bool walk_chunk = read_chunks && op == kOpChunk && fields.compression == "none";
    const bool compressed_chunk =
        read_chunks && op == kOpChunk && (fields.compression == "lz4" || fields.compression == "bz2");
    std::string data;
    if (op == kOpConnection || op == kOpIndexData || walk_chunk || compressed_chunk)
    {
      data.resize(data_length);
      file.read(&data[0], data_length);
    }
    if (op == kOpConnection)
    {
      // A connection record's data is itself a header (topic, type, md5sum, definition).
      RecordFields unused;
      why = checkHeader(data, position, &unused);
    }
    else if (op == kOpChunk)
    {
      chunk = ChunkLayout();
      chunk.present = true;
      chunk.walked = walk_chunk;
      // An uncompressed chunk's records are its data, whatever its size field says (rosbag reads
      // the data length): without reading them, index entries are bounded by the same bytes that
      // the whole-file check walks.
      chunk.uncompressed_size = fields.compression == "none" ? data_length
                                : fields.size.size() == 4    ? u32(fields.size.data())
                                                             : 0;
      if (walk_chunk)
      {
        why = walkChunk(data, position, &chunk);
      }
      else if (compressed_chunk)
      {
        // Offsets in the messages below are then counted in the decompressed data.
        std::string plain;
        why = decompressChunk(fields.compression, data, chunk.uncompressed_size, record, &plain);
        if (why.empty())
        {
          chunk.walked = true;
          why = walkChunk(plain, position, &chunk);
        }
      }
    }
    else if (op == kOpIndexData)
    {
      why = checkIndex(fields, data, record, chunk);
    }
    if (!why.empty())
    {
      return why;
    }
    position += data_length;
  }
  return checkOffsets(file_header, records, chunk_positions);
}

/// bagFileProblem; `read_chunks` as for checkStructure.
std::string bagProblem(const std::string& path, bool read_chunks)
{
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status))
  {
    return "input bag '" + path + "' does not exist";
  }
  if (!std::filesystem::is_regular_file(status))
  {
    return "input bag '" + path + "' is not a file";
  }
  if (std::filesystem::file_size(path, ec) == 0 && !ec)
  {
    return "input bag '" + path + "' is empty (0 bytes)";
  }
  const std::string structure = checkStructure(path, read_chunks);
  return structure.empty() ? std::string() : corruptBagMessage(path, structure);
}
}  // namespace

std::string checkBagStructure(const std::string& path)
{
  return checkStructure(path, true);
}

std::string decompressChunk(const std::string& compression, std::string_view data, std::uint64_t declared,
                            std::uint64_t where, std::string* plain)
{
  const std::string what = "chunk at byte " + std::to_string(where) + " (" + compression + ")";
  if (declared > 1000 * std::uint64_t{ data.size() } + (1u << 20))
  {
    return what + " declares " + std::to_string(declared) + " uncompressed bytes for " + std::to_string(data.size()) +
           " compressed ones";
  }
  plain->assign(declared, '\0');
  unsigned int produced = static_cast<unsigned int>(declared);
  const bool ok =
      compression == "lz4"
          ? roslz4_buffToBuffDecompress(const_cast<char*>(data.data()), static_cast<unsigned int>(data.size()),
                                        &(*plain)[0], &produced) == ROSLZ4_OK
          : BZ2_bzBuffToBuffDecompress(&(*plain)[0], &produced, const_cast<char*>(data.data()),
                                       static_cast<unsigned int>(data.size()), 0, 0) == BZ_OK;
  if (!ok || produced != declared)
  {
    return what + " does not decompress to the " + std::to_string(declared) + " bytes it declares";
  }
  return std::string();
}

std::string corruptBagMessage(const std::string& path, const std::string& what)
{
  return "input bag '" + path + "' is truncated or corrupt (" + what +
         "); a bag cut off while recording has no index: 'rosbag reindex " + path +
         "' recovers the messages written before the cut.";
}

std::string bagFileProblem(const std::string& path)
{
  return bagProblem(path, true);
}

std::string bagOpenProblem(const std::string& path)
{
  return bagProblem(path, false);
}
}  // namespace periodic_bias_compensation
