// Opening a file a program was given to read whole (an LCM log, a candump log): a regular file only,
// and without blocking. A FIFO with no writer blocks open() until one comes (for ever, under a
// service); a device (/dev/zero) never ends; a /proc or /sys file says it holds 0 bytes and then
// yields some. None of them is a recording, and each is refused at once in one line naming it.
#pragma once

#include <cstdint>
#include <string>

namespace whiskeye {

// A regular file opened read-only: its descriptor (the caller closes it) and its size then.
struct InputFile {
  int fd = -1;
  uint64_t size = 0;
};

// Opens `path` for reading as above; otherwise throws std::runtime_error "PATH: cannot open the
// WHAT for reading: WHY" (`what`: "LCM log", "candump log"; WHY: the errno text, "not a regular
// file", or "not a regular file (it reports 0 bytes but holds data)").
InputFile open_input_file(const std::string& path, const std::string& what);

}  // namespace whiskeye
