#include "scratch.h"

#include <unistd.h>

#include <filesystem>
#include <mutex>
#include <vector>

namespace whiskeye::testing {
namespace {

namespace fs = std::filesystem;

struct Registry {
  std::mutex mutex;
  std::vector<fs::path> paths;
  ~Registry() {
    std::error_code ec;
    for (const fs::path& p : paths) fs::remove_all(p, ec);
  }
};

Registry& registry() {
  static Registry r;
  return r;
}

fs::path remember(fs::path p) {
  Registry& r = registry();
  std::lock_guard lock(r.mutex);
  r.paths.push_back(p);
  return p;
}

}  // namespace

std::string scratch_dir(const std::string& name) {
  const fs::path dir = remember(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid())));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string scratch_file(const std::string& name, const std::string& ext) {
  static int calls = 0;
  std::lock_guard lock(registry().mutex);
  const fs::path p =
      fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + "_" + std::to_string(calls++) + ext);
  registry().paths.push_back(p);
  return p.string();
}

}  // namespace whiskeye::testing
