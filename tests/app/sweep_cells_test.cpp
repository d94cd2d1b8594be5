// A sweep as independent cells: `sweep --list-cells` names them, `sweep --cell ID` runs one into
// its record, `sweep --merge` builds the serial sweep's tables from the records. Run through GNU
// parallel, the cells give the serial sweep's tables.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/command.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

const std::string kBinary = std::getenv("IDMPC_TEST_BINARY") ? std::getenv("IDMPC_TEST_BINARY") : IDMPC_BINARY;

// Table 3 (n = 8 … 32, FD and ID: 8 cells), 20 control steps per run: about a second of CPU
const std::string kSweep = "sweep --tables 3 --duration 0.02";

// the columns whose values are measured times (and the deadline misses they make), different on
// every run
const std::set<std::string> kTimingColumns = {"mean_update_ms", "p95_update_ms", "max_update_ms", "deadline_misses"};

using Result = test::CommandResult;
using test::quote;
using test::lines_of;
using test::slurp;
using test::split;


// a row of a sweep's CSV without its timing columns
std::vector<std::string> untimed(const std::vector<std::string>& header, const std::string& row) {
  std::vector<std::string> f = split(row), kept;
  for (size_t k = 0; k < f.size() && k < header.size(); ++k) {
    if (!kTimingColumns.count(header[k])) kept.push_back(f[k]);
  }
  return kept;
}

class SweepCells : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("idmpc_sweep_cells_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
    else std::printf("kept %s for inspection\n", dir_.c_str());
  }

  Result idmpc(const std::string& args) { return test::run_command(quote(kBinary) + " " + args, dir_); }

  // the cells' IDs as --list-cells prints them
  std::vector<std::string> cell_ids(const std::string& args) {
    const Result r = idmpc(args + " --list-cells");
    EXPECT_EQ(r.code, 0) << r.err;
    std::vector<std::string> ids;
    for (const std::string& line : lines_of(r.out)) ids.push_back(split(line, '\t').front());
    return ids;
  }

  // a failed command: exit code 1 and one "idmpc: error:" line that contains every needle
  static void expect_error(const Result& r, const std::vector<std::string>& needles) {
    EXPECT_EQ(r.code, 1) << r.err;
    EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
    EXPECT_EQ(r.err.rfind("idmpc: error: ", 0), 0u) << r.err;
    for (const std::string& needle : needles) {
      EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr does not name '" << needle << "': " << r.err;
    }
  }

  // no temporary of an atomic write survives anywhere under the test directory
  void expect_no_temporaries() const {
    for (const auto& e : fs::recursive_directory_iterator(dir_)) {
      EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << "left behind: " << e.path();
    }
  }

  fs::path dir_;
};

// --list-cells: one line per cell, a stable ID and a description, and nothing written
TEST_F(SweepCells, ListsEachCellOnceWithAStableId) {
  const Result r = idmpc(kSweep + " --out out --list-cells");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const std::vector<std::string> lines = lines_of(r.out);
  ASSERT_EQ(lines.size(), 8u) << r.out;
  std::set<std::string> ids;
  for (const std::string& line : lines) {
    const std::vector<std::string> f = split(line, '\t');
    ASSERT_EQ(f.size(), 2u) << line;
    EXPECT_TRUE(std::regex_match(f[0], std::regex("[0-9a-f]{16}"))) << line;
    EXPECT_NE(f[1].find("table 3: chain"), std::string::npos) << line;
    ids.insert(f[0]);
  }
  EXPECT_EQ(ids.size(), 8u);
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "--list-cells writes nothing";
  // the same options give the same IDs, wherever the sweep writes, and on another installation
  // of the same files (another data directory, as on another machine); other settings other IDs
  EXPECT_EQ(idmpc(kSweep + " --out elsewhere --list-cells").out, r.out);
  fs::create_directories(dir_ / "installed");
  fs::copy(IDMPC_SOURCE_DIR "/mjcf", dir_ / "installed" / "mjcf", fs::copy_options::recursive);
  EXPECT_EQ(idmpc(kSweep + " --data-dir installed --out out --list-cells").out, r.out);
  const std::vector<std::string> longer = cell_ids("sweep --tables 3 --duration 0.03");
  ASSERT_EQ(longer.size(), 8u);
  for (const std::string& id : longer) EXPECT_FALSE(ids.count(id)) << id;
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// the cells run through GNU parallel, two at a time, and merged give the serial sweep's tables.
// Equal means: every column of sweep.csv but the measured times (mean and p95 ms per update)
// equal, row by row; and with the records given the serial run's times, sweep.csv and sweep.md
// byte for byte the serial run's
TEST_F(SweepCells, ParallelCellsGiveTheSerialSweepsTables) {
  ASSERT_EQ(test::run_command("parallel --version | grep -q 'GNU parallel'", dir_).code, 0)
      << "GNU parallel is missing (tools/setup.sh installs the Debian package parallel)";
  const Result serial = idmpc(kSweep + " --out serial");
  ASSERT_EQ(serial.code, 0) << serial.err;

  const std::string cells = quote(kBinary) + " " + kSweep + " --out cells";
  const Result run = test::run_command("( " + cells + " --list-cells | cut -f1 | parallel --will-cite -j2 " +
                                           "--halt now,fail=1 " + cells + " --cell {} )",
                                       dir_);
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_EQ(run.out, "") << "a cell prints nothing on standard output";
  size_t records = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "cells" / "cells")) records += e.path().extension() == ".csv";
  EXPECT_EQ(records, 8u);
  EXPECT_FALSE(fs::exists(dir_ / "cells" / "sweep.csv")) << "cells write their records only";

  const Result merged = idmpc(kSweep + " --out cells --merge");
  ASSERT_EQ(merged.code, 0) << merged.err;
  const std::vector<std::string> expected = lines_of(slurp(dir_ / "serial" / "sweep.csv"));
  const std::vector<std::string> got = lines_of(slurp(dir_ / "cells" / "sweep.csv"));
  ASSERT_EQ(got.size(), expected.size());
  ASSERT_EQ(got.size(), 9u);
  const std::vector<std::string> header = split(expected[0]);
  EXPECT_EQ(got[0], expected[0]);
  for (size_t k = 1; k < got.size(); ++k) {
    EXPECT_EQ(untimed(header, got[k]), untimed(header, expected[k])) << "row " << k << ":\n" << got[k] << "\n"
                                                                      << expected[k];
  }

  // the records with the serial run's times: the merge writes the serial run's files exactly
  for (const auto& e : fs::directory_iterator(dir_ / "cells" / "cells")) {
    std::vector<std::string> record = lines_of(slurp(e.path()));
    ASSERT_EQ(record.size(), 2u) << e.path();
    const auto same = std::find_if(expected.begin() + 1, expected.end(), [&](const std::string& row) {
      return untimed(header, row) == untimed(header, record[1]);
    });
    ASSERT_NE(same, expected.end()) << record[1];
    std::vector<std::string> f = split(record[1]);
    const std::vector<std::string> serial_row = split(*same);
    for (size_t c = 0; c < header.size(); ++c) {
      if (kTimingColumns.count(header[c])) f[c] = serial_row[c];
    }
    std::string row;
    for (const std::string& x : f) row += (row.empty() ? "" : ",") + x;
    std::ofstream(e.path()) << record[0] << '\n' << row << '\n';
  }
  const Result again = idmpc(kSweep + " --out cells --merge");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(slurp(dir_ / "cells" / "sweep.csv"), slurp(dir_ / "serial" / "sweep.csv"));
  EXPECT_EQ(slurp(dir_ / "cells" / "sweep.md"), slurp(dir_ / "serial" / "sweep.md"));
  // the tables on standard output, as the serial sweep prints them, then the files written
  EXPECT_EQ(again.out, std::regex_replace(serial.out, std::regex("serial/"), "cells/"));
  expect_no_temporaries();
}

// an ID that is no cell of the sweep (another sweep's, or none) is refused in one line naming it
TEST_F(SweepCells, RefusesAWrongIdNamingIt) {
  expect_error(idmpc(kSweep + " --out out --cell 0123456789abcdef"), {"--cell '0123456789abcdef'", "no cell"});
  // a cell of the same grid with another duration is another cell
  const std::vector<std::string> ids = cell_ids("sweep --tables 3 --duration 0.03");
  ASSERT_FALSE(ids.empty());
  expect_error(idmpc(kSweep + " --out out --cell " + ids.front()), {"--cell '" + ids.front() + "'", "--list-cells"});
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "nothing is written for a wrong ID";
}

// a merge with a cell missing names it in one line, exits non-zero and writes no table; a cell
// run again finds its record; cells share the directory, a serial sweep or a merge has it alone
TEST_F(SweepCells, AMergeNamesTheMissingCells) {
  const std::string sweep = "sweep --tables 3 --duration 0.01 --out out";
  const std::vector<std::string> ids = cell_ids(sweep);
  ASSERT_EQ(ids.size(), 8u);
  expect_error(idmpc(sweep + " --merge"), {"8 of 8 cells have no record", ids.front(), ids.back()});

  for (size_t k = 0; k + 1 < ids.size(); ++k) {
    const Result r = idmpc(sweep + " --cell " + ids[k]);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const Result missing = idmpc(sweep + " --merge");
  expect_error(missing, {"1 of 8 cells have no record in 'out/cells'", ids.back()});
  for (size_t k = 0; k + 1 < ids.size(); ++k) EXPECT_EQ(missing.err.find(ids[k]), std::string::npos) << ids[k];
  EXPECT_FALSE(fs::exists(dir_ / "out" / "sweep.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "sweep.md"));

  const Result twice = idmpc(sweep + " --cell " + ids.front());
  ASSERT_EQ(twice.code, 0) << twice.err;
  EXPECT_NE(twice.err.find("done earlier"), std::string::npos) << twice.err;

  // cells share the lock: one runs beside another holder of the shared lock, a merge does not
  const int fd = ::open((dir_ / "out").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_SH | LOCK_NB), 0);
  const Result beside = idmpc(sweep + " --cell " + ids.back());
  EXPECT_EQ(beside.code, 0) << beside.err;
  expect_error(idmpc(sweep + " --merge"), {"another sweep is writing into 'out'"});
  expect_error(idmpc(sweep), {"another sweep is writing into 'out'"});
  // a serial sweep or a merge holds the directory alone: no cell runs beside it
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  fs::remove(dir_ / "out" / "cells" / (ids.back() + ".csv"));
  expect_error(idmpc(sweep + " --cell " + ids.back()), {"another sweep is writing into 'out'"});
  ::close(fd);
  expect_no_temporaries();
}

// a cell interrupted by a signal leaves neither its record nor a temporary of it
TEST_F(SweepCells, AnInterruptedCellLeavesNoFile) {
  // chain32 FD, 5 s simulated: it runs for many seconds, long enough to be interrupted
  const std::string sweep = "sweep --tables 3 --duration 5 --out out";
  const std::vector<std::string> ids = cell_ids(sweep);
  ASSERT_EQ(ids.size(), 8u);
  const std::string id = ids[6];
  const pid_t pid = test::start_command("cd " + quote(dir_.string()) + " && ulimit -c 0 && exec " + quote(kBinary) +
                                        " " + sweep + " --cell " + id + " 2> .stderr");
  ASSERT_GE(pid, 0);
  // the record's temporary exists from the start of the run
  const fs::path cells = dir_ / "out" / "cells";
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  bool temporary = false;
  while (!temporary && std::chrono::steady_clock::now() < deadline) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(cells, ec)) temporary |= e.path().filename().string().find(".tmp.") != std::string::npos;
    if (!temporary) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(temporary) << "the cell never created its record's temporary: " << slurp(dir_ / ".stderr");
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << "status " << status;
  fs::remove(dir_ / ".stderr");
  EXPECT_TRUE(fs::is_empty(cells)) << "no record, no temporary";
}

// the temporaries that killed cell runs left (their process gone): a cell run again removes its
// own (other cells may be writing theirs beside it); the merge, which runs alone, every one
TEST_F(SweepCells, StaleTemporariesOfKilledCellsAreRemoved) {
  const pid_t dead = ::fork();
  ASSERT_GE(dead, 0);
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string sweep = "sweep --tables 3 --duration 0.01 --out out";
  const std::vector<std::string> ids = cell_ids(sweep);
  ASSERT_EQ(ids.size(), 8u);
  const fs::path cells = dir_ / "out" / "cells";
  fs::create_directories(cells);
  const std::string mine = "." + ids[0] + ".csv.tmp." + std::to_string(dead) + ".0";
  const std::string other = "." + ids[1] + ".csv.tmp." + std::to_string(dead) + ".0";
  const std::string alive = "." + ids[2] + ".csv.tmp." + std::to_string(::getpid()) + ".0";
  for (const std::string& name : {mine, other, alive}) std::ofstream(cells / name) << "half";
  ASSERT_EQ(idmpc(sweep + " --cell " + ids[0]).code, 0);
  EXPECT_FALSE(fs::exists(cells / mine));
  EXPECT_TRUE(fs::exists(cells / other)) << "another cell's, left to it or to the merge";
  for (size_t k = 1; k < ids.size(); ++k) ASSERT_EQ(idmpc(sweep + " --cell " + ids[k]).code, 0) << ids[k];
  EXPECT_FALSE(fs::exists(cells / other)) << "its cell ran";
  // a second run of a cell killed after the first had written its record
  const std::string again = "." + ids[3] + ".csv.tmp." + std::to_string(dead) + ".1";
  std::ofstream(cells / again) << "half";
  const Result merged = idmpc(sweep + " --merge");
  ASSERT_EQ(merged.code, 0) << merged.err;
  EXPECT_FALSE(fs::exists(cells / again));
  EXPECT_TRUE(fs::exists(cells / alive)) << "a live process's temporary is kept";
}

}  // namespace
}  // namespace idmpc
