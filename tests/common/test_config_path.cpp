// Where programs find the default configs they were not given (common/config_path.h): the installed
// config directory of their prefix, the source tree from a build tree, never the working directory.
#include "whiskeye/common/config_path.h"

#include "scratch.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <stdexcept>

namespace whiskeye {
namespace {

namespace fs = std::filesystem;
using Dirs = std::vector<fs::path>;

void touch(const fs::path& p) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << "robot: {}\n";
}

TEST(ConfigSearchDirs, TheUsrPrefixLooksInEtcAsTheDebInstallsThere) {
  EXPECT_EQ(config_search_dirs("/usr/bin/vita-sim", "/src/build", "/src"), Dirs{"/etc/whiskeye"});
}

TEST(ConfigSearchDirs, AnyOtherPrefixLooksInItsOwnEtc) {
  EXPECT_EQ(config_search_dirs("/usr/local/bin/vita-sim", "/src/build", "/src"), Dirs{"/usr/local/etc/whiskeye"});
  EXPECT_EQ(config_search_dirs("/opt/whiskeye/bin/vita-sim", "/src/build", "/src"), Dirs{"/opt/whiskeye/etc/whiskeye"});
}

TEST(ConfigSearchDirs, AProgramInItsBuildTreeAlsoLooksInTheSourceTree) {
  EXPECT_EQ(config_search_dirs("/src/build/bin/vita-sim", "/src/build", "/src"),
            (Dirs{"/src/build/etc/whiskeye", "/src/config"}));
  EXPECT_EQ(config_search_dirs("/src/build/tests/common/test_common", "/src/build/", "/src"),
            (Dirs{"/src/build/tests/etc/whiskeye", "/src/config"}));
}

TEST(ConfigSearchDirs, ABuildTreeIsMatchedByWholeFolderNames) {
  // build-release/ is not inside build/: a program of another build tree, or installed, never reads
  // this build's source tree.
  EXPECT_EQ(config_search_dirs("/src/build-release/bin/vita-sim", "/src/build", "/src"),
            Dirs{"/src/build-release/etc/whiskeye"});
}

TEST(FindConfig, FindsTheInstalledConfigOfASimulatedPrefix) {
  const fs::path prefix = fs::path(testing::scratch_dir("config_path_install")) / "opt";
  touch(prefix / "etc/whiskeye/robot.yaml");
  const Dirs dirs = config_search_dirs(prefix / "bin/vita-sim", "/nonexistent/build", "/nonexistent");
  EXPECT_EQ(find_config("robot.yaml", dirs, "--robot"), prefix / "etc/whiskeye/robot.yaml");
}

TEST(FindConfig, TheFirstFolderHoldingTheFileWins) {
  const fs::path root = testing::scratch_dir("config_path_order");
  touch(root / "a/slam.yaml");
  touch(root / "b/slam.yaml");
  touch(root / "b/robot.yaml");
  const Dirs dirs{root / "a", root / "b"};
  EXPECT_EQ(find_config("slam.yaml", dirs, "--slam-config"), root / "a/slam.yaml");
  EXPECT_EQ(find_config("robot.yaml", dirs, "--robot"), root / "b/robot.yaml");
}

TEST(FindConfig, NoFileNamesEveryPathTriedAndTheOptionThatGivesOne) {
  const fs::path root = testing::scratch_dir("config_path_missing");
  fs::create_directories(root / "a/robot.yaml");  // a folder of that name is no config
  try {
    find_config("robot.yaml", {root / "a", root / "b"}, "--robot");
    FAIL() << "no robot.yaml exists";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "no default robot.yaml: tried " + (root / "a/robot.yaml").string() + ", " +
                                         (root / "b/robot.yaml").string() + "; give one with --robot");
  }
}

// Restores the working directory when the test ends.
struct ChangeDir {
  fs::path old = fs::current_path();
  explicit ChangeDir(const fs::path& to) { fs::current_path(to); }
  ~ChangeDir() { fs::current_path(old); }
};

TEST(DefaultConfigPath, FromAnotherWorkingDirectoryABuildTreeProgramFindsTheSourceTreesConfig) {
  // A config/ in the working directory, as the old cwd-relative default would have read.
  const fs::path elsewhere = testing::scratch_dir("config_path_cwd");
  touch(elsewhere / "config/robot.yaml");
  const ChangeDir cd(elsewhere);
  const fs::path found = default_config_path("robot.yaml", "--robot");
  EXPECT_TRUE(found.is_absolute()) << found;
  EXPECT_TRUE(fs::equivalent(found, fs::path(WHISKEYE_SOURCE_DIR) / "config/robot.yaml")) << found;
}

TEST(DefaultConfigPath, AConfigThatNoFolderHoldsIsAnErrorNamingThePathsTried) {
  try {
    default_config_path("no-such-config.yaml", "--no-such");
    FAIL() << "no-such-config.yaml exists nowhere";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/etc/whiskeye/no-such-config.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find(WHISKEYE_SOURCE_DIR "/config/no-such-config.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("give one with --no-such"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace whiskeye
