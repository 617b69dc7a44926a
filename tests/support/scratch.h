// Scratch files and folders for tests. ctest runs test cases as separate processes side by side, and
// two checkouts may run the suite at once on one machine, so every name carries the process id; all
// of them are removed when the test program exits.
#pragma once

#include <string>

namespace whiskeye::testing {

// A fresh, empty folder <tmp>/<name>_<pid>, removed with its contents at exit.
std::string scratch_dir(const std::string& name);
// A path <tmp>/<name>_<pid>_<n><ext> (n counts this process's calls; not created), removed at exit.
std::string scratch_file(const std::string& name, const std::string& ext);

}  // namespace whiskeye::testing
