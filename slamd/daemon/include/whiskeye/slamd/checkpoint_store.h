// Durable storage of slamd's state: one file per checkpoint, written atomically, checked on load.
//
// File format (little-endian):
//   offset 0  char[8]  magic "WKSLAMCP"
//          8  uint32   format version (kCheckpointFormatVersion)
//         12  uint32   CRC-32 (zlib) of the header's other 28 bytes (0..11, 16..31) and the payload;
//                      in format 1 of the payload only (still read)
//         16  uint64   sequence (the map's whisk cycle count, over all sessions, the state is after)
//         24  uint64   payload size in bytes
//         32  payload  (VitaSlam::serialise(), which carries its own version)
// A write goes to a hidden temp file in the same directory, is fsync'ed, renamed over the final name
// and the directory is fsync'ed (write_file_atomically, whiskeye/common/output_file.h): a crash leaves
// either the old or the new checkpoint, never half of one.
// Files are named checkpoint-<n>.vslam, n one more than any file in the directory: the newest file is
// always the last one written, whatever map it holds (a resumed one, or a new one after --fresh), so
// rotation never prunes what was just written. One process at a time owns a directory (an flock on
// the directory itself): a second slamd on it (a replay by hand next to the service) would take the
// first one's temp files for unfinished writes and rotate its checkpoints out.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::slamd {

// 2: the CRC covers the header too (a flipped version or sequence was taken at its word). Every later
// format must keep magic, version and this CRC where they are: an unknown version whose CRC holds is
// a newer slamd's file (kUnusable: slamd stops and names it); one whose CRC fails is damage (kCorrupt:
// the previous checkpoint is used).
constexpr uint32_t kCheckpointFormatVersion = 2;

class CheckpointError : public std::runtime_error {
 public:
  // kCorrupt: the bytes are damaged (magic, size, checksum); kUnusable: intact or unreadable here,
  // but not loadable by this slamd (a newer format, another mode, no permission).
  enum class Kind { kCorrupt, kUnusable };
  CheckpointError(const std::string& what, Kind kind = Kind::kCorrupt) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct Checkpoint {
  std::string path;
  uint64_t sequence = 0;
  std::vector<uint8_t> payload;
};

constexpr std::size_t kCheckpointHeaderSize = 32;

struct CheckpointHeader {
  uint32_t version = 0;
  uint32_t crc = 0;
  uint64_t sequence = 0;
  uint64_t payload_size = 0;
};

// The pure half of reading a checkpoint (no I/O; `path` only names it in errors), which
// read_checkpoint() and the fuzz target share. parse_checkpoint_header() checks a header against the
// size of its file (CheckpointError on bad magic, version or size), check_checkpoint_payload() the
// payload against its header (checksum); parse_checkpoint() does both on a whole file in memory.
CheckpointHeader parse_checkpoint_header(std::span<const uint8_t> header, uint64_t file_size, const std::string& path);
void check_checkpoint_payload(const CheckpointHeader& h, std::span<const uint8_t> header,
                              std::span<const uint8_t> payload, const std::string& path);
Checkpoint parse_checkpoint(std::span<const uint8_t> file, const std::string& path);
// The CRC that `header` (32 bytes) should hold for `payload`, by the header's version (for the fuzz
// target, which makes it match so that mutations reach the parsers).
uint32_t checkpoint_crc(std::span<const uint8_t> header, std::span<const uint8_t> payload);
// The header of a checkpoint of `payload` (what write_checkpoint_file() puts before it); another
// `version` for tests (1: the old format).
std::vector<uint8_t> checkpoint_header(uint64_t sequence, std::span<const uint8_t> payload,
                                       uint32_t version = kCheckpointFormatVersion);

// Reads and validates one checkpoint file; CheckpointError "<path>: <reason>" when it is unusable.
// Only a regular file is read, and its payload only once the header agrees with the file's size, so
// a wrong path (/dev/zero, a FIFO, a huge stray file) is refused before anything is allocated.
Checkpoint read_checkpoint(const std::string& path);
// Writes one checkpoint file atomically (write_file_atomically); CheckpointError "<path>: <reason>".
void write_checkpoint_file(const std::string& path, uint64_t sequence, std::span<const uint8_t> payload);

// A directory of numbered checkpoints, newest kept, older ones pruned.
class CheckpointStore {
 public:
  // Creates the directory if needed and locks it for this process; CheckpointError (kUnusable) naming
  // it when that fails or another process holds it. Temp files a crash left behind
  // (.checkpoint-*.tmp) are then removed and listed in removed_temp_files().
  CheckpointStore(std::string directory, int keep);
  ~CheckpointStore();
  CheckpointStore(const CheckpointStore&) = delete;
  CheckpointStore& operator=(const CheckpointStore&) = delete;

  // Writes the next checkpoint-<n>.vslam (header sequence = `sequence`) and prunes all but the
  // newest `keep`, and all but the newest `keep` of the files renamed *.corrupt. Returns its path.
  std::string write(uint64_t sequence, std::span<const uint8_t> payload);

  // The newest checkpoint that validates and that `use` (if given) accepts; `use` throws to refuse
  // one. A corrupt newer file is reported in `problems` as "<path>: <reason>", renamed *.corrupt
  // (kept for inspection, out of the rotation) and the next older one is tried. A file that is
  // intact but unusable here (a newer format, refused by `use`, unreadable) throws CheckpointError
  // kUnusable naming it: falling back past it, or starting a new map whose checkpoints would rotate
  // it out, could lose that map. Entries named like checkpoints that cannot be one (a directory, a
  // FIFO, a symlink — never followed —, a number beyond 2^64 - 2) are left alone and each named in
  // `problems`.
  std::optional<Checkpoint> load_newest(std::vector<std::string>* problems,
                                        const std::function<void(const Checkpoint&)>& use = {});

  // Checkpoint files present (regular files named checkpoint-<n>.vslam, n any number up to 2^64 - 2),
  // oldest first.
  std::vector<std::string> list() const;
  const std::string& directory() const { return directory_; }
  const std::vector<std::string>& removed_temp_files() const { return removed_temp_files_; }

 private:
  struct Scan {
    std::vector<std::string> files;    // checkpoints, oldest first
    std::vector<std::string> corrupt;  // *.vslam.corrupt, oldest first
    std::vector<std::string> skipped;  // "<path>: why it is not a checkpoint file"
  };
  Scan scan() const;

  std::string directory_;
  int lock_fd_ = -1;  // the directory, flock'ed while this store lives
  int keep_;
  uint64_t next_number_ = 1;
  std::vector<std::string> removed_temp_files_;
};

}  // namespace whiskeye::slamd
