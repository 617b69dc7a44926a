// write_file_atomically and same_regular_file (whiskeye/common/output_file.h) against a real full
// filesystem (a tmpfs of the test's own), a writer SIGKILLed half way, two writers at once, and
// targets that are not regular files.
#include "whiskeye/common/output_file.h"

#include "private_tmpfs.h"
#include "scratch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Names in `dir` other than `keep`: what a write left behind.
std::vector<std::string> others(const std::string& dir, const std::vector<std::string>& keep) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (std::find(keep.begin(), keep.end(), name) == keep.end()) names.push_back(name);
  }
  return names;
}

// `n` bytes of `c`: a content whose every prefix but the whole is told apart from it.
std::string content(char c, std::size_t n) { return std::string(n, c); }

// Whether `text` is one of the contents written whole: `n` bytes, all the same letter of `letters`.
bool whole(const std::string& text, std::size_t n, const std::string& letters) {
  if (text.size() != n || letters.find(text.front()) == std::string::npos) return false;
  return text.find_first_not_of(text.front()) == std::string::npos;
}

// Runs `body` in a child process and waits up to `timeout_s`: its exit status, or -1 (killed) if it
// did not end in time (a write that blocks).
template <typename Body>
int in_child(Body body, double timeout_s) {
  const pid_t pid = ::fork();
  if (pid == 0) ::_exit(body());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(OutputFile, AFullDiskLeavesTheOldFileWholeAndNoTempFileAndSaysWhyOnOneLine) {
  testing::PrivateTmpfs disk(testing::scratch_dir("output_file_full") + "/disk", "64k");
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const std::string target = disk.dir() + "/20-rest.yaml";
  const std::string old = content('o', 3000);
  write_file_atomically(target, old);
  ASSERT_GT(testing::fill_disk(disk.dir() + "/filler"), 0u);

  try {
    write_file_atomically(target, content('n', 20000));
    FAIL() << "a write to a full disk succeeded";
  } catch (const OutputFileError& e) {
    EXPECT_EQ(std::string(e.what()), target + ": cannot write: No space left on device");
  }
  EXPECT_TRUE(whole(slurp(target), old.size(), "o")) << "the file a service reads must stay whole: "
                                                      << slurp(target).substr(0, 40) << "..., " << slurp(target).size()
                                                      << " bytes";
  EXPECT_THAT(others(disk.dir(), {"20-rest.yaml", "filler"}), IsEmpty()) << "the temp file is removed";

  fs::remove(disk.dir() + "/filler");  // room again: the same write goes through
  write_file_atomically(target, content('n', 20000));
  EXPECT_TRUE(whole(slurp(target), 20000, "n"));
  EXPECT_THAT(others(disk.dir(), {"20-rest.yaml"}), IsEmpty());
}

// A writer killed while a file of the directory holds part of a content (its temp file, or the target
// itself were it written in place) leaves the target as the last whole write made it; the temp file
// it leaves is hidden and not the target's name.
TEST(OutputFile, AWriterKilledHalfWayLeavesTheOldOrTheNewFileNeverPart) {
  testing::PrivateTmpfs disk(testing::scratch_dir("output_file_kill") + "/disk", "256m");
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const std::string target = disk.dir() + "/world.yaml";
  constexpr std::size_t kSize = 24u << 20;
  write_file_atomically(target, content('a', kSize));
  for (int run = 0; run < 6; ++run) {
    const pid_t child = ::fork();
    if (child == 0) {
      // Rewrites the target, 'a' and 'b' in turn, until killed.
      for (int i = 0;; ++i) write_file_atomically(target, content(i % 2 == 0 ? 'b' : 'a', kSize));
    }
    bool half_way = false;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!half_way && std::chrono::steady_clock::now() < deadline) {
      for (const auto& e : fs::directory_iterator(disk.dir())) {
        std::error_code ec;
        const auto size = fs::file_size(e.path(), ec);
        if (!ec && size > 0 && size < kSize) half_way = true;
      }
    }
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    ASSERT_TRUE(half_way) << "run " << run << ": no write was seen half way in 20 s";
    EXPECT_TRUE(whole(slurp(target), kSize, "ab")) << "run " << run << ": the target holds part of a write";
    for (const std::string& name : others(disk.dir(), {"world.yaml"})) {
      EXPECT_THAT(name, ::testing::MatchesRegex("\\.world\\.yaml\\.[0-9a-f]{16}\\.tmp")) << "a left-over temp file";
      fs::remove(disk.dir() + "/" + name);
    }
  }
}

// Two writers of one file, each rewriting it 150 times while a reader reads it: every read is one
// writer's whole content (no shared temp file, no file written in place), nothing is left behind.
TEST(OutputFile, TwoWritersAtOnceNeverTearTheFile) {
  const std::string dir = testing::scratch_dir("output_file_two");
  const std::string target = dir + "/20-rest.yaml";
  constexpr std::size_t kSize = 256u << 10;
  write_file_atomically(target, content('a', kSize));
  std::vector<pid_t> writers;
  for (const char c : {'a', 'b'}) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      try {
        for (int i = 0; i < 150; ++i) write_file_atomically(target, content(c, kSize));
      } catch (const std::exception& e) {
        std::fprintf(stderr, "writer %c: %s\n", c, e.what());
        ::_exit(1);
      }
      ::_exit(0);
    }
    writers.push_back(pid);
  }
  int reads = 0, torn = 0;
  std::vector<int> statuses(writers.size(), -1);
  for (std::size_t ended = 0; ended < writers.size();) {
    if (!whole(slurp(target), kSize, "ab")) ++torn;
    ++reads;
    for (std::size_t i = 0; i < writers.size(); ++i) {
      if (statuses[i] == -1 && ::waitpid(writers[i], &statuses[i], WNOHANG) == writers[i]) ++ended;
    }
  }
  for (const int status : statuses) EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  EXPECT_EQ(torn, 0) << "of " << reads << " reads";
  EXPECT_TRUE(whole(slurp(target), kSize, "ab"));
  EXPECT_THAT(others(dir, {"20-rest.yaml"}), IsEmpty());
}

TEST(OutputFile, ATargetThatIsNotARegularFileIsRefusedAndLeftAlone) {
  testing::PrivateTmpfs disk(testing::scratch_dir("output_file_kinds") + "/disk", "1m");
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const std::string d = disk.dir();
  ASSERT_EQ(::mkfifo((d + "/fifo").c_str(), 0644), 0);
  ASSERT_EQ(::mknod((d + "/null").c_str(), S_IFCHR | 0644, makedev(1, 3)), 0);
  fs::create_directory(d + "/dir");
  std::ofstream(d + "/elsewhere") << "not to be written through a link";
  fs::create_symlink(d + "/elsewhere", d + "/link");
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::string sock_path = d + "/sock";
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", sock_path.c_str());
  ASSERT_EQ(::bind(sock, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0);

  const std::pair<const char*, const char*> cases[] = {
      {"fifo", "is a FIFO, not a regular file"},     {"null", "is a device, not a regular file"},
      {"dir", "is a directory, not a regular file"}, {"sock", "is a socket, not a regular file"},
      {"link", "is a symbolic link (to "},
  };
  for (const auto& [name, why] : cases) {
    const std::string path = d + "/" + name;
    EXPECT_THAT(output_file_problem(path), HasSubstr(why)) << name;
    // In a child: a FIFO opened for writing would block it until a reader came.
    const int status = in_child(
        [&] {
          try {
            write_file_atomically(path, "drop-in");
          } catch (const OutputFileError& e) {
            const std::string what = e.what();
            return what.rfind(path + ": ", 0) == 0 && what.find(why) != std::string::npos ? 0 : 3;
          }
          return 4;  // written
        },
        5.0);
    EXPECT_EQ(status, 0) << name << ": -1 blocked, 3 another message, 4 written";
  }
  EXPECT_THAT(output_file_problem(d + "/link"), HasSubstr("(to " + d + "/elsewhere), not followed: give the file itself"));
  EXPECT_EQ(slurp(d + "/elsewhere"), "not to be written through a link");
  EXPECT_TRUE(fs::is_symlink(d + "/link"));
  EXPECT_TRUE(fs::is_fifo(d + "/fifo"));
  EXPECT_TRUE(fs::is_character_file(d + "/null"));
  EXPECT_TRUE(fs::is_empty(d + "/dir"));
  EXPECT_THAT(others(d, {"fifo", "null", "dir", "elsewhere", "link", "sock"}), IsEmpty());
  ::close(sock);

  EXPECT_THAT(output_file_problem(d + "/missing/x.yaml"), HasSubstr("its directory " + d + "/missing cannot be used"));
  EXPECT_THAT(output_file_problem(d + "/elsewhere/x.yaml"), HasSubstr("is not a directory"));
  EXPECT_EQ(output_file_problem(d + "/new.yaml"), "");
  EXPECT_EQ(output_file_problem(d + "/elsewhere"), "");
}

TEST(OutputFile, AReplacedFileKeepsItsPermissionsAndANewOneGetsTheUmasks) {
  const std::string dir = testing::scratch_dir("output_file_mode");
  const std::string kept = dir + "/kept.yaml";
  std::ofstream(kept) << "old";
  fs::permissions(kept, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  write_file_atomically(kept, "new");
  EXPECT_EQ(slurp(kept), "new");
  EXPECT_EQ(fs::status(kept).permissions(), fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);

  const mode_t mask = ::umask(022);
  write_file_atomically(dir + "/new.yaml", "new");
  ::umask(mask);
  EXPECT_EQ(fs::status(dir + "/new.yaml").permissions(),
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read);
}

TEST(OutputFile, SameRegularFileFollowsLinksAndComparesDeviceAndInode) {
  const std::string dir = testing::scratch_dir("output_file_same");
  const std::string log = dir + "/run.lcmlog";
  std::ofstream(log) << "log";
  std::ofstream(dir + "/other.lcmlog") << "log";
  fs::create_hard_link(log, dir + "/hard.lcmlog");
  fs::create_symlink(log, dir + "/soft.lcmlog");
  fs::create_directory(dir + "/sub");
  EXPECT_TRUE(same_regular_file(log, log));
  EXPECT_TRUE(same_regular_file(log, dir + "/sub/../run.lcmlog"));
  EXPECT_TRUE(same_regular_file(log, dir + "/hard.lcmlog"));
  EXPECT_TRUE(same_regular_file(dir + "/soft.lcmlog", log));
  EXPECT_FALSE(same_regular_file(log, dir + "/other.lcmlog")) << "equal bytes are not the same file";
  EXPECT_FALSE(same_regular_file(log, dir + "/missing.lcmlog"));
  EXPECT_FALSE(same_regular_file("/dev/null", "/dev/null")) << "not a regular file: reading and writing it loses nothing";
  EXPECT_FALSE(same_regular_file(dir + "/sub", dir + "/sub"));
}

}  // namespace
}  // namespace whiskeye
