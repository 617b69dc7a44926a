#include "whiskeye/slamd/checkpoint_store.h"
#include "scratch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <sys/stat.h>

namespace whiskeye::slamd {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class CheckpointStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = whiskeye::testing::scratch_dir("cp_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  static std::vector<uint8_t> payload(int n, uint8_t seed) {
    std::vector<uint8_t> p(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(i)] = static_cast<uint8_t>(seed + i * 7);
    return p;
  }
  static void corrupt_byte(const std::string& path, long offset) {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(offset);
    char c = 0;
    f.read(&c, 1);
    c = static_cast<char>(c ^ 0x5a);
    f.seekp(offset);
    f.write(&c, 1);
  }
  // A checkpoint file written by hand: `version` 1 is the old format, 3 a newer slamd's.
  static void write_raw(const std::string& path, uint64_t sequence, const std::vector<uint8_t>& p, uint32_t version) {
    std::vector<uint8_t> bytes = checkpoint_header(sequence, p, version);
    bytes.insert(bytes.end(), p.begin(), p.end());
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                static_cast<std::streamsize>(bytes.size()));
  }
  fs::path dir_;
};

TEST_F(CheckpointStoreTest, WritesAndReadsBackExactly) {
  CheckpointStore store(dir_.string(), 3);
  const auto p = payload(10000, 3);
  const std::string path = store.write(42, p);
  const Checkpoint cp = read_checkpoint(path);
  EXPECT_EQ(cp.sequence, 42u);
  EXPECT_EQ(cp.payload, p);
  std::vector<std::string> problems;
  const auto newest = store.load_newest(&problems);
  ASSERT_TRUE(newest);
  EXPECT_EQ(newest->payload, p);
  EXPECT_TRUE(problems.empty());
}

TEST_F(CheckpointStoreTest, KeepsOnlyTheNewestAndLeavesNoTempFiles) {
  CheckpointStore store(dir_.string(), 2);
  for (uint64_t s = 1; s <= 5; ++s) store.write(s, payload(100, static_cast<uint8_t>(s)));
  const auto files = store.list();
  ASSERT_EQ(files.size(), 2u);
  EXPECT_THAT(files[0], HasSubstr("checkpoint-000000000004.vslam"));
  EXPECT_THAT(files[1], HasSubstr("checkpoint-000000000005.vslam"));
  int others = 0;
  for (const auto& e : fs::directory_iterator(dir_)) others += e.path().extension() != ".vslam";
  EXPECT_EQ(others, 0);
}

TEST_F(CheckpointStoreTest, CorruptNewestFallsBackToPreviousAndNamesTheFile) {
  CheckpointStore store(dir_.string(), 3);
  store.write(1, payload(500, 1));
  const std::string newest = store.write(2, payload(500, 2));
  corrupt_byte(newest, 100);  // inside the payload
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->sequence, 1u);
  EXPECT_EQ(cp->payload, payload(500, 1));
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_THAT(problems[0], HasSubstr(newest + ": checksum mismatch"));
  EXPECT_TRUE(fs::exists(newest + ".corrupt")) << "the bad file is kept for inspection";
}

TEST_F(CheckpointStoreTest, RejectsTruncatedBadMagicAndFutureVersion) {
  CheckpointStore store(dir_.string(), 3);
  const std::string path = store.write(7, payload(64, 9));
  fs::resize_file(path, fs::file_size(path) - 1);
  EXPECT_THROW(
      {
        try {
          read_checkpoint(path);
        } catch (const CheckpointError& e) {
          EXPECT_THAT(e.what(), HasSubstr("truncated or appended"));
          throw;
        }
      },
      CheckpointError);
  const std::string p2 = store.write(8, payload(64, 9));
  corrupt_byte(p2, 0);
  try {
    read_checkpoint(p2);
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad magic"));
  }
  const std::string p3 = (dir_ / "checkpoint-000000000009.vslam").string();
  write_raw(p3, 9, payload(64, 9), 3);  // intact, from a newer slamd
  try {
    read_checkpoint(p3);
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_EQ(e.kind(), CheckpointError::Kind::kUnusable);
    EXPECT_THAT(e.what(), HasSubstr("unsupported checkpoint format version 3"));
  }
  std::ofstream(dir_ / "checkpoint-000000000010.vslam") << "short";
  try {
    read_checkpoint((dir_ / "checkpoint-000000000010.vslam").string());
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_THAT(e.what(), HasSubstr("truncated header"));
  }
}

// One flipped bit in the version field stopped slamd ("unsupported checkpoint format version 17")
// although older good checkpoints were there; a flipped sequence was taken silently. The checksum
// now covers the header: both are damage, and the previous checkpoint is used.
TEST_F(CheckpointStoreTest, AFlippedBitInTheHeaderIsDamageAndThePreviousCheckpointIsUsed) {
  CheckpointStore store(dir_.string(), 3);
  store.write(1, payload(300, 1));
  const std::string middle = store.write(2, payload(300, 2));
  const std::string newest = store.write(3, payload(300, 3));
  corrupt_byte(newest, 8);   // version
  corrupt_byte(middle, 17);  // sequence
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->sequence, 1u);
  EXPECT_EQ(cp->payload, payload(300, 1));
  ASSERT_EQ(problems.size(), 2u);
  EXPECT_THAT(problems[0], HasSubstr(newest + ": checksum mismatch (corrupt header or data)"));
  EXPECT_THAT(problems[1], HasSubstr(middle + ": checksum mismatch"));
  EXPECT_TRUE(fs::exists(newest + ".corrupt"));
}

TEST_F(CheckpointStoreTest, AFormatOneCheckpointIsStillRead) {
  fs::create_directories(dir_);
  const std::string path = (dir_ / "checkpoint-000000000004.vslam").string();
  write_raw(path, 44, payload(100, 4), 1);
  const Checkpoint cp = read_checkpoint(path);
  EXPECT_EQ(cp.sequence, 44u);
  EXPECT_EQ(cp.payload, payload(100, 4));
  corrupt_byte(path, 60);
  EXPECT_THROW(read_checkpoint(path), CheckpointError);
}

TEST_F(CheckpointStoreTest, TheLastWrittenIsTheNewestAcrossRestartsWhateverItsSequence) {
  {
    CheckpointStore store(dir_.string(), 2);
    for (uint64_t s = 10; s <= 12; ++s) store.write(s, payload(50, static_cast<uint8_t>(s)));
  }
  // A restart that begins a new map (cycle 1) or resumes: its checkpoints come after the old ones.
  CheckpointStore store(dir_.string(), 2);
  const std::string path = store.write(1, payload(50, 99));
  const auto files = store.list();
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files.back(), path) << "the file just written is never the one rotated out";
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->sequence, 1u);
  EXPECT_EQ(cp->payload, payload(50, 99));
}

TEST_F(CheckpointStoreTest, FilesAreOrderedByTheirNumberNotTheirName) {
  {
    CheckpointStore store(dir_.string(), 3);
    store.write(5, payload(50, 5));
  }
  // The operator puts an older map back by the name the docs give (checkpoint-<n>.vslam).
  fs::rename(dir_ / "checkpoint-000000000001.vslam", dir_ / "checkpoint-7.vslam");
  CheckpointStore store(dir_.string(), 1);
  const std::string path = store.write(8, payload(50, 8));
  EXPECT_EQ(fs::path(path).filename(), "checkpoint-000000000008.vslam");
  ASSERT_EQ(store.list(), std::vector<std::string>{path}) << "the file just written is kept, the older rotated out";
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->sequence, 8u);
}

TEST_F(CheckpointStoreTest, AnIntactButUnusableNewestIsNamedAndKeptNotSkipped) {
  CheckpointStore store(dir_.string(), 3);
  store.write(1, payload(64, 1));
  const std::string newest = store.write(2, payload(64, 2));
  std::vector<std::string> problems;
  try {
    store.load_newest(&problems, [](const Checkpoint&) { throw std::runtime_error("written in another mode"); });
    FAIL() << "an unusable checkpoint must not be passed over";
  } catch (const CheckpointError& e) {
    EXPECT_EQ(e.kind(), CheckpointError::Kind::kUnusable);
    EXPECT_THAT(e.what(), HasSubstr(newest + ": written in another mode"));
  }
  EXPECT_TRUE(fs::exists(newest)) << "not renamed: it is not corrupt";
  write_raw(newest, 2, payload(64, 2), 3);  // intact, in a format version this slamd does not read
  try {
    store.load_newest(&problems);
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_EQ(e.kind(), CheckpointError::Kind::kUnusable);
    EXPECT_THAT(e.what(), HasSubstr("unsupported checkpoint format version"));
  }
  EXPECT_TRUE(fs::exists(newest));
  EXPECT_TRUE(problems.empty());
}

TEST_F(CheckpointStoreTest, TempFilesOfAnInterruptedWriteAreRemovedOnStart) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / ".checkpoint-000000000007.vslam.tmp") << "half a checkpoint";
  std::ofstream(dir_ / "notes.txt") << "not ours";
  CheckpointStore store(dir_.string(), 3);
  ASSERT_EQ(store.removed_temp_files().size(), 1u);
  EXPECT_THAT(store.removed_temp_files()[0], HasSubstr(".checkpoint-000000000007.vslam.tmp"));
  EXPECT_FALSE(fs::exists(dir_ / ".checkpoint-000000000007.vslam.tmp"));
  EXPECT_TRUE(fs::exists(dir_ / "notes.txt"));
}

// Two slamd on one state directory would take each other's temp files for unfinished writes and
// rotate each other's checkpoints out (one map lost): the second is refused, naming the directory.
TEST_F(CheckpointStoreTest, OneStoreAtATimeOwnsADirectory) {
  std::string written;
  {
    CheckpointStore first(dir_.string(), 1);
    written = first.write(1, payload(20, 1));
    try {
      CheckpointStore second(dir_.string(), 1);
      FAIL() << "a second store on the same directory";
    } catch (const CheckpointError& e) {
      EXPECT_EQ(e.kind(), CheckpointError::Kind::kUnusable);
      EXPECT_THAT(e.what(), HasSubstr(dir_.string() + ": in use by another slamd"));
    }
    EXPECT_EQ(first.list(), std::vector<std::string>{written}) << "the refused one touched nothing";
  }
  CheckpointStore after(dir_.string(), 1);  // released with the first
  EXPECT_EQ(after.list(), std::vector<std::string>{written});
}

TEST_F(CheckpointStoreTest, OnlyARegularFileIsReadAndNotBeyondWhatItsHeaderSays) {
  try {
    read_checkpoint("/dev/zero");  // --map /dev/zero: refused before reading a byte
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_EQ(e.kind(), CheckpointError::Kind::kUnusable);
    EXPECT_THAT(e.what(), HasSubstr("/dev/zero: not a regular file"));
  }
  fs::create_directories(dir_);
  EXPECT_THROW(read_checkpoint(dir_.string()), CheckpointError);
  // A header claiming an enormous payload: refused by the file's size, nothing allocated for it.
  const std::string path = (dir_ / "huge.vslam").string();
  write_checkpoint_file(path, 1, payload(40, 3));
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(24);
    const char huge[8] = {0, 0, 0, 0, 0, 0, 0, 0x40};  // 2^62 bytes
    f.write(huge, sizeof huge);
  }
  try {
    read_checkpoint(path);
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_EQ(e.kind(), CheckpointError::Kind::kCorrupt);
    EXPECT_THAT(e.what(), HasSubstr("payload size 40 differs from the header's 4611686018427387904"));
  }
}

TEST_F(CheckpointStoreTest, AFileNumberedBeyondCountingIsNamedAndNotCountedFrom) {
  fs::create_directories(dir_);
  write_checkpoint_file((dir_ / "checkpoint-18446744073709551615.vslam").string(), 9, payload(10, 9));
  write_checkpoint_file((dir_ / "checkpoint-99999999999999999999999.vslam").string(), 9, payload(10, 9));
  CheckpointStore store(dir_.string(), 1);
  std::vector<std::string> problems;
  EXPECT_FALSE(store.load_newest(&problems));
  ASSERT_EQ(problems.size(), 2u) << "each is named, not skipped silently";
  for (const auto& p : problems) EXPECT_THAT(p, HasSubstr("numbered beyond what slamd can count on from"));
  const std::string path = store.write(1, payload(10, 1));
  EXPECT_EQ(fs::path(path).filename(), "checkpoint-000000000001.vslam") << "the next number did not wrap";
  EXPECT_EQ(store.list(), std::vector<std::string>{path}) << "the file just written is kept";
  EXPECT_TRUE(fs::exists(dir_ / "checkpoint-18446744073709551615.vslam")) << "not ours: left alone";
}

// A file numbered beyond 10^15 was invisible: never pruned, and the next start resumed an older
// state beside it (silent loss). Any number slamd can count on from is a checkpoint like the others.
TEST_F(CheckpointStoreTest, AFileNumberedBeyondTenToTheFifteenIsResumedCountedFromAndPruned) {
  fs::create_directories(dir_);
  const std::string big = (dir_ / "checkpoint-1000000000000005.vslam").string();
  write_checkpoint_file((dir_ / "checkpoint-000000000007.vslam").string(), 7, payload(10, 7));
  write_checkpoint_file(big, 8, payload(10, 8));
  CheckpointStore store(dir_.string(), 2);
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->path, big);
  EXPECT_EQ(cp->sequence, 8u);
  EXPECT_TRUE(problems.empty());
  const std::string next = store.write(9, payload(10, 9));
  EXPECT_EQ(fs::path(next).filename(), "checkpoint-1000000000000006.vslam");
  EXPECT_EQ(store.list(), (std::vector<std::string>{big, next})) << "the older file was pruned";
  store.write(10, payload(10, 10));
  EXPECT_FALSE(fs::exists(big)) << "pruned in its turn";
}

TEST_F(CheckpointStoreTest, ANewestCheckpointThatIsNotARegularFileIsNamedAndSkipped) {
  fs::create_directories(dir_);
  write_checkpoint_file((dir_ / "checkpoint-000000000001.vslam").string(), 1, payload(10, 1));
  fs::create_directory(dir_ / "checkpoint-000000000002.vslam");
  ASSERT_EQ(::mkfifo((dir_ / "checkpoint-000000000003.vslam").c_str(), 0600), 0);
  write_checkpoint_file((dir_ / "elsewhere.vslam").string(), 4, payload(10, 4));
  fs::create_symlink(dir_ / "elsewhere.vslam", dir_ / "checkpoint-000000000004.vslam");
  CheckpointStore store(dir_.string(), 3);
  std::vector<std::string> problems;
  const auto cp = store.load_newest(&problems);
  ASSERT_TRUE(cp);
  EXPECT_EQ(cp->sequence, 1u);
  ASSERT_EQ(problems.size(), 3u);
  const std::string all = problems[0] + "\n" + problems[1] + "\n" + problems[2];
  EXPECT_THAT(all, HasSubstr("checkpoint-000000000002.vslam: a directory, not a checkpoint file"));
  EXPECT_THAT(all, HasSubstr("checkpoint-000000000003.vslam: a FIFO, not a checkpoint file"));
  EXPECT_THAT(all, HasSubstr("checkpoint-000000000004.vslam: a symbolic link, not a checkpoint file"));
  const std::string next = store.write(5, payload(10, 5));
  EXPECT_EQ(fs::path(next).filename(), "checkpoint-000000000005.vslam") << "counted on past them";
  store.write(6, payload(10, 6));
  store.write(7, payload(10, 7));
  EXPECT_TRUE(fs::is_directory(dir_ / "checkpoint-000000000002.vslam")) << "not ours to remove";
  EXPECT_TRUE(fs::exists(dir_ / "elsewhere.vslam")) << "a link is never followed";
}

TEST_F(CheckpointStoreTest, FilesSetAsideAsCorruptArePrunedLikeCheckpoints) {
  fs::create_directories(dir_);
  for (int n = 1; n <= 4; ++n) {
    std::ofstream(dir_ / ("checkpoint-00000000000" + std::to_string(n) + ".vslam.corrupt")) << "damaged";
  }
  CheckpointStore store(dir_.string(), 2);
  store.write(1, payload(10, 1));
  int corrupt = 0;
  for (const auto& e : fs::directory_iterator(dir_)) corrupt += e.path().extension() == ".corrupt";
  EXPECT_EQ(corrupt, 2);
  EXPECT_TRUE(fs::exists(dir_ / "checkpoint-000000000004.vslam.corrupt")) << "the newest are kept";
  EXPECT_TRUE(fs::exists(dir_ / "checkpoint-000000000003.vslam.corrupt"));
}

TEST_F(CheckpointStoreTest, NothingValidMeansNoCheckpoint) {
  CheckpointStore store(dir_.string(), 3);
  std::vector<std::string> problems;
  EXPECT_FALSE(store.load_newest(&problems));
  const std::string path = store.write(1, payload(10, 1));
  corrupt_byte(path, 40);
  EXPECT_FALSE(store.load_newest(&problems));
  EXPECT_EQ(problems.size(), 1u);
}

TEST_F(CheckpointStoreTest, UnwritableDirectoryIsAnErrorNamingIt) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "file") << "x";
  try {
    CheckpointStore store((dir_ / "file" / "sub").string(), 3);
    FAIL();
  } catch (const CheckpointError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot create the checkpoint directory"));
  }
}

}  // namespace
}  // namespace whiskeye::slamd
