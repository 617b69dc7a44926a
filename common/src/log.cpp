#include "whiskeye/common/log.h"

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace whiskeye {

std::string format_log_line(LogLevel level, std::string_view line, bool to_journal) {
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  // Appended, not "<" + std::string: GCC 12's -Wrestrict misfires on that at -O3 (GCC bug 105329).
  std::string prefix;
  if (to_journal) prefix.append("<").append(std::to_string(static_cast<int>(level))).append(">");
  std::string out;
  out.reserve(line.size() + prefix.size() + 1);
  // Every line of a multi-line message carries the priority: the journal reads each line on its own.
  std::size_t start = 0;
  while (true) {
    const std::size_t end = line.find('\n', start);
    out += prefix;
    out += line.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
    out += '\n';
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return out;
}

bool is_journal_stream(const char* journal_stream, int fd) {
  if (journal_stream == nullptr) return false;
  unsigned long long dev = 0;
  unsigned long long ino = 0;
  char tail = 0;
  if (std::sscanf(journal_stream, "%llu:%llu%c", &dev, &ino, &tail) != 2) return false;
  struct stat st {};
  if (fstat(fd, &st) != 0) return false;
  return static_cast<unsigned long long>(st.st_dev) == dev && static_cast<unsigned long long>(st.st_ino) == ino;
}

void log_line(LogLevel level, std::string_view line) {
  static const bool to_journal = is_journal_stream(std::getenv("JOURNAL_STREAM"), 2);
  const std::string text = format_log_line(level, line, to_journal);
  std::fwrite(text.data(), 1, text.size(), stderr);
  std::fflush(stderr);
}

}  // namespace whiskeye
