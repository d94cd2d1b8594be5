// Input files read without trusting them (input_file.hpp): only regular files, of bounded size,
// JSON of bounded nesting, and values in error messages abbreviated; and what the task file
// reader and resolve() make of integers and sizes out of range.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "idmpc/experiment/input_file.hpp"
#include "idmpc/experiment/run_record.hpp"
#include "idmpc/experiment/task.hpp"
#include "idmpc/experiment/trajectory_io.hpp"
#include "support/errors.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;
using test::error_of;

class InputFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("idmpc_input_file_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  fs::path dir_;
};

TEST(Abbreviate, KeepsShortTextAndShortensLongText) {
  EXPECT_EQ(abbreviate("[1, 2]"), "[1, 2]");
  EXPECT_EQ(abbreviate(std::string(80, 'x')), std::string(80, 'x'));
  EXPECT_EQ(abbreviate(std::string(120000, 'x')), std::string(80, 'x') + "\xE2\x80\xA6 (120000 characters)");
  // never inside a UTF-8 character: "é" is two bytes
  std::string accents;
  for (int k = 0; k < 50; ++k) accents += "\xC3\xA9";
  EXPECT_EQ(abbreviate(accents, 5), "\xC3\xA9\xC3\xA9\xE2\x80\xA6 (100 characters)");
}

TEST_F(InputFileTest, OnlyRegularFilesOfBoundedSizeAreInputFiles) {
  EXPECT_EQ(input_file_problem(write("ok.json", "{}"), "a JSON file"), "");
  EXPECT_EQ(input_file_problem((dir_ / "missing.json").string(), "a JSON file"), "does not exist");
  EXPECT_EQ(input_file_problem(dir_.string(), "a JSON file"), "is a directory, expected a JSON file");
  EXPECT_EQ(input_file_problem("/dev/zero", "a JSON file"), "is a character device, expected a JSON file");
  const std::string fifo = (dir_ / "fifo").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(input_file_problem(fifo, "a JSON file"), "is a FIFO (named pipe), expected a JSON file");
  // a sparse file over the limit: refused by its size, unread
  const std::string big = write("big.xml", "");
  fs::resize_file(big, kMaxInputFileBytes + 1);
  EXPECT_EQ(input_file_problem(big, "an MJCF file"), "is 65 MiB, expected at most 64 MiB");
  EXPECT_EQ(error_of([&] { read_input_file(big, "model", "an MJCF file"); }),
            "model '" + big + "': is 65 MiB, expected at most 64 MiB");
  EXPECT_EQ(read_input_file(write("text", "abc"), "model", "an MJCF file"), "abc");
  if (::geteuid() != 0) {  // root reads any file
    const std::string locked = write("locked.json", "{}");
    fs::permissions(locked, fs::perms::none);
    EXPECT_EQ(input_file_problem(locked, "a JSON file"), "permission denied");
  }
}

TEST_F(InputFileTest, DeepJsonIsRefusedNamingTheFileAndTheDepth) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  const std::string path = write("deep.json", "{\n\"qref\": " + deep + "}");
  EXPECT_EQ(error_of([&] { read_json_file(path, "task file"); }),
            "task file '" + path + "': arrays and objects nested 100001 levels deep (line 2), expected at most 64");
  EXPECT_NE(error_of([&] { load_task(path); }).find("100001 levels deep"), std::string::npos);
  // brackets in strings do not count; 64 levels are fine
  EXPECT_NO_THROW(parse_json("[\"" + std::string(1000, '[') + "\"]", "x"));
  EXPECT_NO_THROW(parse_json(std::string(64, '[') + std::string(64, ']'), "x"));
  EXPECT_THROW(parse_json(std::string(65, '[') + std::string(65, ']'), "x"), std::invalid_argument);
}

// The parser alone would keep the last of two equal keys; a file that gives a field twice is
// refused, naming the field by its enclosing objects
TEST_F(InputFileTest, AKeyGivenTwiceInOneObjectIsRefusedNamingIt) {
  const std::string path = write("twice.json", R"({"duration": 1, "weights": {"Qq": 1, "R": 2, "Qq": 3}})");
  EXPECT_EQ(error_of([&] { read_json_file(path, "task file"); }),
            "task file '" + path + "': key \"weights.Qq\" appears twice in one object; give it once");
  EXPECT_NE(error_of([&] { load_task(path); }).find("\"weights.Qq\" appears twice"), std::string::npos);
  EXPECT_EQ(error_of([&] { parse_json(R"({"a": 1, "a": 1})", "x"); }), "x: key \"a\" appears twice in one object; give it once");
  EXPECT_EQ(error_of([&] { parse_json(R"({"r": {"points": [{"t": 0}, {"t": 1, "t": 2}]}})", "x"); }),
            "x: key \"r.points[].t\" appears twice in one object; give it once");
  // the same key in different objects, or as a string value, is fine
  EXPECT_NO_THROW(parse_json(R"({"a": {"a": 1}, "b": [{"a": 1}, {"a": 2}], "c": "a"})", "x"));
}

TEST_F(InputFileTest, ValuesEchoedIntoErrorsAreAbbreviated) {
  const std::string wide = "[\"" + std::string(100000, 'a') + "\"]";
  for (const std::string& text : {R"({"qref": [)" + wide + "]}", R"({"q0": {"a": )" + wide + "}}",
                                  "{\"" + std::string(100000, 'k') + "\": 1}",
                                  R"({"reference": {"shape": "line", "to": )" + wide + "}}"}) {
    const std::string message = error_of([&] {
      const Task t = load_task(write("wide.json", text));
      if (!t.reference.is_null()) {
        trajectory_from_json(t.reference, "reference", VecX<double>::Zero(1), dir_.string());
      }
    });
    EXPECT_LT(message.size(), 300u) << message.substr(0, 300);
    EXPECT_NE(message.find("\xE2\x80\xA6"), std::string::npos) << message.substr(0, 300);
  }
  // a long word is refused by resolve before its parser echoes it
  Task t = paper_task();
  t.formulation = std::string(100000, 'f');
  const std::string message = error_of([&] { resolve(t, 4); });
  EXPECT_LT(message.size(), 300u) << message.substr(0, 300);
  EXPECT_NE(message.find("--formulation"), std::string::npos) << message.substr(0, 300);
}

TEST_F(InputFileTest, TaskIntegersAreReadWhole) {
  // 4294967321 = 2^32 + 25: not N = 25
  const std::string wrap = write("wrap.json", R"({"cgmres": {"N": 4294967321}})");
  const std::string message = error_of([&] { load_task(wrap); });
  EXPECT_NE(message.find("field 'N'"), std::string::npos) << message;
  EXPECT_NE(message.find("4294967321"), std::string::npos) << message;
  EXPECT_NE(error_of([&] { load_task(write("low.json", R"({"cgmres": {"kmax": -2147483649}})")); }).find("'kmax'"),
            std::string::npos);
  EXPECT_EQ(load_task(write("edge.json", R"({"cgmres": {"N": 2147483647, "kmax": 7}})")).N, 2147483647);
}

TEST(ResolveLimits, HorizonIsBoundedBeforeAnythingIsSized) {
  Task t = paper_task();
  t.N = 2147483647;
  EXPECT_EQ(error_of([&] { resolve(t, 4); }), "--N (cgmres.N) must be from 1 to 10000 horizon steps, got 2147483647");
  t.N = 0;
  EXPECT_EQ(error_of([&] { resolve(t, 4); }), "--N (cgmres.N) must be from 1 to 10000 horizon steps, got 0");
  t.N = kMaxHorizonSteps;
  EXPECT_NO_THROW(resolve(t, 4));
}

TEST_F(InputFileTest, TrajectoriesAndRunLogsMustBeRegularFiles) {
  EXPECT_EQ(error_of([&] { read_trajectory_csv("/dev/zero", 1); }),
            "trajectory file '/dev/zero': is a character device, expected a CSV file");
  EXPECT_EQ(error_of([&] { read_run_log("/dev/zero"); }), "run log '/dev/zero': is a character device, expected a CSV file");
  EXPECT_EQ(error_of([&] { read_run_log(dir_.string()); }),
            "run log '" + dir_.string() + "': is a directory, expected a CSV file");
  EXPECT_EQ(error_of([&] { read_summary("/dev/zero"); }),
            "run summary '/dev/zero': is a character device, expected a JSON file");
}

}  // namespace
}  // namespace idmpc

namespace idmpc {
namespace {

// the one grammar of decimal numbers the command line and the task's text fields share
TEST(DecimalNumbers, RealsAndIntegersAsUsersWriteThem) {
  for (const char* s : {"0", "2", "0.5", ".5", "5.", "1e-3", "2E+4", "10"}) {
    EXPECT_TRUE(is_decimal_real(s, false, false)) << s;
  }
  for (const char* s : {"", "-1", "+1", "010", "0x1", "1e", "e3", ".", "inf", "nan", "1 ", " 1", "1,5"}) {
    EXPECT_FALSE(is_decimal_real(s, false, false)) << "'" << s << "'";
  }
  for (const char* s : {"-1", "+0.5", "-inf", "inf", "-2e3"}) EXPECT_TRUE(is_decimal_real(s, true, true)) << s;
  for (const char* s : {"-", "--1", "-010", "infinity", "nan"}) EXPECT_FALSE(is_decimal_real(s, true, true)) << s;
  for (const char* s : {"0", "10", "-3", "+7"}) EXPECT_TRUE(is_decimal_integer(s, true)) << s;
  for (const char* s : {"", "010", "1.0", "1e3", "0x10", "-"}) EXPECT_FALSE(is_decimal_integer(s, true)) << s;
  EXPECT_FALSE(is_decimal_integer("-3", false));
}

}  // namespace
}  // namespace idmpc
