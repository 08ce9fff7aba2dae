// Checks of a bag file before rosbag reads it, and the messages that name it when it cannot be
// read; shared by compensate_bag and diagnose_gap. No NodeHandle, no master needed.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace periodic_bias_compensation
{
/// Walks the record structure of a bag (format 2.0) before rosbag reads it: every field of
/// every record header that is present must lie inside its header, also for the records inside
/// uncompressed chunks, and every index entry must point at a message of its connection in the
/// chunk before it (compressed chunks are decompressed first, as rosbag will). rosbag
/// (ros::Header::parse, Bag::readHeaderFromBuffer) trusts those lengths and offsets and reads
/// past its buffer on a corrupt one (found by test/fuzz/fuzz_bag.cpp; docs/reliability.md F7,
/// F10). A record cut off by the end of the file (a bag that ends mid-chunk) is reported here
/// too: rosbag would first allocate the length it claims.
/// @return an empty string, or what is wrong and where
std::string checkBagStructure(const std::string& path);

/// Why the bag at `path` cannot be read, in a sentence that names it ("input bag 'x.bag' does
/// not exist", "... is empty", corruptBagMessage() for a broken structure), or "" when it can.
/// Reads the whole file once (checkBagStructure).
std::string bagFileProblem(const std::string& path);

/// bagFileProblem without reading the chunks' contents: what rosbag::Bag::open reads (the file
/// header, connection and chunk info records, chunk headers and index records) is checked as
/// bagFileProblem checks it, index entries only against their chunk's size. Enough for rosbag to
/// open the bag, not to read its messages; quick (it skips over the chunks). Whatever it finds,
/// bagFileProblem finds too.
std::string bagOpenProblem(const std::string& path);

/// A compressed chunk's data (`compression`: "lz4" or "bz2") decompressed into *plain by the
/// libraries rosbag uses. `declared`: the chunk header's uncompressed size, refused above 1000 x
/// the compressed size + 1 MiB (it is allocated first); `where`: the chunk's place in the file.
/// @return an empty string, or what is wrong and where
std::string decompressChunk(const std::string& compression, std::string_view data, std::uint64_t declared,
                            std::uint64_t where, std::string* plain);

/// "input bag 'PATH' is truncated or corrupt (WHAT); a bag cut off while recording has no
/// index: 'rosbag reindex PATH' recovers the messages written before the cut." WHAT: what the
/// structure check or rosbag said.
std::string corruptBagMessage(const std::string& path, const std::string& what);
}  // namespace periodic_bias_compensation
