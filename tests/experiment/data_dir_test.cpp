// The data directory: set in the process, by IDMPC_DATA_DIR, or found beside the executable
// (here the build tree's share/idmpc, a link to the sources' mjcf/); a wrong setting is an
// error naming it and saying how to set it, never a silent fallback.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/experiment/task.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

// a fresh directory, and neither the process setting nor IDMPC_DATA_DIR set, for each test
class DataDir : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path tmp = fs::temp_directory_path() / ("idmpc_data_dir_test_" + std::to_string(::getpid()));
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    dir_ = fs::canonical(tmp);  // as shipped_mjcf_path names files
    set_data_dir("");
    ::unsetenv(kDataDirVariable);
  }
  void TearDown() override {
    set_data_dir("");
    ::unsetenv(kDataDirVariable);
    fs::remove_all(dir_);
  }
  // a directory holding an mjcf/ with the paper's task
  fs::path data_dir_named(const std::string& name) {
    const fs::path d = dir_ / name;
    fs::create_directories(d / "mjcf");
    fs::copy_file(fs::path(IDMPC_SOURCE_DIR) / "mjcf/paper_swingup.json", d / "mjcf/paper_swingup.json");
    return d;
  }
  fs::path dir_;
};

std::string message_of(void (*f)()) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST_F(DataDir, WithoutSettingsIsTheBuildTreesLinkToTheSources) {
  const fs::path found = data_dir();
  EXPECT_TRUE(fs::equivalent(found / "mjcf", fs::path(IDMPC_SOURCE_DIR) / "mjcf")) << found;
  // files named by their place in the sources, not through the build tree's link
  const fs::path sources = fs::canonical(IDMPC_SOURCE_DIR);
  EXPECT_EQ(paper_task_path(), (sources / "mjcf/paper_swingup.json").string());
  EXPECT_EQ(paper_tables_path(), (sources / "mjcf/paper_tables.json").string());
}

TEST_F(DataDir, TheEnvironmentSetsIt) {
  const fs::path d = data_dir_named("env");
  ::setenv(kDataDirVariable, d.c_str(), 1);
  EXPECT_EQ(data_dir(), d.string());
  EXPECT_EQ(paper_task_path(), (d / "mjcf/paper_swingup.json").string());
  EXPECT_EQ(load_task(paper_task_path()).source, (d / "mjcf/paper_swingup.json").string());
}

TEST_F(DataDir, TheProcessSettingComesBeforeTheEnvironmentAndClears) {
  const fs::path env = data_dir_named("env"), set = data_dir_named("set");
  ::setenv(kDataDirVariable, env.c_str(), 1);
  set_data_dir(set.string());
  EXPECT_EQ(data_dir(), set.string());
  set_data_dir("");
  EXPECT_EQ(data_dir(), env.string());
}

TEST_F(DataDir, AnEnvironmentWithoutMjcfIsAnErrorNamingItAndHowToSetIt) {
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  ::setenv(kDataDirVariable, empty.c_str(), 1);
  const std::string m = message_of([] { data_dir(); });
  EXPECT_NE(m.find("IDMPC_DATA_DIR='" + empty.string() + "'"), std::string::npos) << m;
  EXPECT_NE(m.find("holding mjcf/"), std::string::npos) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_THROW(paper_task_path(), std::runtime_error);
}

TEST_F(DataDir, SettingADirectoryWithoutMjcfIsRefusedAndKeepsTheSetting) {
  const fs::path good = data_dir_named("good");
  set_data_dir(good.string());
  const std::string missing = (dir_ / "missing").string();
  try {
    set_data_dir(missing);
    FAIL() << "set_data_dir accepted " << missing;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'" + missing + "'"), std::string::npos) << e.what();
  }
  EXPECT_EQ(data_dir(), good.string());
}

}  // namespace
}  // namespace idmpc
