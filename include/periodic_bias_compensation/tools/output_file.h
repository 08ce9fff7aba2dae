// The files the package's tools write, written safely: under a temporary name next to the
// target ("PATH.partial-PID"), renamed to PATH only when complete. Until then the temporary is
// removed when the tool fails (exception, error exit), exits, or is ended by SIGINT, SIGTERM or
// SIGHUP (an async-signal-safe handler unlinks it, then the signal ends the process as it
// would have). A tool never writes over one of its inputs, and an output that cannot be written
// is reported as such, naming it, before any work is done. No ROS.
//
//   refuseOverwritingInputs({ { "--in", in } }, { { "--out", out } });  // UsageError: exit 2
//   OutputFile file(out);                    // the temporary exists from here; error if it cannot
//   writeSomething(file.temporary());
//   file.commit();                           // renamed to `out`
//   OutputFile report(md); ... report.commit(text);   // or: the whole contents at once
#pragma once

#include <string>
#include <vector>

namespace periodic_bias_compensation
{
class OutputFile
{
public:
  /// Creates the (empty) temporary file next to `path`. Throws std::runtime_error "cannot
  /// write output 'PATH': why" when it cannot (directory missing or not writable, PATH a
  /// directory). A `path` that is a device or a pipe (/dev/stdout) is written directly:
  /// temporary() is `path` itself, and it is never removed or replaced. Through a symbolic
  /// link, the file it names is written (the link stays).
  explicit OutputFile(std::string path);
  /// Removes the temporary unless commit() renamed it.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// The file the output is for.
  const std::string& path() const
  {
    return path_;
  }
  /// Where to write it until commit().
  const std::string& temporary() const
  {
    return temporary_;
  }

  /// Renames the temporary, written and closed by the caller, to path(). Throws
  /// std::runtime_error naming path() on failure (the temporary is then removed).
  void commit();
  /// Writes `contents` to the temporary, then renames it to path().
  void commit(const std::string& contents);

private:
  std::string path_;
  std::string target_;     ///< path_, or the file it names when it is a symbolic link
  std::string temporary_;  ///< next to target_; target_ itself for a device or a pipe
  int slot_ = -1;          ///< registration for removal on a signal or at exit; -1 when none
};

/// Writes `contents` to `path` through an OutputFile.
void writeOutputFile(const std::string& path, const std::string& contents);

/// A file named on the command line, with the option that named it ("--out").
struct NamedPath
{
  std::string option;
  std::string path;  ///< empty: the option was not given (ignored)
};

/// Throws UsageError (a command-line error) naming both options when an output is the same file
/// as an input or as another output: same path once made absolute and normalised (symbolic links
/// resolved), or, for files that exist, the same file (hard links).
void refuseOverwritingInputs(const std::vector<NamedPath>& inputs, const std::vector<NamedPath>& outputs);

/// Creates the directory `dir` (and its parents) if missing and checks that files can be
/// created in it; std::runtime_error "cannot write output directory 'DIR': why" otherwise.
void prepareOutputDirectory(const std::string& dir);
}  // namespace periodic_bias_compensation
