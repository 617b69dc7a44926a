// A small filesystem a test can fill: a tmpfs mounted in a mount namespace of the test process's own,
// so that nothing it mounts is seen outside it, and the disk-full paths run against a real ENOSPC.
// Tests run as root: a test that cannot mount fails (error() says why), it never skips.
#pragma once

#include <cstddef>
#include <string>

namespace whiskeye::testing {

class PrivateTmpfs {
 public:
  // Mounts a tmpfs of `size` (mount's size=, e.g. "256k") on `dir`, created if missing. The first
  // one moves the process into a mount namespace of its own (unshare(CLONE_NEWNS), which refuses a
  // process with threads: mount before any thread starts).
  PrivateTmpfs(std::string dir, const std::string& size);
  ~PrivateTmpfs();  // unmounts (lazily: a child still in it does not keep it)
  PrivateTmpfs(const PrivateTmpfs&) = delete;
  PrivateTmpfs& operator=(const PrivateTmpfs&) = delete;

  bool mounted() const { return error_.empty(); }
  const std::string& error() const { return error_; }  // "": mounted
  const std::string& dir() const { return dir_; }

 private:
  std::string dir_;
  std::string error_;
};

// Writes `path` until its filesystem is full (a full page left over at most); returns the bytes written.
std::size_t fill_disk(const std::string& path);

}  // namespace whiskeye::testing
