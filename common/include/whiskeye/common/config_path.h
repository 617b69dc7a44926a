// Where a program finds a config file it was not given on the command line (vita-sim's --robot,
// --whiskerd-config, --slam-config): in the installed config directory of the prefix the program was
// installed to, or in the source tree's config/ when the program runs from a build tree. Never
// relative to the working directory, so a program behaves the same from any folder.
//
// The installed directory follows systemd/install_layout.cmake: <sysconfdir>/whiskeye, where
// <sysconfdir> is /etc for the /usr prefix (the .deb) and <prefix>/etc otherwise, and <prefix> is the
// parent of the folder holding the program (<prefix>/bin/vita-sim), so a relocated install works too.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace whiskeye {

// The folders searched for a default config of the program at `exe`, in order: the installed config
// directory of its prefix; then `source_dir`/config if `exe` lies inside `build_dir` (a build tree).
// Pure (no file is looked at): `exe`, `build_dir` and `source_dir` are taken as given.
std::vector<std::filesystem::path> config_search_dirs(const std::filesystem::path& exe,
                                                      const std::filesystem::path& build_dir,
                                                      const std::filesystem::path& source_dir);

// `name` (e.g. "robot.yaml") in the first of `dirs` that holds a regular file of that name. None:
// ParamError (a configuration error, exit 2) "no default <name>: tried <dir>/<name>, ...; give one with
// <option>".
std::filesystem::path find_config(std::string_view name, const std::vector<std::filesystem::path>& dirs,
                                  std::string_view option);

// find_config over the search folders of this process: the running executable (/proc/self/exe) and the
// build and source trees it was built from.
std::filesystem::path default_config_path(std::string_view name, std::string_view option);

}  // namespace whiskeye
