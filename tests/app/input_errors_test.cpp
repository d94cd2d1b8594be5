// Hostile inputs on the command line: task files nested deep or with values out of range,
// numeric options in forms CLI11 would misread, models that include themselves, device files
// and FIFOs in place of models, task files, includes, trajectories and run logs, directories and
// unreadable files, and models with NaN in the numbers the controller uses. Each is refused at
// once with one short error line naming the file or option; none crashes, hangs or reads gigabytes.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/command.hpp"
#include "support/sanitizers.hpp"
#include "support/test_models.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;
using test::arm2_mjcf;
using test::quote;

const std::string kBinary = std::getenv("IDMPC_TEST_BINARY") ? std::getenv("IDMPC_TEST_BINARY") : IDMPC_BINARY;
const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";

// a command that hangs or reads without end without its fix is killed (exit code 137) after
// this, and its memory is capped (none under AddressSanitizer, which reserves terabytes)
#if IDMPC_TEST_ASAN
const std::string kLimits = "timeout -s KILL 20 ";
#else
const std::string kLimits = "ulimit -v 3000000; timeout -s KILL 20 ";
#endif

class InputErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("idmpc_input_errors_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_ / "locked.xml", fs::perms::owner_all, ec);
    if (!HasFailure()) fs::remove_all(dir_);
    else std::printf("kept %s for inspection\n", dir_.c_str());
  }

  // `idmpc <args>` from the test directory, under the time and memory limits, in a subshell
  // whose output is captured; `shell` runs first, `after` after it
  test::CommandResult idmpc(const std::string& args, const std::string& shell = "", const std::string& after = "") {
    return test::run_command("(" + shell + kLimits + quote(kBinary) + " " + args + after + ")", dir_);
  }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  // exit code 1 and exactly one short "idmpc: error:" line holding every needle
  static void expect_one_line(const test::CommandResult& r, const std::vector<std::string>& needles) {
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_EQ(r.err.rfind("idmpc: error: ", 0), 0u) << r.err.substr(0, 400);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err.substr(0, 400);
    EXPECT_LT(r.err.size(), 400u) << r.err.substr(0, 400);
    for (const std::string& needle : needles) {
      EXPECT_NE(r.err.find(needle), std::string::npos) << "no '" << needle << "' in: " << r.err.substr(0, 400);
    }
  }

  fs::path dir_;
};

// ---------------------------------------------------------------------------------------------
// task files: nesting, long values, integers out of range

TEST_F(InputErrors, DeeplyNestedTaskFileIsRefusedNamingTheDepth) {
  const std::string deep = std::string(100000, '[') + "0" + std::string(100000, ']');
  write("deep.json", R"({"qref": )" + deep + "}");
  expect_one_line(idmpc("swingup --task deep.json"), {"task file 'deep.json'", "100001 levels", "64"});
  // deep where no field is expected, and deep as a reference's waypoints
  write("deep_unknown.json", R"({"whatever": )" + deep + "}");
  expect_one_line(idmpc("swingup --task deep_unknown.json"), {"'deep_unknown.json'", "100001 levels"});
}

TEST_F(InputErrors, LongValuesAreAbbreviatedInErrors) {
  const std::string wide = "[\"" + std::string(60000, 'a') + "\", \"" + std::string(60000, 'b') + "\"]";
  write("wide.json", R"({"qref": [)" + wide + "]}");
  expect_one_line(idmpc("swingup --task wide.json"), {"'wide.json'", "'qref'", "\xE2\x80\xA6"});
  write("word.json", R"({"model": ")" + kArm4 + R"(", "formulation": ")" + std::string(200000, 'f') + R"("})");
  expect_one_line(idmpc("swingup --task word.json"), {"formulation", "\xE2\x80\xA6"});
  write("key.json", "{\"" + std::string(200000, 'k') + "\": 1}");
  expect_one_line(idmpc("swingup --task key.json"), {"unknown field", "\xE2\x80\xA6"});
}

TEST_F(InputErrors, TaskIntegersOutsideIntAreRefusedNotWrapped) {
  // 4294967321 = 2^32 + 25 would run N = 25
  write("wrap.json", R"({"model": ")" + kArm4 + R"(", "q0": [0, 0, 0, 0], "cgmres": {"N": 4294967321}})");
  expect_one_line(idmpc("swingup --task wrap.json --duration 0.002"), {"'wrap.json'", "'N'", "4294967321"});
  write("negative.json", R"({"model": ")" + kArm4 + R"(", "q0": [0, 0, 0, 0], "cgmres": {"kmax": -4294967295}})");
  expect_one_line(idmpc("swingup --task negative.json --duration 0.002"), {"'kmax'", "-4294967295"});
}

TEST_F(InputErrors, HorizonBeyondItsLimitIsRefusedBeforeAllocating) {
  expect_one_line(idmpc("swingup --N 2147483647 --duration 0.002"), {"--N", "10000", "2147483647"});
  write("big.json", R"({"model": ")" + kArm4 + R"(", "q0": [0, 0, 0, 0], "cgmres": {"N": 20000}})");
  expect_one_line(idmpc("swingup --task big.json --duration 0.002"), {"cgmres.N", "10000", "20000"});
}

// ---------------------------------------------------------------------------------------------
// numeric options: decimal only

TEST_F(InputErrors, NumericOptionsRefuseEmptyAndNonDecimalText) {
  // the trial's cases, each form once (every numeric option has the same check)
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"swingup --N 010", "--N"},        {"swingup --kmax 0x10", "--kmax"}, {"swingup --N 0b1", "--N"},
      {"swingup --alpha ''", "--alpha"}, {"swingup --zeta ''", "--zeta"},   {"swingup --qref 0 ''", "--qref"},
      {"swingup --Qq ''", "--Qq"},       {"swingup --Tf 0x1p3", "--Tf"},    {"swingup --R nan", "--R"},
      {"check " + quote(kArm4) + " --seed ''", "--seed"},
      {"sweep --duration '' --out out", "--duration"},
      {"render " + quote(kArm4) + " --log x.csv --out x.mp4 --width 0640", "--width"}};
  for (const auto& [args, option] : cases) {
    SCOPED_TRACE(args);
    // a swing-up that would run is kept short
    expect_one_line(idmpc(args + (args.rfind("swingup", 0) == 0 ? " --duration 0.002" : "")), {option, "decimal"});
  }
}

TEST_F(InputErrors, NumericOptionsAcceptDecimalNumbers) {
  // a run of two control steps: every value parsed as written
  const test::CommandResult r =
      idmpc("swingup --duration 0.002 --N 0 --kmax 10 --Tf 0.5 --alpha 0 --zeta 1e3 --h 1e-8 --qref -0.5 "
            "--Qq 10 --Qv .5 --R 1E-4 --dt +0.001");
  // N 0 passes the option and is refused by the task's limit, naming it
  expect_one_line(r, {"--N (cgmres.N)", "got 0"});
  const test::CommandResult ok = idmpc("swingup --duration 0.002 --N 10 --kmax 2 --Tf 0.5 --zeta 1e3 --qref -0.5");
  EXPECT_NE(ok.code, 1) << ok.err;
  EXPECT_NE(ok.out.find("N = 10, kmax = 2"), std::string::npos) << ok.out;
}

TEST_F(InputErrors, LatencyIsNoneMeasuredOrMilliseconds) {
  for (const std::string bad : {"-1", "fast", "''", "inf", "nan", "1e999", "010"}) {
    SCOPED_TRACE(bad);
    expect_one_line(idmpc("swingup --duration 0.002 --latency " + bad), {"--latency", "got"});
  }
  expect_one_line(idmpc("sweep --out out --latency none,-2"), {"--latency", "'-2'"});
  expect_one_line(idmpc("sweep --out out --latency none,1,1.0"), {"--latency", "'1' twice"});
  // (a non-finite number is no JSON: 1e999 is refused as the file's parse error)
  for (const std::string bad : {"-1", "\"fast\"", "\"\"", "[1]", "\"inf\""}) {
    SCOPED_TRACE(bad);
    write("late.json", R"({"model": ")" + kArm4 + R"(", "q0": [0, 0, 0, 0], "latency": )" + bad + "}");
    expect_one_line(idmpc("swingup --task late.json --duration 0.002"), {"task file 'late.json'", "field 'latency'"});
  }
  const test::CommandResult ok = idmpc("swingup --duration 0.003 --latency 2.5");
  EXPECT_NE(ok.code, 1) << ok.err;
  EXPECT_NE(ok.out.find("compute latency 2.5: 1 update(s) took longer"), std::string::npos) << ok.out;
}

// ---------------------------------------------------------------------------------------------
// models: include cycles, devices, FIFOs, directories, permissions

TEST_F(InputErrors, ModelIncludingItselfIsRefusedAtOnce) {
  std::string includes;
  for (int k = 0; k < 6; ++k) includes += "  <include file=\"self.xml\"/>\n";
  write("self.xml", "<mujoco>\n" + includes + "</mujoco>\n");
  expect_one_line(idmpc("check self.xml"), {"model 'self.xml'", "include cycle", "line 2"});
  // a cycle through a second file
  write("a.xml", "<mujoco>\n  <include file=\"b.xml\"/>\n</mujoco>\n");
  write("b.xml", "<mujoco>\n  <include file=\"a.xml\"/>\n</mujoco>\n");
  expect_one_line(idmpc("check a.xml"), {"model 'a.xml'", "include cycle", "b.xml"});
}

TEST_F(InputErrors, DeviceFilesAreRefusedBeforeReading) {
  const std::string device = "is a character device";
  expect_one_line(idmpc("check /dev/zero"), {"model '/dev/zero'", device});
  write("includes_zero.xml", "<mujoco>\n  <include file=\"/dev/zero\"/>\n</mujoco>\n");
  expect_one_line(idmpc("check includes_zero.xml"), {"'includes_zero.xml'", "'/dev/zero'", device});
  expect_one_line(idmpc("swingup --task /dev/zero"), {"task file '/dev/zero'", device});
  write("zero_model.json", R"({"model": "/dev/zero"})");
  expect_one_line(idmpc("swingup --task zero_model.json"), {"model '/dev/zero'", device});
  write("arm.xml", arm2_mjcf());
  write("zero_reference.json", R"({"model": "arm.xml", "q0": [0, 0], "qref": [0, 0],
                                  "reference": {"shape": "csv", "file": "/dev/zero"}})");
  expect_one_line(idmpc("swingup --task zero_reference.json"), {"trajectory file '/dev/zero'", device});
  const test::CommandResult render = idmpc("render " + quote(kArm4) + " --log /dev/zero --out x.mp4");
  if (render.err.find("built without rendering") == std::string::npos) {
    expect_one_line(render, {"run log '/dev/zero'", device});
  }
}

TEST_F(InputErrors, FifoModelIsRefusedWithoutWaitingForItsWriter) {
  ASSERT_EQ(::mkfifo((dir_ / "fifo.xml").c_str(), 0600), 0);
  // without a writer (an open for reading would block), and with one that never closes it
  expect_one_line(idmpc("check fifo.xml"), {"model 'fifo.xml'", "is a FIFO"});
  const test::CommandResult r =
      idmpc("check fifo.xml", "sleep 60 > fifo.xml & writer=$!; ", "; code=$?; kill $writer; exit $code");
  expect_one_line(r, {"model 'fifo.xml'", "is a FIFO"});
}

TEST_F(InputErrors, DirectoryModelSaysSo) {
  fs::create_directories(dir_ / "d");
  expect_one_line(idmpc("check d"), {"model 'd': is a directory, expected an MJCF or URDF file"});
  expect_one_line(idmpc("swingup d --duration 0.002"), {"model 'd': is a directory"});
}

TEST_F(InputErrors, UnreadableModelSaysPermissionDenied) {
  write("locked.xml", arm2_mjcf());
  fs::permissions(dir_ / "locked.xml", fs::perms::none);
  // root reads any file: as root the command runs as nobody (setpriv, util-linux)
  std::string as_user;
  if (::geteuid() == 0) {
    if (std::system("command -v setpriv > /dev/null") != 0) GTEST_SKIP() << "as root without setpriv: not testable";
    as_user = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  }
  const test::CommandResult r =
      test::run_command("(" + kLimits + as_user + quote(kBinary) + " check locked.xml)", dir_);
  expect_one_line(r, {"model 'locked.xml': permission denied"});
}

// ---------------------------------------------------------------------------------------------
// models with NaN: refused by swingup too, not only warned about by check

TEST_F(InputErrors, SwingupRefusesANonFiniteTorqueRange) {
  write("nan_ctrl.xml", arm2_mjcf("motor0", R"(ctrlrange="nan 1")"));
  expect_one_line(idmpc("swingup nan_ctrl.xml --q0 0 0 --qref 1 1 --duration 0.05"),
                  {"<motor> 'motor0'", "ctrlrange=\"nan 1\"", "nan_ctrl.xml"});
  write("nan_mass.xml", arm2_mjcf("geom0", R"(mass="nan")"));
  expect_one_line(idmpc("swingup nan_mass.xml --q0 0 0 --qref 1 1 --duration 0.05"),
                  {"<geom> 'geom0'", "mass=\"nan\"", "nan_mass.xml"});
}

}  // namespace
}  // namespace idmpc
