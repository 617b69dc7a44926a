#include "private_tmpfs.h"

#include <sched.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

namespace whiskeye::testing {

namespace {

// "" once this process is in a mount namespace of its own in which mounts do not propagate.
std::string private_namespace() {
  static const std::string error = []() -> std::string {
    if (::unshare(CLONE_NEWNS) != 0) {
      return std::string("unshare(CLONE_NEWNS): ") + std::strerror(errno) + " (tests run as root, before any thread)";
    }
    if (::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
      return std::string("making / private: ") + std::strerror(errno);
    }
    return "";
  }();
  return error;
}

}  // namespace

PrivateTmpfs::PrivateTmpfs(std::string dir, const std::string& size) : dir_(std::move(dir)) {
  error_ = private_namespace();
  if (!error_.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  const std::string options = "size=" + size + ",mode=0700";
  if (::mount("whiskeye-test", dir_.c_str(), "tmpfs", 0, options.c_str()) != 0) {
    error_ = "mount -t tmpfs -o " + options + " " + dir_ + ": " + std::strerror(errno);
  }
}

PrivateTmpfs::~PrivateTmpfs() {
  if (mounted()) ::umount2(dir_.c_str(), MNT_DETACH);
}

std::size_t fill_disk(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return 0;
  std::setvbuf(f, nullptr, _IONBF, 0);
  std::size_t written = 0;
  for (const std::size_t chunk : {std::size_t{65536}, std::size_t{512}, std::size_t{1}}) {
    const std::vector<char> block(chunk, 'x');
    for (std::size_t n = chunk; n == chunk;) {
      n = std::fwrite(block.data(), 1, block.size(), f);
      written += n;
    }
    std::clearerr(f);
  }
  std::fclose(f);
  return written;
}

}  // namespace whiskeye::testing
