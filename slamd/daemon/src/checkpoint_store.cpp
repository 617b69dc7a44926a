#include "whiskeye/slamd/checkpoint_store.h"

#include "whiskeye/common/output_file.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <string_view>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace whiskeye::slamd {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'W', 'K', 'S', 'L', 'A', 'M', 'C', 'P'};
constexpr std::size_t kHeaderSize = kCheckpointHeaderSize;

template <typename T>
void put(std::vector<uint8_t>& out, T value) {
  for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<uint8_t>(value >> (8 * i)));
}

template <typename T>
T get(const uint8_t* p) {
  T v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= static_cast<T>(static_cast<T>(p[i]) << (8 * i));
  return v;
}

uint32_t crc_of(std::span<const uint8_t> data, uLong crc = crc32(0L, Z_NULL, 0)) {
  // zlib takes uInt lengths: feed in chunks.
  std::size_t pos = 0;
  while (pos < data.size()) {
    const std::size_t n = std::min<std::size_t>(data.size() - pos, 1u << 30);
    crc = crc32(crc, data.data() + pos, static_cast<uInt>(n));
    pos += n;
  }
  return static_cast<uint32_t>(crc);
}

// Format 2 and later: the CRC covers the header (all of it but the CRC field, bytes 12..15) and the
// payload, so a flipped version, sequence or size is damage like a flipped payload byte.
uint32_t crc_of_file(std::span<const uint8_t> header, std::span<const uint8_t> payload) {
  uint32_t crc = crc_of(header.first(12));
  crc = crc_of(header.subspan(16, 16), crc);
  return crc_of(payload, crc);
}

[[noreturn]] void fail(const std::string& path, const std::string& what,
                       CheckpointError::Kind kind = CheckpointError::Kind::kCorrupt) {
  throw CheckpointError(path + ": " + what, kind);
}

constexpr char kPrefix[] = "checkpoint-";

std::string file_name(uint64_t number) {
  char name[64];
  std::snprintf(name, sizeof name, "%s%012llu.vslam", kPrefix, static_cast<unsigned long long>(number));
  return name;
}

// The largest number a file may carry: one more must still be a number (the next file's).
constexpr uint64_t kMaxFileNumber = UINT64_MAX - 1;

// n of "checkpoint-<n>.vslam[.corrupt]" (1..kMaxFileNumber), or 0; `out_of_range` says that the name
// is one but its number is beyond kMaxFileNumber.
uint64_t file_number(const std::string& name, bool* out_of_range = nullptr) {
  if (out_of_range) *out_of_range = false;
  if (name.rfind(kPrefix, 0) != 0) return 0;
  const char* first = name.data() + sizeof kPrefix - 1;
  const char* last = name.data() + name.size();
  uint64_t n = 0;
  const auto [end, ec] = std::from_chars(first, last, n);
  if (end == first || std::string_view(end, static_cast<std::size_t>(last - end)).rfind(".vslam", 0) != 0) return 0;
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && n > kMaxFileNumber)) {
    if (out_of_range) *out_of_range = true;
    return 0;
  }
  return ec == std::errc() ? n : 0;
}

bool is_corrupt_name(const std::string& name) {
  constexpr std::string_view kSuffix = ".vslam.corrupt";
  return name.size() > kSuffix.size() && name.compare(name.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0;
}

bool is_checkpoint_name(const std::string& name) {
  constexpr std::string_view kSuffix = ".vslam";
  return name.size() > kSuffix.size() && name.compare(name.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0;
}

const char* kind_of(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory: return "a directory";
    case fs::file_type::symlink: return "a symbolic link";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    case fs::file_type::block:
    case fs::file_type::character: return "a device";
    default: return "not a regular file";
  }
}

}  // namespace

CheckpointHeader parse_checkpoint_header(std::span<const uint8_t> header, uint64_t file_size, const std::string& path) {
  if (header.size() < kHeaderSize || file_size < kHeaderSize) {
    fail(path, "truncated header (" + std::to_string(std::min<uint64_t>(file_size, header.size())) + " bytes)");
  }
  if (std::memcmp(header.data(), kMagic, sizeof kMagic) != 0) fail(path, "not a slamd checkpoint (bad magic)");
  CheckpointHeader h;
  // The version is checked with the checksum (check_checkpoint_payload): only then is an unknown one
  // known to be what a newer slamd wrote and not a flipped bit.
  h.version = get<uint32_t>(header.data() + 8);
  h.crc = get<uint32_t>(header.data() + 12);
  h.sequence = get<uint64_t>(header.data() + 16);
  h.payload_size = get<uint64_t>(header.data() + 24);
  if (h.payload_size != file_size - kHeaderSize) {
    fail(path, "payload size " + std::to_string(file_size - kHeaderSize) + " differs from the header's " +
                   std::to_string(h.payload_size) + " (truncated or appended)");
  }
  return h;
}

void check_checkpoint_payload(const CheckpointHeader& h, std::span<const uint8_t> header,
                              std::span<const uint8_t> payload, const std::string& path) {
  if (header.size() < kHeaderSize) fail(path, "truncated header (" + std::to_string(header.size()) + " bytes)");
  if (h.version == 1) {
    // Format 1 (before the header was covered): the payload's CRC only.
    if (crc_of(payload) != h.crc) fail(path, "checksum mismatch (corrupt data)");
    return;
  }
  if (crc_of_file(header, payload) != h.crc) fail(path, "checksum mismatch (corrupt header or data)");
  // Intact: a version this slamd does not know was written by a newer one (every format from 2 on
  // keeps the magic, the version and this CRC where they are).
  if (h.version != kCheckpointFormatVersion) {
    fail(path,
         "unsupported checkpoint format version " + std::to_string(h.version) + " (this slamd reads 1 and " +
             std::to_string(kCheckpointFormatVersion) + ")",
         CheckpointError::Kind::kUnusable);
  }
}

Checkpoint parse_checkpoint(std::span<const uint8_t> file, const std::string& path) {
  const CheckpointHeader h = parse_checkpoint_header(file.first(std::min(file.size(), kHeaderSize)), file.size(), path);
  const auto payload = file.subspan(kHeaderSize);
  check_checkpoint_payload(h, file.first(kHeaderSize), payload, path);
  return Checkpoint{path, h.sequence, std::vector<uint8_t>(payload.begin(), payload.end())};
}

uint32_t checkpoint_crc(std::span<const uint8_t> header, std::span<const uint8_t> payload) {
  if (header.size() < kHeaderSize) return 0;
  return get<uint32_t>(header.data() + 8) == 1 ? crc_of(payload) : crc_of_file(header, payload);
}

std::vector<uint8_t> checkpoint_header(uint64_t sequence, std::span<const uint8_t> payload, uint32_t version) {
  std::vector<uint8_t> header(kMagic, kMagic + sizeof kMagic);
  put<uint32_t>(header, version);
  put<uint32_t>(header, 0);  // the CRC, below
  put<uint64_t>(header, sequence);
  put<uint64_t>(header, payload.size());
  const uint32_t crc = version == 1 ? crc_of(payload) : crc_of_file(header, payload);
  for (std::size_t i = 0; i < 4; ++i) header[12 + i] = static_cast<uint8_t>(crc >> (8 * i));
  return header;
}

Checkpoint read_checkpoint(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    fail(path, std::string("cannot open: ") + std::strerror(errno), CheckpointError::Kind::kUnusable);
  }
  if (!S_ISREG(st.st_mode)) fail(path, "not a regular file", CheckpointError::Kind::kUnusable);
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, std::string("cannot open: ") + std::strerror(errno), CheckpointError::Kind::kUnusable);
  const uint64_t file_size = static_cast<uint64_t>(st.st_size);
  std::array<uint8_t, kHeaderSize> header{};
  const auto header_bytes = static_cast<std::size_t>(std::min<uint64_t>(file_size, kHeaderSize));
  in.read(reinterpret_cast<char*>(header.data()), static_cast<std::streamsize>(header_bytes));
  if (in.bad()) fail(path, "read error", CheckpointError::Kind::kUnusable);
  // The payload is read only once the header agrees with the file's size: nothing is allocated for
  // a stray huge file.
  const CheckpointHeader h = parse_checkpoint_header(std::span<const uint8_t>(header.data(), header_bytes), file_size, path);
  Checkpoint cp;
  cp.path = path;
  cp.sequence = h.sequence;
  cp.payload.resize(h.payload_size);
  in.read(reinterpret_cast<char*>(cp.payload.data()), static_cast<std::streamsize>(h.payload_size));
  if (in.bad()) fail(path, "read error", CheckpointError::Kind::kUnusable);  // the disk, not the file
  if (static_cast<uint64_t>(in.gcount()) != h.payload_size) fail(path, "shorter than its size while being read");
  check_checkpoint_payload(h, header, cp.payload, path);
  return cp;
}

void write_checkpoint_file(const std::string& path, uint64_t sequence, std::span<const uint8_t> payload) {
  const std::vector<uint8_t> header = checkpoint_header(sequence, payload);
  try {
    write_file_atomically(path, {header, payload});
  } catch (const OutputFileError& e) {
    throw CheckpointError(e.what());
  }
}

CheckpointStore::CheckpointStore(std::string directory, int keep) : directory_(std::move(directory)), keep_(std::max(1, keep)) {
  std::error_code ec;
  fs::create_directories(directory_, ec);
  if (ec || !fs::is_directory(directory_)) {
    throw CheckpointError(directory_ + ": cannot create the checkpoint directory" + (ec ? ": " + ec.message() : ""),
                          CheckpointError::Kind::kUnusable);
  }
  lock_fd_ = ::open(directory_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (lock_fd_ < 0) {
    throw CheckpointError(directory_ + ": cannot open the checkpoint directory: " + std::strerror(errno),
                          CheckpointError::Kind::kUnusable);
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    ::close(lock_fd_);
    throw CheckpointError(directory_ + (e == EWOULDBLOCK
                                            ? std::string(": in use by another slamd (it holds the directory's lock); "
                                                          "give this one its own --state-dir")
                                            : std::string(": cannot lock the checkpoint directory: ") + std::strerror(e)),
                          CheckpointError::Kind::kUnusable);
  }
  for (const auto& entry : fs::directory_iterator(directory_)) {
    const std::string name = entry.path().filename().string();
    next_number_ = std::max(next_number_, file_number(name) + 1);
    if (entry.is_regular_file() && name.rfind(std::string(".") + kPrefix, 0) == 0 && entry.path().extension() == ".tmp") {
      std::error_code rm;
      if (fs::remove(entry.path(), rm)) removed_temp_files_.push_back(entry.path().string());
    }
  }
}

CheckpointStore::Scan CheckpointStore::scan() const {
  Scan scan;
  std::vector<std::pair<uint64_t, std::string>> files, corrupt;
  for (const auto& entry : fs::directory_iterator(directory_)) {
    const std::string name = entry.path().filename().string();
    const bool checkpoint = is_checkpoint_name(name);
    if (!checkpoint && !is_corrupt_name(name)) continue;
    bool out_of_range = false;
    const uint64_t n = file_number(name, &out_of_range);
    if (out_of_range && checkpoint) {
      scan.skipped.push_back(entry.path().string() + ": numbered beyond what slamd can count on from (" +
                             std::to_string(kMaxFileNumber) + "); rename it to resume from it");
      continue;
    }
    if (n == 0) continue;
    std::error_code ec;
    const fs::file_type type = entry.symlink_status(ec).type();  // a symlink is not followed
    if (type != fs::file_type::regular) {
      if (checkpoint) scan.skipped.push_back(entry.path().string() + ": " + kind_of(type) + ", not a checkpoint file");
      continue;
    }
    (checkpoint ? files : corrupt).emplace_back(n, entry.path().string());
  }
  // By number, not by name: a file renamed by hand ("checkpoint-5.vslam") or a number of more than
  // twelve digits would sort out of order, and rotation would delete the newest.
  std::sort(files.begin(), files.end());
  std::sort(corrupt.begin(), corrupt.end());
  for (auto& f : files) scan.files.push_back(std::move(f.second));
  for (auto& f : corrupt) scan.corrupt.push_back(std::move(f.second));
  return scan;
}

CheckpointStore::~CheckpointStore() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock
}

std::vector<std::string> CheckpointStore::list() const { return scan().files; }

std::string CheckpointStore::write(uint64_t sequence, std::span<const uint8_t> payload) {
  const std::string path = (fs::path(directory_) / file_name(next_number_)).string();
  write_checkpoint_file(path, sequence, payload);
  ++next_number_;  // after success: a failed write leaves no file, and its number is reused
  // The newest `keep` checkpoints stay, and as many of the files set aside as corrupt (kept for
  // inspection, but not for ever: each start after a crash in a write could add one).
  Scan files = scan();
  for (auto* list : {&files.files, &files.corrupt}) {
    for (std::size_t i = 0; i + static_cast<std::size_t>(keep_) < list->size(); ++i) {
      std::error_code ec;
      fs::remove((*list)[i], ec);
    }
  }
  return path;
}

std::optional<Checkpoint> CheckpointStore::load_newest(std::vector<std::string>* problems,
                                                        const std::function<void(const Checkpoint&)>& use) {
  const Scan found = scan();
  // Entries named like checkpoints that are not (a directory, a FIFO, a symlink, a number beyond
  // counting): never read, but named, so that the newest one being skipped is not silent.
  if (problems) problems->insert(problems->end(), found.skipped.begin(), found.skipped.end());
  const auto& files = found.files;
  for (auto it = files.rbegin(); it != files.rend(); ++it) {
    Checkpoint cp;
    try {
      cp = read_checkpoint(*it);
    } catch (const CheckpointError& e) {
      if (e.kind() != CheckpointError::Kind::kCorrupt) throw;
      if (problems) problems->push_back(e.what());
      std::error_code ec;
      fs::rename(*it, *it + ".corrupt", ec);  // keep it for inspection, out of the rotation
      continue;
    }
    if (use) {
      try {
        use(cp);
      } catch (const std::exception& e) {
        fail(*it, e.what(), CheckpointError::Kind::kUnusable);
      }
    }
    return cp;
  }
  return std::nullopt;
}

}  // namespace whiskeye::slamd
