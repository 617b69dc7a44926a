// What the slamd binary tests read back from slamd's files: its output log and its checkpoints.
#pragma once

#include "whiskeye/common/bus.h"

#include <whiskeye/vita_event_t.hpp>
#include <whiskeye/vita_map_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace whiskeye::testing {

struct SlamdOutput {
  std::vector<vita_event_t> events;
  std::vector<vita_map_t> maps;
  int ground_truth = 0;
};

// VITA_EVENT and VITA_MAP of a slamd output log, in order, and how many GROUND_TRUTH it copied.
inline SlamdOutput read_slamd_output(const std::string& path) {
  SlamdOutput o;
  LogReader r(path);
  LogEvent ev;
  while (r.next(ev)) {
    if (ev.channel == "VITA_EVENT") {
      vita_event_t m;
      EXPECT_TRUE(decode_message(ev.data, m)) << path;
      o.events.push_back(m);
    } else if (ev.channel == "VITA_MAP") {
      vita_map_t m;
      EXPECT_TRUE(decode_message(ev.data, m)) << path;
      o.maps.push_back(m);
    } else if (ev.channel == "GROUND_TRUTH") {
      ++o.ground_truth;
    }
  }
  return o;
}

// Checkpoint files in `dir`, oldest first (read without taking the directory's lock, which a running
// slamd holds).
inline std::vector<std::filesystem::path> checkpoint_files(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".vslam") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace whiskeye::testing
