// The command-line convention of every WhiskEye program, in one place (docs/deployment.md,
// "Command-line convention"):
//   -c/--config FILE   the program's YAML parameters (must exist);
//   --print-config     the parameters in use, command-line overrides included, then exit 0;
//   --version          "<program> <version>" (the build's project version and git description);
//   --lcm-url URL      where the program talks LCM;
//   -o/--output FILE   where the program writes its one output file; no output is a file the
//                      program reads (refuse_output_onto_input());
//   exit status        0 done, 1 runtime failure, 2 bad command line or configuration, with one line
//                      "<program>: <reason>" on stderr (command-line errors too).
// A program builds its options on app(), then hands its body to run(), which parses and maps every
// error to that status and line. Its parameters are the config file's with the command line's
// overrides over them (read_config()), printed by --print-config (Program::print_config()).
#pragma once

#include "whiskeye/common/params.h"

#include <CLI/CLI.hpp>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::cli {

inline constexpr int kExitOk = 0;       // done
inline constexpr int kExitFailure = 1;  // failed at run time (a device, the disk, a damaged input)
inline constexpr int kExitUsage = 2;    // a bad command line or configuration: retrying will not help

// A bad command line found after parsing (a missing option, a bad combination): run() exits 2 with
// "<program>: <what>".
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "0.1.0 (0358d50-dirty)": the project version and `git describe --always --dirty` of the source
// tree at build time; the project version alone when built from a tree without git (a tarball).
// Generated at build time (cmake/WhiskeyeVersion.cmake).
const char* version();

// One parameter the command line sets over the config file: `key` (dotted, e.g. "lcm.url") to
// `value`, by `option` (named in errors and in --print-config).
struct Override {
  std::string key;
  std::string value;
  std::string option;
};

// The parameters a program runs with: the YAML file at `path` ("": every default), then the command
// line's `overrides` over it, each checked by the loader as the file's values are; so what
// --print-config prints is what runs. A file that cannot be read, or a key two overrides give,
// throws ParamError (run(): exit 2).
ParamNode read_config(const std::string& path, const std::vector<Override>& overrides = {});

// A file the program reads and the option that gave it, for refuse_output_onto_input().
struct InputFile {
  std::string option;  // "--replay", "-c", ...
  std::string path;    // empty: not given (skipped)
};

// Before `output` (given by `output_option`) is opened: UsageError "<output_option> <output> is the
// file given to <option> (<path>): writing it would destroy it" when it is one of `inputs`, the same
// regular file (device and inode, symbolic links followed: a hard link, a symbolic link and another
// spelling of the path are caught). An output that does not exist yet is none of them.
void refuse_output_onto_input(const std::string& output_option, const std::string& output,
                              const std::vector<InputFile>& inputs);

// Before the work whose result is written with write_file_atomically (whiskeye/common/output_file.h):
// UsageError "<option> <path>: <why>" when that write would be refused (a FIFO, a directory, a
// device, a symbolic link, a missing directory), so that it is said before, not after, the work.
void refuse_unwritable_output(const std::string& option, const std::string& path);

class Program {
 public:
  // `name` is the program's name on every error line and in --version; --help and --version are
  // added here.
  Program(std::string name, const std::string& description);
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;

  CLI::App& app() { return app_; }
  const std::string& name() const { return name_; }

  // -c/--config FILE: `what` says what the file holds. A file that does not exist is a usage error.
  CLI::Option* add_config(std::string& path, const std::string& what);
  // --print-config: print the parameters in use and exit (print_config()).
  CLI::Option* add_print_config(bool& flag);
  // With --print-config given: prints `parameters` (the dump() of every ParamNode the program
  // loaded) to stdout and returns true; the program then exits 0 without running.
  bool print_config(const std::string& parameters) const;
  // --lcm-url URL (empty: $LCM_DEFAULT_URL, or LCM's default).
  CLI::Option* add_lcm_url(std::string& url);
  // -o/--output FILE: `what` says what is written.
  CLI::Option* add_output(std::string& path, const std::string& what);

  // Parses argv, then returns body()'s exit status. --help and --version print to stdout and return
  // 0. A parse error, a CLI::ParseError or UsageError thrown by body, and a ParamError (a bad config)
  // print one line "<name>: <reason>" to stderr and return 2; any other exception from body the same
  // line and 1.
  int run(int argc, char** argv, const std::function<int()>& body);

  // Prints "<name>: <reason>" to stderr, on one line (line breaks in `reason` become "; ").
  void error(const std::string& reason) const;

 private:
  std::string name_;
  CLI::App app_;
  const bool* print_config_ = nullptr;  // add_print_config()'s flag
};

}  // namespace whiskeye::cli
