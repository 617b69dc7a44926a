// One home for a daemon's log lines with a level. Under systemd a daemon's stderr is a stream into
// the journal, and systemd names that stream in JOURNAL_STREAM ("<device>:<inode>" of the file behind
// stderr). A line starting with "<N>" (sd-daemon(3); SyslogLevelPrefix=yes, systemd's default) is
// stored with syslog priority N, without the prefix, so `journalctl -p warning -u slamd` shows the
// warnings and errors alone. Anywhere else (a terminal, a test, a pipe) the line is plain text.
// Lines without a level stay at the unit's SyslogLevel= (info).
#pragma once

#include <string>
#include <string_view>

namespace whiskeye {

// syslog(3) priorities, the numbers the journal stores.
enum class LogLevel { kError = 3, kWarning = 4, kNotice = 5, kInfo = 6 };

// The text to write for `line` (one or more lines; each gets the prefix, a trailing newline ends it):
// "<4>slamd: …\n" when writing to the journal, "slamd: …\n" otherwise. Pure.
std::string format_log_line(LogLevel level, std::string_view line, bool to_journal);

// Whether `journal_stream` (the value of JOURNAL_STREAM, or null) names the file open on `fd`: only
// then is that descriptor the journal (a child whose stderr was redirected inherits the variable).
bool is_journal_stream(const char* journal_stream, int fd);

// Writes `line` (the program's name first, as every line of ours) to stderr at `level`, prefixed for
// the journal when stderr is it (decided once per process). One write per call, so lines of
// several threads do not interleave.
void log_line(LogLevel level, std::string_view line);
inline void log_error(std::string_view line) { log_line(LogLevel::kError, line); }
inline void log_warning(std::string_view line) { log_line(LogLevel::kWarning, line); }
inline void log_notice(std::string_view line) { log_line(LogLevel::kNotice, line); }
inline void log_info(std::string_view line) { log_line(LogLevel::kInfo, line); }

}  // namespace whiskeye
