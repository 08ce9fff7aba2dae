// Fuzz target: compensate_bag on corrupted and truncated bags, in-process (the tool's own
// compensateBagMain, compiled from src/tools/compensate_bag.cpp). The input bytes are the bag.
// Allowed outcomes: exit status 0 with a complete output bag, or 1 with a message and no
// output file and no temporary file left; the quick structure check before opening
// (bagOpenProblem) never finds what the whole-file check (bagFileProblem) does not. A crash, UB, an uncaught exception (std::terminate)
// or a hang is a finding.
#define PBC_COMPENSATE_BAG_NO_MAIN
#include "../../src/tools/compensate_bag.cpp"

#include <sys/stat.h>

#include <cstdint>
#include <fstream>

#include "fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  static const std::string dir = [] {
    char pattern[] = "/tmp/pbc_fuzz_bag.XXXXXX";
    const char* made = ::mkdtemp(pattern);
    if (made == nullptr)
    {
      pbc_fuzz::fail("mkdtemp failed");
    }
    return std::string(made);
  }();
  const std::string in = dir + "/in.bag";
  const std::string out = dir + "/out.bag";
  {
    std::ofstream file(in, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  std::remove(out.c_str());
  // The quick check before opening is a subset of the whole-file check.
  if (!periodic_bias_compensation::bagOpenProblem(in).empty() && periodic_bias_compensation::bagFileProblem(in).empty())
  {
    pbc_fuzz::fail("bagOpenProblem found a problem that bagFileProblem did not");
  }
  std::string a0 = "compensate_bag", a1 = "--in", a2 = in, a3 = "--out", a4 = out;
  char* argv[] = { a0.data(), a1.data(), a2.data(), a3.data(), a4.data(), nullptr };
  // The tool reports on stderr: scripts/fuzz passes -close_fd_mask=2 (libFuzzer keeps its own
  // and the sanitizers' reports on a duplicate of stderr).
  const int status = compensateBagMain(5, argv);

  struct stat st;
  const bool written = ::stat(out.c_str(), &st) == 0;
  if (status == 0 && !written)
  {
    pbc_fuzz::fail("exit 0 without an output bag");
  }
  if (status != 0 && written)
  {
    pbc_fuzz::fail("failed run left an output bag");
  }
  if (status != 0 && status != 1)
  {
    pbc_fuzz::fail("unexpected exit status " + std::to_string(status));
  }
  std::remove(out.c_str());
  // No temporary file may be left behind.
  const std::string partial = out + ".partial-" + std::to_string(::getpid());
  if (::stat(partial.c_str(), &st) == 0)
  {
    pbc_fuzz::fail("temporary output left behind");
  }
  return 0;
}
