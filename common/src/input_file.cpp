// open_input_file (input_file.h).
#include "whiskeye/common/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace whiskeye {

InputFile open_input_file(const std::string& path, const std::string& what) {
  const std::string cannot = path + ": cannot open the " + what + " for reading: ";
  // O_NONBLOCK: opening a FIFO with no writer returns at once (and is refused below) instead of
  // waiting for one; a regular file's reads ignore the flag.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw std::runtime_error(cannot + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw std::runtime_error(cannot + "not a regular file");
  }
  if (uint8_t byte = 0; st.st_size == 0 && ::pread(fd, &byte, 1, 0) > 0) {  // a /proc or /sys file: sized as it is read
    ::close(fd);
    throw std::runtime_error(cannot + "not a regular file (it reports 0 bytes but holds data)");
  }
  return {fd, static_cast<uint64_t>(st.st_size)};
}

}  // namespace whiskeye
