// The files a program writes for a service or a later run to read (a calibration drop-in, a
// checkpoint, a generated world, vita-eval's JSON): replaced atomically, and never onto a file the
// program reads (docs/reliability.md, "Hostile input, round 3: files").
//
// write_file_atomically() writes the bytes to a new temp file beside the target, fsyncs it, renames
// it over the target and fsyncs the directory: a reader, a crash, a full disk or a writer killed half
// way sees the old file or the new one, never part of one. The temp file is ".<name>.<unique>.tmp",
// created with O_EXCL (two writers of one target never share it; the last rename wins whole), mode
// 0644 less the umask, or the replaced file's permission bits. A failure removes it; a killed writer
// leaves it (hidden, and no service reads a *.tmp).
//
// An existing target that is not a regular file is refused and left alone: a directory, a FIFO
// (opening one blocks until a reader comes), a device, a socket, and a symbolic link, which is
// neither followed (a link in a drop-in directory would send the write anywhere the writer may
// write) nor replaced (the file it names would silently stay as it was): the error says where it
// points, so the user can give that file.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace whiskeye {

// A file not written, or not checked: "<path>: <what failed>[: <errno text>]", one line.
class OutputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Why write_file_atomically(path) would refuse `path` before writing a byte, "" when it would not:
// an existing entry that is not a regular file, or a directory that does not exist (or is not one).
// For a program to refuse such an output up front, before the work that produces its bytes.
std::string output_file_problem(const std::string& path);

// Replaces `path` with `pieces`, concatenated, as described above. Throws OutputFileError naming
// `path` (its temp file removed, the old `path` untouched) when the target is refused or a step
// fails: creating the temp file, a write (ENOSPC, EIO), fsync, rename, the directory's fsync. A
// failing directory fsync is reported too, though the rename has happened: the new file is in
// place but not known to survive a power loss.
void write_file_atomically(const std::string& path, std::initializer_list<std::span<const uint8_t>> pieces);
void write_file_atomically(const std::string& path, std::string_view text);

// Whether `a` and `b` are one regular file: the same device and inode, symbolic links followed (so
// a hard link, a symbolic link and another spelling of the path all count). False when either does
// not exist or is not a regular file (a terminal or a pipe read and written at once is no loss).
bool same_regular_file(const std::string& a, const std::string& b);

}  // namespace whiskeye
