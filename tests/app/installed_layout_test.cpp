// idmpc as installed: <prefix>/bin/idmpc finds its data in <prefix>/share/idmpc without any
// setting, from any working directory; without it, --data-dir or IDMPC_DATA_DIR say where, and a
// missing data directory is one error line saying how to set it.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/command.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

using Result = test::CommandResult;
using test::quote;
using test::slurp;

// a prefix holding a copy of the idmpc binary in bin/ and, unless removed, share/idmpc/mjcf
class InstalledLayout : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path tmp = fs::temp_directory_path() / ("idmpc_installed_layout_test_" + std::to_string(::getpid()));
    fs::remove_all(tmp);
    fs::create_directories(tmp / "bin");
    fs::create_directories(tmp / "work");
    prefix_ = fs::canonical(tmp);  // as the running executable sees itself
    fs::copy_file(IDMPC_BINARY, prefix_ / "bin/idmpc");
    fs::create_directories(prefix_ / "share/idmpc");
    fs::copy(fs::path(IDMPC_SOURCE_DIR) / "mjcf", prefix_ / "share/idmpc/mjcf", fs::copy_options::recursive);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(prefix_);
    else std::printf("kept %s for inspection\n", prefix_.c_str());
  }
  // runs the copied idmpc from a directory outside the sources with IDMPC_DATA_DIR unset
  // unless `env` sets it
  Result idmpc(const std::string& args, const std::string& env = "") {
    return test::run_command("env -u IDMPC_DATA_DIR " + env + " " + quote((prefix_ / "bin/idmpc").string()) + " " + args,
                             prefix_ / "work");
  }
  fs::path prefix_;
};

// a run that completed: 0 (reached) or 2 (not reached in so short a run)
bool completed(const Result& r) { return r.code == 0 || r.code == 2; }

TEST_F(InstalledLayout, SwingupFindsTheSharedDataBesideTheExecutable) {
  const Result r = idmpc("swingup --duration 0.02");
  ASSERT_TRUE(completed(r)) << r.code << ": " << r.err;
  EXPECT_NE(r.out.find((prefix_ / "share/idmpc/mjcf/arm4.xml").string()), std::string::npos) << r.out;
}

TEST_F(InstalledLayout, WithoutDataTheErrorSaysWhereItLookedAndHowToSetIt) {
  fs::remove_all(prefix_ / "share");
  for (const std::string command : {"swingup --duration 0.02", "sweep --tables 12 --duration 0.002"}) {
    const Result r = idmpc(command);
    EXPECT_EQ(r.code, 1) << command << ": " << r.out;
    EXPECT_EQ(r.err, "idmpc: error: idmpc data directory not found: IDMPC_DATA_DIR is not set and '" +
                         (prefix_ / "share/idmpc").string() +
                         "' (beside the executable) has no mjcf/; set IDMPC_DATA_DIR (idmpc: --data-dir) to the "
                         "directory holding mjcf/ (an install's share/idmpc or the source tree)\n")
        << command;
  }
}

TEST_F(InstalledLayout, DataDirOptionAndEnvironmentSayWhereTheDataIs) {
  fs::remove_all(prefix_ / "share");
  const std::string sources = fs::canonical(IDMPC_SOURCE_DIR).string();
  const Result swingup = idmpc("swingup --duration 0.02 --data-dir " + quote(sources));
  ASSERT_TRUE(completed(swingup)) << swingup.code << ": " << swingup.err;
  EXPECT_NE(swingup.out.find(sources + "/mjcf/arm4.xml"), std::string::npos) << swingup.out;
  const Result env = idmpc("swingup --duration 0.02", "IDMPC_DATA_DIR=" + quote(sources));
  ASSERT_TRUE(completed(env)) << env.code << ": " << env.err;
  EXPECT_NE(env.out.find(sources + "/mjcf/arm4.xml"), std::string::npos) << env.out;
  const Result sweep = idmpc("sweep --tables 12 --duration 0.002 --out out --data-dir " + quote(sources));
  EXPECT_EQ(sweep.code, 0) << sweep.err;
  EXPECT_TRUE(fs::exists(prefix_ / "work/out/sweep.md")) << sweep.out;
}

TEST_F(InstalledLayout, ADataDirWithoutMjcfIsOneErrorLineNamingIt) {
  const std::string missing = (prefix_ / "missing").string();
  for (const std::string command : {"swingup --duration 0.02", "sweep --tables 12 --duration 0.002"}) {
    const Result r = idmpc(command + " --data-dir " + quote(missing));
    EXPECT_EQ(r.code, 1) << command;
    EXPECT_EQ(r.err, "idmpc: error: --data-dir: data directory '" + missing +
                         "': expected a directory holding mjcf/ (an install's share/idmpc or the source tree), "
                         "got none there\n")
        << command;
  }
}

}  // namespace
}  // namespace idmpc
