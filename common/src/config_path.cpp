// Default config files found from the program's own location (common/config_path.h).
#include "whiskeye/common/config_path.h"

#include "whiskeye/common/params.h"

#include <stdexcept>

#ifndef WHISKEYE_BUILD_DIR
#error "WHISKEYE_BUILD_DIR (the build tree) must be defined for config_path.cpp"
#endif
#ifndef WHISKEYE_CONFIG_SOURCE_DIR
#error "WHISKEYE_CONFIG_SOURCE_DIR (the source tree) must be defined for config_path.cpp"
#endif

namespace whiskeye {

namespace fs = std::filesystem;

namespace {

// True if `p` is `dir` or lies below it (both absolute and normalised).
bool is_within(const fs::path& p, const fs::path& dir) {
  const fs::path rel = p.lexically_relative(dir);
  return !rel.empty() && *rel.begin() != "..";
}

std::string no_default(std::string_view name) {
  std::string s = "no default ";
  s += name;
  s += ": ";
  return s;
}

}  // namespace

std::vector<fs::path> config_search_dirs(const fs::path& exe, const fs::path& build_dir, const fs::path& source_dir) {
  const fs::path prefix = exe.lexically_normal().parent_path().parent_path();
  // systemd/install_layout.cmake's <sysconfdir>.
  const fs::path sysconfdir = prefix == "/usr" ? fs::path("/etc") : prefix / "etc";
  std::vector<fs::path> dirs{sysconfdir / "whiskeye"};
  if (is_within(exe.lexically_normal(), build_dir.lexically_normal())) dirs.push_back(source_dir / "config");
  return dirs;
}

fs::path find_config(std::string_view name, const std::vector<fs::path>& dirs, std::string_view option) {
  std::string tried;
  for (const fs::path& dir : dirs) {
    const fs::path candidate = dir / name;
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate;
    if (!tried.empty()) tried += ", ";
    tried += candidate.string();
  }
  throw ParamError(no_default(name) + "tried " + tried + "; give one with " + std::string(option));
}

fs::path default_config_path(std::string_view name, std::string_view option) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    throw ParamError(no_default(name) + "cannot read /proc/self/exe (" + ec.message() + "); give one with " +
                             std::string(option));
  }
  // /proc/self/exe is canonical; the compiled-in build tree may have been named through a symbolic link.
  fs::path build_dir = fs::weakly_canonical(WHISKEYE_BUILD_DIR, ec);
  if (ec) build_dir = WHISKEYE_BUILD_DIR;
  return find_config(name, config_search_dirs(exe, build_dir, WHISKEYE_CONFIG_SOURCE_DIR), option);
}

}  // namespace whiskeye
