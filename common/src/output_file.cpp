// Files replaced atomically, and the same-file test (whiskeye/common/output_file.h).
#include "whiskeye/common/output_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <random>
#include <sys/stat.h>
#include <unistd.h>

namespace whiskeye {

namespace {

namespace fs = std::filesystem;

std::string errno_text(int e) { return std::strerror(e); }

[[noreturn]] void fail(const std::string& path, const std::string& what) { throw OutputFileError(path + ": " + what); }

// The directory a file of `path` is in ("." for a bare name) and its name.
struct Place {
  std::string dir;
  std::string name;
};
Place place_of(const std::string& path) {
  const fs::path p(path);
  return {p.has_parent_path() ? p.parent_path().string() : std::string("."), p.filename().string()};
}

// output_file_problem(), and the target's mode when it exists (`existing`).
std::string problem_of(const std::string& path, struct stat& st, bool& existing) {
  existing = false;
  const Place at = place_of(path);
  if (at.name.empty() || at.name == "." || at.name == "..") return "names a directory, not a file";
  if (::lstat(path.c_str(), &st) == 0) {
    existing = true;
    if (S_ISREG(st.st_mode)) return "";
    if (S_ISLNK(st.st_mode)) {
      char target[4096];
      const ssize_t n = ::readlink(path.c_str(), target, sizeof target - 1);
      const std::string to = n >= 0 ? std::string(target, static_cast<std::size_t>(n)) : std::string("?");
      return "is a symbolic link (to " + to + "), not followed: give the file itself";
    }
    if (S_ISDIR(st.st_mode)) return "is a directory, not a regular file";
    if (S_ISFIFO(st.st_mode)) return "is a FIFO, not a regular file";
    if (S_ISSOCK(st.st_mode)) return "is a socket, not a regular file";
    return "is a device, not a regular file";
  }
  if (errno != ENOENT && errno != ENOTDIR) return "cannot be looked at: " + errno_text(errno);
  struct stat dir {};
  if (::stat(at.dir.c_str(), &dir) != 0) return "its directory " + at.dir + " cannot be used: " + errno_text(errno);
  if (!S_ISDIR(dir.st_mode)) return "its directory " + at.dir + " is not a directory";
  return "";
}

// ".<name>.<16 hex digits>.tmp" in `dir`, created O_EXCL; the fd, its name in `tmp`.
int create_temp(const Place& at, const std::string& path, std::string& tmp) {
  static thread_local std::mt19937_64 draw{std::random_device{}() ^ (static_cast<uint64_t>(::getpid()) << 32)};
  for (int attempt = 0; attempt < 100; ++attempt) {
    char unique[24];
    std::snprintf(unique, sizeof unique, "%016llx", static_cast<unsigned long long>(draw()));
    // A char, not a one-character string: GCC 12 at -O3 raises a bogus -Wrestrict on "x" + std::string&&
    // (GCC bug 105329), which breaks the Release build.
    tmp = (fs::path(at.dir) / ('.' + at.name + "." + unique + ".tmp")).string();
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd >= 0) return fd;
    if (errno != EEXIST) fail(path, "cannot create a temp file in " + at.dir + ": " + errno_text(errno));
  }
  fail(path, "cannot create a temp file in " + at.dir + ": 100 names taken");
}

void write_all(int fd, const uint8_t* data, std::size_t size, const std::string& path) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(path, "cannot write: " + errno_text(errno));
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

}  // namespace

std::string output_file_problem(const std::string& path) {
  struct stat st {};
  bool existing = false;
  return problem_of(path, st, existing);
}

void write_file_atomically(const std::string& path, std::initializer_list<std::span<const uint8_t>> pieces) {
  struct stat st {};
  bool existing = false;
  if (const std::string problem = problem_of(path, st, existing); !problem.empty()) fail(path, problem + "; not written");
  const Place at = place_of(path);
  std::string tmp;
  int fd = create_temp(at, path, tmp);
  try {
    if (existing && ::fchmod(fd, st.st_mode & 07777) != 0) fail(path, "cannot set the mode of its temp file: " + errno_text(errno));
    for (const std::span<const uint8_t>& piece : pieces) write_all(fd, piece.data(), piece.size(), path);
    if (::fsync(fd) != 0) fail(path, "fsync failed: " + errno_text(errno));
    const int closed = ::close(fd);
    fd = -1;
    if (closed != 0) fail(path, "close failed: " + errno_text(errno));
    // rename() never follows a link at `path`: a target swapped for one since the check is replaced,
    // not written through.
    if (::rename(tmp.c_str(), path.c_str()) != 0) fail(path, "cannot rename its temp file over it: " + errno_text(errno));
  } catch (...) {
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    throw;
  }
  const int dir = ::open(at.dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) fail(path, "written, but its directory " + at.dir + " cannot be opened to sync it: " + errno_text(errno));
  const int rc = ::fsync(dir);
  const int e = errno;
  ::close(dir);
  if (rc != 0) fail(path, "written, but the fsync of its directory " + at.dir + " failed: " + errno_text(e));
}

void write_file_atomically(const std::string& path, std::string_view text) {
  write_file_atomically(path, {std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size())});
}

bool same_regular_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return S_ISREG(sa.st_mode) && S_ISREG(sb.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

}  // namespace whiskeye
