// Hostile inputs to the command line that used to pass as something else: boolean options given
// '' or -1 (read as false), an empty --arms-tasks (read as the shipped list), one task listed
// under two spellings of its path (run twice), work-precision kmax values beyond int (wrapped) or
// listed twice (an internal error), a sweep cell's record that is a FIFO or a device (a hang, or
// gigabytes read), an error of a cell glued onto its progress line, a cell refused beside a serial
// sweep that still made cells/, and the log temporary a killed `--cell --logs` left. Each is one
// error line naming the option, file or field, exit code 1, or a directory left clean.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/command.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;
using test::lines_of;
using test::quote;
using test::split;

const std::string kBinary = std::getenv("IDMPC_TEST_BINARY") ? std::getenv("IDMPC_TEST_BINARY") : IDMPC_BINARY;
const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
// a command that hangs or reads without end is killed (exit code 137)
const std::string kTimeout = "timeout -s KILL 20 ";
// Table 3 (8 cells), 10 control steps per run
const std::string kSweep = "sweep --tables 3 --duration 0.01 --out out";

class HostileCli : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("idmpc_hostile_cli_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
    else std::printf("kept %s for inspection\n", dir_.c_str());
  }

  test::CommandResult idmpc(const std::string& args) {
    return test::run_command("(" + kTimeout + quote(kBinary) + " " + args + ")", dir_);
  }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p;
  }

  std::vector<std::string> cell_ids(const std::string& args) {
    const test::CommandResult r = idmpc(args + " --list-cells");
    EXPECT_EQ(r.code, 0) << r.err;
    std::vector<std::string> ids;
    for (const std::string& line : lines_of(r.out)) ids.push_back(split(line, '\t').front());
    return ids;
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

TEST_F(HostileCli, BooleanOptionsTakeTrueOrFalse) {
  for (const char* value : {"''", "-1", "on", "1", "yes"}) {
    expect_one_line(idmpc(std::string("swingup --duration 0.002 --offset-free ") + value),
                    {"--offset-free", "expected true or false"});
    expect_one_line(idmpc(std::string("swingup --duration 0.002 --init-full-horizon ") + value),
                    {"--init-full-horizon", "expected true or false"});
  }
  const test::CommandResult r = idmpc("swingup --duration 0.002 --offset-free false --init-full-horizon false");
  EXPECT_TRUE(r.code == 0 || r.code == 2) << r.err;
}

TEST_F(HostileCli, AnEmptyArmsTasksIsRefused) {
  expect_one_line(idmpc("sweep --arms-tasks '' --list-cells"), {"--arms-tasks", "''"});
}

TEST_F(HostileCli, ATaskListedUnderTwoSpellingsIsRefused) {
  write("mine.json", R"({"model": ")" + kArm4 + R"(", "q0": [0, 0, 0, 0], "qref": [0.1, 0, 0, 0], "duration": 0.01})");
  fs::create_directories(dir_ / "sub");
  fs::create_symlink("mine.json", dir_ / "link.json");
  write("one.json", R"({"tasks": ["mine.json"]})");
  EXPECT_EQ(cell_ids("sweep --arms-tasks one.json").size(), 2u);
  for (const char* other : {"./mine.json", "sub/../mine.json", "link.json"}) {
    write("list.json", std::string(R"({"tasks": ["mine.json", ")") + other + "\"]}");
    expect_one_line(idmpc("sweep --arms-tasks list.json --list-cells"), {"'list.json'", other, "twice", "'mine.json'"});
  }
}

TEST_F(HostileCli, WorkPrecisionKmaxValuesAreIntegersInRangeListedOnce) {
  fs::create_directories(dir_ / "m");
  fs::copy_file(kArm4, dir_ / "m" / "arm4.xml");
  const std::string sweep = "sweep --tables work-precision --models m --list-cells";
  auto grid = [&](const std::string& models, const std::string& kmax) {
    write("m/work_precision.json", R"({"models": )" + models + R"(, "tasks": [], "kmax": )" + kmax + "}");
  };
  grid(R"(["arm4.xml"])", "[1, 10]");
  EXPECT_EQ(cell_ids("sweep --tables work-precision --models m").size(), 4u);
  // 2^32 + 10 ran as kmax 10
  grid(R"(["arm4.xml"])", "[4294967306]");
  expect_one_line(idmpc(sweep), {"work_precision.json", "'kmax'", "4294967306"});
  grid(R"(["arm4.xml"])", "[-4294967286]");
  expect_one_line(idmpc(sweep), {"'kmax'", "-4294967286"});
  grid(R"(["arm4.xml"])", R"(["10"])");
  const test::CommandResult text = idmpc(sweep);
  expect_one_line(text, {"'kmax'", "integers", "\"10\""});
  EXPECT_EQ(text.err.find("json.exception"), std::string::npos) << text.err;
  grid(R"("arm4.xml")", "[10]");
  const test::CommandResult models = idmpc(sweep);
  expect_one_line(models, {"'models'", "a list of"});
  EXPECT_EQ(models.err.find("json.exception"), std::string::npos) << models.err;
  // twice: one line naming the entry, not the internal "two cells have the ID"
  grid(R"(["arm4.xml"])", "[10, 10]");
  expect_one_line(idmpc(sweep), {"'kmax'", "10 twice"});
  grid(R"(["arm4.xml", "arm4.xml"])", "[10]");
  expect_one_line(idmpc(sweep), {"'arm4.xml' twice"});
}

TEST_F(HostileCli, AnArmsListThatIsNotAListNamesTheField) {
  write("list.json", R"({"tasks": "mine.json"})");
  const test::CommandResult r = idmpc("sweep --arms-tasks list.json --list-cells");
  expect_one_line(r, {"'list.json'", "'tasks'", "a list of"});
  EXPECT_EQ(r.err.find("json.exception"), std::string::npos) << r.err;
}

// a cell's record is read as any input file: a FIFO or a device in its place is refused at once,
// on a line of its own (the progress line is not started yet)
TEST_F(HostileCli, ACellRecordThatIsNoRegularFileIsRefused) {
  const std::vector<std::string> ids = cell_ids(kSweep);
  ASSERT_EQ(ids.size(), 8u);
  fs::create_directories(dir_ / "out" / "cells");
  const fs::path fifo = dir_ / "out" / "cells" / (ids[0] + ".csv");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  expect_one_line(idmpc(kSweep + " --cell " + ids[0]), {ids[0] + ".csv", "FIFO"});
  fs::create_symlink("/dev/zero", dir_ / "out" / "cells" / (ids[1] + ".csv"));
  expect_one_line(idmpc(kSweep + " --cell " + ids[1]), {ids[1] + ".csv", "character device"});
  expect_one_line(idmpc(kSweep + " --merge"), {"cells", "FIFO"});
}

TEST_F(HostileCli, AnErrorOfACellIsOnALineOfItsOwn) {
  const std::vector<std::string> ids = cell_ids(kSweep);
  ASSERT_EQ(ids.size(), 8u);
  write("out/cells/" + ids[0] + ".csv", "not a record\n");
  expect_one_line(idmpc(kSweep + " --cell " + ids[0]), {ids[0] + ".csv", "something other than"});
}

// a cell refused beside a serial sweep or a merge (which hold the directory's lock alone) makes
// nothing, not even cells/
TEST_F(HostileCli, ARefusedCellMakesNoDirectory) {
  const std::vector<std::string> ids = cell_ids(kSweep);
  ASSERT_EQ(ids.size(), 8u);
  fs::create_directories(dir_ / "out");
  const int fd = ::open((dir_ / "out").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  expect_one_line(idmpc(kSweep + " --cell " + ids[0]), {"another sweep is writing into 'out'"});
  ::close(fd);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "cells"));
}

// the log temporary of a `--cell --logs` run killed outright (SIGKILL) is removed when the cell
// runs again, and by the merge (which runs alone) for every cell
TEST_F(HostileCli, TheLogTemporaryOfAKilledCellIsRemoved) {
  const pid_t dead = ::fork();
  ASSERT_GE(dead, 0);
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string sweep = kSweep + " --logs";
  const std::vector<std::string> ids = cell_ids(sweep);
  ASSERT_EQ(ids.size(), 8u);
  ASSERT_EQ(idmpc(sweep + " --cell " + ids[0]).code, 0);
  std::vector<std::string> logs;
  for (const auto& e : fs::directory_iterator(dir_ / "out")) {
    if (e.path().filename().string().rfind("log_", 0) == 0) logs.push_back(e.path().filename().string());
  }
  ASSERT_EQ(logs.size(), 1u);
  const std::string mine = "." + logs[0] + ".tmp." + std::to_string(dead) + ".0";
  const std::string other = ".log_3_other.csv.tmp." + std::to_string(dead) + ".0";
  for (const std::string& name : {mine, other}) std::ofstream(dir_ / "out" / name) << "half";
  fs::remove(dir_ / "out" / "cells" / (ids[0] + ".csv"));
  ASSERT_EQ(idmpc(sweep + " --cell " + ids[0]).code, 0);
  EXPECT_FALSE(fs::exists(dir_ / "out" / mine));
  EXPECT_TRUE(fs::exists(dir_ / "out" / other)) << "another cell's, left to it or to the merge";
  for (size_t k = 1; k < ids.size(); ++k) ASSERT_EQ(idmpc(sweep + " --cell " + ids[k]).code, 0) << ids[k];
  const test::CommandResult merged = idmpc(sweep + " --merge");
  ASSERT_EQ(merged.code, 0) << merged.err;
  EXPECT_FALSE(fs::exists(dir_ / "out" / other));
}

}  // namespace
}  // namespace idmpc
