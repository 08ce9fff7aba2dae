// The rosbag 2.0 format's constants (rosbag/constants.h) and little-endian reads, shared by the
// bag check, reader and writer (internal to the ROS wrapper library).
#pragma once

#include <cstdint>
#include <string_view>

namespace periodic_bias_compensation::bag_format
{
/// The first line of every 2.0 bag.
constexpr std::string_view kMagic = "#ROSBAG V2.0\n";

/// Record types (a record header's "op" field).
constexpr char kOpMessage = 0x02, kOpFileHeader = 0x03, kOpIndexData = 0x04, kOpChunk = 0x05, kOpChunkInfo = 0x06,
               kOpConnection = 0x07;

/// Little-endian u32 at p.
inline std::uint32_t u32(const char* p)
{
  return static_cast<std::uint32_t>(static_cast<unsigned char>(p[0])) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(p[1])) << 8) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(p[2])) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(p[3])) << 24);
}

/// Little-endian u64 at p.
inline std::uint64_t u64(const char* p)
{
  return static_cast<std::uint64_t>(u32(p)) | (static_cast<std::uint64_t>(u32(p + 4)) << 32);
}
}  // namespace periodic_bias_compensation::bag_format
