// Durable storage of slamd's state: one file per checkpoint, written atomically, checked on load.
//
// File format (little-endian):
//   offset 0  char[8]  magic "WKSLAMCP"
//          8  uint32   format version (kCheckpointFormatVersion)
//         12  uint32   CRC-32 (zlib) of the payload
//         16  uint64   sequence (the whisk cycle number the state is after)
//         24  uint64   payload size in bytes
//         32  payload  (VitaSlam::serialise(), which carries its own version)
// A write goes to a hidden temp file in the same directory, is fsync'ed, renamed over the final name
// and the directory is fsync'ed: a crash leaves either the old or the new checkpoint, never half of one.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace whiskeye::slamd {

constexpr uint32_t kCheckpointFormatVersion = 1;

class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Checkpoint {
  std::string path;
  uint64_t sequence = 0;
  std::vector<uint8_t> payload;
};

// Reads and validates one checkpoint file; CheckpointError "<path>: <reason>" when it is unusable.
Checkpoint read_checkpoint(const std::string& path);
// Writes one checkpoint file atomically (temp + fsync + rename + directory fsync).
void write_checkpoint_file(const std::string& path, uint64_t sequence, std::span<const uint8_t> payload);

// A directory of numbered checkpoints, newest kept, older ones pruned.
class CheckpointStore {
 public:
  // Creates the directory if needed; CheckpointError naming it when that fails.
  CheckpointStore(std::string directory, int keep);

  // Writes checkpoint-<sequence>.vslam and prunes all but the newest `keep`. Returns its path.
  std::string write(uint64_t sequence, std::span<const uint8_t> payload);

  // The newest checkpoint that validates. Each newer file that does not is reported in
  // `problems` as "<path>: <reason>" and left on disk for inspection (renamed *.corrupt).
  std::optional<Checkpoint> load_newest(std::vector<std::string>* problems);

  // Checkpoint files present, oldest first.
  std::vector<std::string> list() const;
  const std::string& directory() const { return directory_; }

 private:
  std::string directory_;
  int keep_;
};

}  // namespace whiskeye::slamd
