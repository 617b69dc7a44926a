// Log lines with their journal priority (common/log.h).
#include "whiskeye/common/log.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace whiskeye {
namespace {

TEST(LogLine, ForTheJournalStartsWithTheSyslogPriority) {
  EXPECT_EQ(format_log_line(LogLevel::kError, "slamd: bad config", true), "<3>slamd: bad config\n");
  EXPECT_EQ(format_log_line(LogLevel::kWarning, "slamd: rejected", true), "<4>slamd: rejected\n");
  EXPECT_EQ(format_log_line(LogLevel::kNotice, "based: state ok", true), "<5>based: state ok\n");
  EXPECT_EQ(format_log_line(LogLevel::kInfo, "slamd: running", true), "<6>slamd: running\n");
}

TEST(LogLine, ElsewhereIsPlainText) {
  EXPECT_EQ(format_log_line(LogLevel::kWarning, "slamd: rejected", false), "slamd: rejected\n");
  EXPECT_EQ(format_log_line(LogLevel::kError, "", false), "\n");
}

TEST(LogLine, EveryLineOfAMultiLineMessageCarriesThePriority) {
  EXPECT_EQ(format_log_line(LogLevel::kWarning, "a\nb", true), "<4>a\n<4>b\n");
  EXPECT_EQ(format_log_line(LogLevel::kWarning, "a\nb\n", true), "<4>a\n<4>b\n") << "one trailing newline ends it";
  EXPECT_EQ(format_log_line(LogLevel::kWarning, "a\nb\n", false), "a\nb\n");
}

class JournalStream : public ::testing::Test {
 protected:
  void SetUp() override {
    char name[] = "/tmp/whiskeye-test-log-XXXXXX";
    fd_ = mkstemp(name);
    ASSERT_GE(fd_, 0);
    path_ = name;
    struct stat st {};
    ASSERT_EQ(fstat(fd_, &st), 0);
    dev_ino_ = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  }
  void TearDown() override {
    close(fd_);
    unlink(path_.c_str());
  }
  int fd_ = -1;
  std::string path_;
  std::string dev_ino_;
};

TEST_F(JournalStream, IsTheJournalOnlyWhenTheVariableNamesThatFile) {
  EXPECT_TRUE(is_journal_stream(dev_ino_.c_str(), fd_));
  EXPECT_FALSE(is_journal_stream(nullptr, fd_)) << "not under systemd";
  EXPECT_FALSE(is_journal_stream("", fd_));
  EXPECT_FALSE(is_journal_stream("garbage", fd_));
  EXPECT_FALSE(is_journal_stream((dev_ino_ + "x").c_str(), fd_));
  const int other = open("/dev/null", O_WRONLY);
  ASSERT_GE(other, 0);
  EXPECT_FALSE(is_journal_stream(dev_ino_.c_str(), other)) << "stderr redirected away from the journal";
  close(other);
}

}  // namespace
}  // namespace whiskeye
