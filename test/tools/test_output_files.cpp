// The tools' output files (tools/output_file.h): the helper itself, then every tool that writes
// files run as a program. An output that is one of the inputs is refused (exit 2) and the input
// stays byte for byte; SIGINT or SIGTERM mid-run leaves neither the output nor a temporary; an
// output in a directory that cannot be written is named as the output that cannot be written.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "../common/shell.h"
#include "periodic_bias_compensation/tools/command_line.h"
#include "periodic_bias_compensation/tools/output_file.h"

namespace fs = std::filesystem;
using pbc_test::CommandResult;
using pbc_test::shell;
using periodic_bias_compensation::NamedPath;
using periodic_bias_compensation::OutputFile;
using periodic_bias_compensation::refuseOverwritingInputs;
using periodic_bias_compensation::UsageError;

namespace
{
std::string readAll(const std::string& path)
{
  std::ifstream file(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

bool exists(const std::string& path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

/// The message of the exception `f` throws ("" if none).
template <class Exception, class F>
std::string thrown(F f)
{
  try
  {
    f();
  }
  catch (const Exception& e)
  {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

class OutputFiles : public testing::Test
{
protected:
  void SetUp() override
  {
    char pattern[] = "/tmp/output_files_test.XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    dir_ = pattern;
    scenario_ = dir_ + "/scenario.yaml";
    fs::copy_file(std::string(PBC_SOURCE_DIR) + "/config/scenarios/paper_bench.yaml", scenario_);
  }
  void TearDown() override
  {
    fs::permissions(dir_ + "/readonly", fs::perms::owner_all, fs::perm_options::add, ec_);
    fs::remove_all(dir_, ec_);
  }
  std::string write(const std::string& name, const std::string& contents)
  {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }
  /// Files of the scratch directory (recursively) that are temporaries of an output.
  std::vector<std::string> temporaries() const
  {
    std::vector<std::string> found;
    for (const auto& entry : fs::recursive_directory_iterator(dir_))
    {
      const std::string name = entry.path().filename().string();
      if (contains(name, ".partial-") || contains(name, ".write-check-"))
        found.push_back(entry.path().string());
    }
    return found;
  }
  /// A 5 s bag of the bench scenario.
  std::string tinyBag()
  {
    const std::string bag = dir_ + "/tiny.bag";
    const CommandResult r =
        shell(std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario_ + " --duration 5 --out " + bag);
    EXPECT_EQ(r.status, 0) << r.output;
    return bag;
  }
  /// A directory in which no file can be created, also by root ("" if there is none here).
  std::string unwritableDirectory()
  {
    const std::string own = dir_ + "/readonly";
    fs::create_directory(own);
    fs::permissions(own, fs::perms::owner_read | fs::perms::owner_exec);
    for (const std::string& candidate : { own, std::string("/sys"), std::string("/proc/sys") })
    {
      const std::string probe = candidate + "/output_files_test_probe";
      const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0644);
      if (fd < 0 && fs::is_directory(candidate))
        return candidate;
      if (fd >= 0)
      {
        ::close(fd);
        ::unlink(probe.c_str());
      }
    }
    return "";
  }

  std::string dir_;
  std::string scenario_;
  std::error_code ec_;
};
}  // namespace

TEST_F(OutputFiles, CommitRenamesTheCompleteFile)
{
  const std::string path = dir_ + "/out.txt";
  {
    OutputFile file(path);
    EXPECT_TRUE(exists(file.temporary())) << "the temporary is created at once";
    EXPECT_FALSE(exists(path));
    std::ofstream(file.temporary()) << "streamed";
    file.commit();
  }
  EXPECT_EQ(readAll(path), "streamed");
  periodic_bias_compensation::writeOutputFile(path, "whole");
  EXPECT_EQ(readAll(path), "whole");

  // Through a symbolic link: the file it names gets the contents, the link stays a link.
  const std::string link = dir_ + "/link.txt";
  ASSERT_EQ(::symlink(path.c_str(), link.c_str()), 0);
  periodic_bias_compensation::writeOutputFile(link, "through the link");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(readAll(path), "through the link");
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputFiles, WithoutCommitTheTemporaryGoesAndAnOldFileStays)
{
  const std::string path = write("out.txt", "old");
  std::string temporary;
  try
  {
    OutputFile file(path);
    temporary = file.temporary();
    std::ofstream(file.temporary()) << "half";
    throw std::runtime_error("failed mid-way");
  }
  catch (const std::runtime_error&)
  {
  }
  EXPECT_FALSE(temporary.empty());
  EXPECT_FALSE(exists(temporary));
  EXPECT_EQ(readAll(path), "old");
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputFiles, ADeviceIsWrittenAsItIs)
{
  {
    OutputFile file("/dev/null");
    EXPECT_EQ(file.temporary(), "/dev/null");
    file.commit("discarded");
  }
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  const CommandResult r = shell(std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario_ +
                                " --duration 1 --csv /dev/stdout 2>/dev/null | head -c 100000 | grep -c ^index,t,");
  EXPECT_EQ(r.output, "1\n") << "no CSV on stdout";
  // /dev/stdout sent to a file: the file gets the CSV, /dev/stdout stays what it was.
  const bool stdout_was_link = fs::is_symlink("/dev/stdout");
  const CommandResult redirected = shell(std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario_ +
                                         " --duration 1 --csv /dev/stdout > " + dir_ + "/stdout.csv");
  EXPECT_EQ(redirected.status, 0) << redirected.output;
  EXPECT_EQ(readAll(dir_ + "/stdout.csv").rfind("index,t,", 0), 0u);
  EXPECT_EQ(fs::is_symlink("/dev/stdout"), stdout_was_link);
  EXPECT_TRUE(fs::is_character_file("/dev/null"));
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputFiles, AnOutputThatIsAnInputIsACommandLineError)
{
  const std::string in = write("in.yaml", "x: 1\n");
  ASSERT_EQ(::symlink(in.c_str(), (dir_ + "/symlink.yaml").c_str()), 0);
  ASSERT_EQ(::link(in.c_str(), (dir_ + "/hardlink.yaml").c_str()), 0);
  const std::string base = fs::path(dir_).filename().string();
  for (const std::string& same :
       { in, dir_ + "/./in.yaml", dir_ + "/../" + base + "/in.yaml", dir_ + "/symlink.yaml", dir_ + "/hardlink.yaml" })
  {
    const std::string message = thrown<UsageError>([&] {
      refuseOverwritingInputs({ { "--scenario", in } }, { { "--out", same } });
    });
    EXPECT_TRUE(contains(message, "--out '" + same + "' is the same file as --scenario '" + in + "'")) << message;
  }
  EXPECT_EQ(thrown<UsageError>([&] {
              refuseOverwritingInputs({ { "--scenario", in } }, { { "--out", dir_ + "/o" } });
            }),
            "");
  EXPECT_EQ(thrown<UsageError>([&] {
              refuseOverwritingInputs({ { "--params", "" } }, { { "--out", dir_ + "/o" } });
            }),
            "");
  const std::string both = thrown<UsageError>([&] {
    refuseOverwritingInputs({}, { { "--md", dir_ + "/r" }, { "--json", dir_ + "/./r" } });
  });
  EXPECT_TRUE(contains(both, "--json") && contains(both, "--md")) << both;
  EXPECT_EQ(readAll(in), "x: 1\n");
}

TEST_F(OutputFiles, AnOutputThatCannotBeWrittenIsNamed)
{
  const std::string missing = dir_ + "/no_such_dir/out.bag";
  EXPECT_EQ(thrown<std::runtime_error>([&] { OutputFile file(missing); }),
            "cannot write output '" + missing + "': directory '" + dir_ + "/no_such_dir' does not exist");
  EXPECT_EQ(thrown<std::runtime_error>([&] { OutputFile file(dir_); }),
            "cannot write output '" + dir_ + "': it is a directory");
  const std::string unwritable = unwritableDirectory();
  if (unwritable.empty())
  {
    GTEST_SKIP() << "no directory here refuses new files";
  }
  const std::string message = thrown<std::runtime_error>([&] { OutputFile file(unwritable + "/out.bag"); });
  EXPECT_TRUE(contains(message, "cannot write output '" + unwritable + "/out.bag': ")) << message;
  const std::string dir_message =
      thrown<std::runtime_error>([&] { periodic_bias_compensation::prepareOutputDirectory(unwritable); });
  EXPECT_TRUE(contains(dir_message, "cannot write output directory '" + unwritable + "'")) << dir_message;
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputFiles, ToolsRefuseToWriteOverAnInput)
{
  const std::string scenario = readAll(scenario_);
  const std::string sim = PBC_SIMULATE_IMU;
  const std::string params = write("params.yaml", "mode: paper\n");
  const std::string bag = tinyBag();
  struct Case
  {
    std::string command, input, option;
  };
  const std::vector<Case> cases = {
    { sim + " --scenario " + scenario_ + " --out " + scenario_, scenario_, "--out" },
    { sim + " --scenario " + scenario_ + " --duration 1 --csv " + dir_ + "/./scenario.yaml", scenario_, "--csv" },
    { std::string(PBC_COMPENSATE_BAG) + " --in " + bag + " --out " + dir_ + "/o.bag --params " + params +
          " --tune-gains " + params,
      params, "--tune-gains" },
    { std::string(PBC_DIAGNOSE_GAP) + " --real " + bag + " --sim " + dir_ + "/fitted_scenario.yaml --out " + dir_,
      dir_ + "/fitted_scenario.yaml", "--out" },
    { std::string(PBC_EVALUATE_COMPENSATOR) + " --scenario " + scenario_ + " --markdown " + scenario_, scenario_,
      "--markdown" },
  };
  fs::copy_file(scenario_, dir_ + "/fitted_scenario.yaml");
  for (const Case& c : cases)
  {
    const std::string before = readAll(c.input);
    const CommandResult r = shell(c.command);
    EXPECT_EQ(r.status, 2) << c.command << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, c.option + " '") && contains(r.output, "is the same file as")) << c.command << "\n"
                                                                                                  << r.output;
    EXPECT_EQ(readAll(c.input), before) << c.input << " changed by " << c.command;
  }
  const CommandResult r =
      shell(std::string(PBC_VALIDATE_GAP) + " --small --md " + dir_ + "/r.md --json " + dir_ + "/r.md");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_TRUE(contains(r.output, "--json '")) << r.output;
  EXPECT_FALSE(exists(dir_ + "/o.bag"));
  EXPECT_TRUE(temporaries().empty());
}

TEST_F(OutputFiles, SignalMidRunLeavesNeitherOutputNorTemporary)
{
  const std::string bag = dir_ + "/long.bag", csv = dir_ + "/long.csv";
  for (const int signal_number : { SIGINT, SIGTERM })
  {
    // An hour of the bench scenario: seconds of work, ended when its temporaries have data.
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0)
    {
      ::signal(SIGINT, SIG_DFL);  // as from a terminal, even if this test runs with SIGINT ignored
      ::signal(SIGTERM, SIG_DFL);
      ::execl(PBC_SIMULATE_IMU, PBC_SIMULATE_IMU, "--scenario", scenario_.c_str(), "--duration", "3600", "--out",
              bag.c_str(), "--csv", csv.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    const std::string temporary = bag + ".partial-" + std::to_string(pid);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    std::error_code ec;
    while (!(fs::file_size(temporary, ec) > 100000 && !ec) && std::chrono::steady_clock::now() < deadline)
    {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    EXPECT_TRUE(exists(temporary)) << "simulate_imu never wrote " << temporary;
    ::kill(pid, signal_number);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number)
        << "simulate_imu did not end by signal " << signal_number << " (status " << status << ")";
    EXPECT_FALSE(exists(bag));
    EXPECT_FALSE(exists(csv));
    const std::vector<std::string> left = temporaries();
    EXPECT_TRUE(left.empty()) << "left behind: " << (left.empty() ? "" : left.front());
  }
}

TEST_F(OutputFiles, AnUnwritableDirectoryIsBlamedOnTheOutput)
{
  const std::string bag = tinyBag();
  const std::string d = unwritableDirectory();
  if (d.empty())
  {
    GTEST_SKIP() << "no directory here refuses new files";
  }
  struct Case
  {
    std::string command, named;
  };
  const std::vector<Case> cases = {
    { std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario_ + " --out " + d + "/x.bag",
      "cannot write output '" + d + "/x.bag'" },
    { std::string(PBC_SIMULATE_IMU) + " --scenario " + scenario_ + " --csv " + d + "/x.csv",
      "cannot write output '" + d + "/x.csv'" },
    { std::string(PBC_COMPENSATE_BAG) + " --in " + bag + " --out " + d + "/x.bag",
      "cannot write output '" + d + "/x.bag'" },
    { std::string(PBC_COMPENSATE_BAG) + " --in " + bag + " --out " + dir_ + "/ok.bag --tune-gains " + d + "/g.yaml",
      "cannot write output '" + d + "/g.yaml'" },
    { std::string(PBC_DIAGNOSE_GAP) + " --real " + bag + " --sim " + scenario_ + " --out " + d,
      "cannot write output directory '" + d + "'" },
    { std::string(PBC_EVALUATE_COMPENSATOR) + " --scenario " + scenario_ + " --csv " + d + "/x.csv",
      "cannot write output '" + d + "/x.csv'" },
    { std::string(PBC_VALIDATE_GAP) + " --small --json " + d + "/x.json", "cannot write output '" + d + "/x.json'" },
  };
  for (const Case& c : cases)
  {
    const auto start = std::chrono::steady_clock::now();
    const CommandResult r = shell(c.command);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.status, 1) << c.command << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, c.named)) << c.command << "\n" << r.output;
    EXPECT_FALSE(contains(r.output, "corrupt") || contains(r.output, "reindex")) << c.command << "\n" << r.output;
    EXPECT_LT(seconds, 5.0) << "said only after the work: " << c.command;
  }
  EXPECT_FALSE(exists(dir_ + "/ok.bag"));
  EXPECT_TRUE(temporaries().empty());
}
