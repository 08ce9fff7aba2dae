// Corpus replay: runs one fuzz harness (linked in) over every file of its committed corpus,
// as a gtest in the ordinary build (g++, and ASan+UBSan with PBC_SANITIZE=ON). Keeps every input
// that once found a bug, and the seeds, as a regression test without clang or libFuzzer.
// PBC_FUZZ_CORPUS is the corpus directory of the harness. Files named on the command line are
// replayed instead (e.g. `test_fuzz_corpus_compensator test/fuzz/findings/F5-...`).
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace
{
std::vector<std::filesystem::path> g_files;  ///< from the command line; empty: the corpus
}

TEST(FuzzCorpus, EveryInputRunsClean)
{
  namespace fs = std::filesystem;
  std::vector<fs::path> files = g_files;
  for (const auto& entry : fs::directory_iterator(PBC_FUZZ_CORPUS))
  {
    if (g_files.empty() && entry.is_regular_file())
    {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty()) << "empty corpus " << PBC_FUZZ_CORPUS;
  for (const auto& file : files)
  {
    SCOPED_TRACE(file.string());
    std::ifstream in(file, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    // A failure aborts the process (the harnesses' pbc_fuzz::fail): the test then has no result,
    // which catkin_test_results reports as a failure.
    std::fprintf(stderr, "replaying %s (%zu bytes)\n", file.filename().c_str(), bytes.size());
    EXPECT_EQ(LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0);
  }
  std::printf("[fuzz corpus] %zu inputs from %s replayed\n", files.size(), PBC_FUZZ_CORPUS);
}

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  g_files.assign(argv + 1, argv + argc);
  return RUN_ALL_TESTS();
}
