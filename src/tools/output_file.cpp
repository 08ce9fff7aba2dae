#include "periodic_bias_compensation/tools/output_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>

#include "periodic_bias_compensation/tools/command_line.h"

namespace fs = std::filesystem;

namespace periodic_bias_compensation
{
namespace
{
// The temporaries to remove on a signal or at exit, in fixed storage the signal handler can read
// without allocating or locking: a slot's path is only read while its state is kArmed.
constexpr int kSlots = 64;
constexpr std::size_t kMaxPath = 4096;
enum SlotState : int
{
  kFree,
  kFilling,
  kArmed,
};
struct Slot
{
  std::atomic<int> state{ kFree };
  char path[kMaxPath];
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler reads the slots' state");
Slot g_slots[kSlots];

/// Async-signal-safe: only atomic loads and unlink().
void removeArmed()
{
  for (Slot& slot : g_slots)
  {
    if (slot.state.load() == kArmed)
    {
      ::unlink(slot.path);
    }
  }
}

void removeTemporariesOnSignal(int signal_number)
{
  const int saved_errno = errno;
  removeArmed();
  errno = saved_errno;
  // Then the signal ends the process as it would have without this handler (it is blocked
  // while the handler runs and delivered with the default action when it returns).
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

/// Once per process: the handler for the signals that end a tool by default (an ignored signal,
/// e.g. SIGHUP under nohup or SIGINT of a background job, stays ignored), and removal at exit().
void installCleanup()
{
  static std::once_flag once;
  std::call_once(once, [] {
    const int signals[] = { SIGINT, SIGTERM, SIGHUP };
    struct sigaction action = {};
    action.sa_handler = removeTemporariesOnSignal;
    sigemptyset(&action.sa_mask);
    for (const int s : signals)
    {
      sigaddset(&action.sa_mask, s);
    }
    for (const int s : signals)
    {
      struct sigaction old = {};
      if (::sigaction(s, nullptr, &old) == 0 && old.sa_handler == SIG_DFL)
      {
        ::sigaction(s, &action, nullptr);
      }
    }
    std::atexit(removeArmed);
  });
}

/// Registers `path` for removal; returns its slot.
int registerTemporary(const std::string& path)
{
  if (path.size() >= kMaxPath)
  {
    throw std::runtime_error("cannot write output '" + path + "': path too long");
  }
  installCleanup();
  for (int i = 0; i < kSlots; ++i)
  {
    int expected = kFree;
    if (g_slots[i].state.compare_exchange_strong(expected, kFilling))
    {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(kArmed);
      return i;
    }
  }
  throw std::runtime_error("cannot write output '" + path + "': more than " + std::to_string(kSlots) +
                           " output files open at once");
}

/// "cannot write output 'PATH': why", with the directory named when it is the cause.
std::string cannotWrite(const std::string& path, int error)
{
  const fs::path parent = fs::path(path).parent_path();
  const std::string dir = parent.empty() ? std::string(".") : parent.string();
  std::error_code ec;
  const bool no_directory = error == ENOENT && !fs::is_directory(dir, ec);
  const std::string why = no_directory ? "directory '" + dir + "' does not exist"
                                       : std::string(std::strerror(error)) + " (in directory '" + dir + "')";
  return "cannot write output '" + path + "': " + why;
}

/// Creates (or empties) `path`; 0 or the errno of the failure.
int createEmpty(const std::string& path)
{
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0)
  {
    return errno;
  }
  ::close(fd);
  return 0;
}

/// Same path once absolute and normalised with symbolic links resolved, or the same existing file.
bool sameFile(const std::string& a, const std::string& b)
{
  std::error_code ec_a, ec_b, ec;
  const fs::path ca = fs::weakly_canonical(fs::absolute(a), ec_a);
  const fs::path cb = fs::weakly_canonical(fs::absolute(b), ec_b);
  if (!ec_a && !ec_b && ca == cb)
  {
    return true;
  }
  if (fs::absolute(a).lexically_normal() == fs::absolute(b).lexically_normal())
  {
    return true;
  }
  return fs::exists(a, ec) && fs::exists(b, ec) && fs::equivalent(a, b, ec) && !ec;
}
}  // namespace

OutputFile::OutputFile(std::string path) : path_(std::move(path)), target_(path_)
{
  std::error_code ec;
  const fs::file_status status = fs::status(path_, ec);
  if (fs::is_directory(status))
  {
    throw std::runtime_error("cannot write output '" + path_ + "': it is a directory");
  }
  if (fs::exists(status) && !fs::is_regular_file(status))
  {
    // A device or a pipe (/dev/stdout, /dev/null, a FIFO): written as it is, never replaced.
    temporary_ = path_;
    return;
  }
  if (fs::is_symlink(fs::symlink_status(path_, ec)))
  {
    // Through a symbolic link, as a plain write goes: the file it names is replaced, the link stays.
    const fs::path resolved = fs::weakly_canonical(path_, ec);
    target_ = ec ? path_ : resolved.string();
  }
  temporary_ = target_ + ".partial-" + std::to_string(::getpid());
  // Registered before it exists: a signal never leaves it behind.
  const fs::path absolute = fs::absolute(temporary_, ec);
  slot_ = registerTemporary(ec ? temporary_ : absolute.string());
  const int error = createEmpty(temporary_);
  if (error != 0)
  {
    g_slots[slot_].state.store(kFree);
    slot_ = -1;
    throw std::runtime_error(cannotWrite(path_, error));
  }
}

OutputFile::~OutputFile()
{
  if (slot_ >= 0)
  {
    ::unlink(temporary_.c_str());
    g_slots[slot_].state.store(kFree);
  }
}

void OutputFile::commit()
{
  if (temporary_ == target_)
  {
    return;  // a device or a pipe, written directly
  }
  if (slot_ < 0)
  {
    throw std::logic_error("OutputFile::commit: " + path_ + " committed already");
  }
  const int error = ::rename(temporary_.c_str(), target_.c_str()) == 0 ? 0 : errno;
  if (error != 0)
  {
    ::unlink(temporary_.c_str());
  }
  g_slots[slot_].state.store(kFree);
  slot_ = -1;
  if (error != 0)
  {
    throw std::runtime_error(cannotWrite(path_, error));
  }
}

void OutputFile::commit(const std::string& contents)
{
  errno = 0;
  std::ofstream file(temporary_, std::ios::binary | std::ios::trunc);
  file << contents;
  file.close();
  if (!file)
  {
    const int error = errno != 0 ? errno : EIO;
    throw std::runtime_error(cannotWrite(path_, error));
  }
  commit();
}

void writeOutputFile(const std::string& path, const std::string& contents)
{
  OutputFile(path).commit(contents);
}

void refuseOverwritingInputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs)
{
  for (std::size_t i = 0; i < outputs.size(); ++i)
  {
    const NamedPath& out = outputs[i];
    if (out.path.empty())
    {
      continue;
    }
    for (const NamedPath& in : inputs)
    {
      if (!in.path.empty() && sameFile(out.path, in.path))
      {
        throw UsageError(out.option + " '" + out.path + "' is the same file as " + in.option + " '" + in.path +
                         "': the input would be overwritten");
      }
    }
    for (std::size_t j = 0; j < i; ++j)
    {
      if (!outputs[j].path.empty() && sameFile(out.path, outputs[j].path))
      {
        throw UsageError(out.option + " '" + out.path + "' is the same file as " + outputs[j].option + " '" +
                         outputs[j].path + "': two outputs cannot share a file");
      }
    }
  }
}

void prepareOutputDirectory(const std::string& dir)
{
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
  {
    throw std::runtime_error("cannot write output directory '" + dir +
                             "': " + (ec ? ec.message() : std::string("it is not a directory")));
  }
  // Writable: a file can be created in it (also for root, whom permissions do not stop).
  const std::string probe = (fs::path(dir) / (".write-check-" + std::to_string(::getpid()))).string();
  const int slot = registerTemporary(fs::absolute(probe).string());
  const int error = createEmpty(probe);
  ::unlink(probe.c_str());
  g_slots[slot].state.store(kFree);
  if (error != 0)
  {
    throw std::runtime_error("cannot write output directory '" + dir + "': " + std::strerror(error));
  }
}
}  // namespace periodic_bias_compensation
