// The idmpc command line as a user meets it: exit codes, one clear error line naming what is
// wrong, outputs in the promised format, and no half-written file left behind by a failure.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/reference.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

const std::string kBinary = IDMPC_BINARY;
const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
const std::string kTree = IDMPC_SOURCE_DIR "/mjcf/tree.xml";

// the dynamics command prints 17 significant digits; our RNEA/ABA agree with MuJoCo to ~1e-14
// (`idmpc check`'s tolerance is 1e-10)
constexpr double kSameDynamics = 1e-10;

// a two-link arm whose shoulder is a ball joint: unsupported by the controller's model
const char* kBallJointModel = R"(<mujoco model="ball">
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder_ball" type="ball"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.5" size="0.05" mass="1"/>
      <body name="fore" pos="0 0 0.5">
        <joint name="elbow" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.5" size="0.05" mass="1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
)";

struct Result {
  int code = -1;
  std::string out, err;
};

std::string quote(const std::string& s) { return "'" + s + "'"; }

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  std::string line;
  while (std::getline(ss, line)) lines.push_back(line);
  return lines;
}

// fields of a CSV line, a trailing empty field included
std::vector<std::string> split(const std::string& line, char sep = ',') {
  std::vector<std::string> f;
  size_t begin = 0;
  for (size_t end = line.find(sep); end != std::string::npos; end = line.find(sep, begin)) {
    f.push_back(line.substr(begin, end - begin));
    begin = end + 1;
  }
  f.push_back(line.substr(begin));
  return f;
}

// each test gets a fresh directory, removed afterwards
class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    static std::atomic<int> counter{0};
    dir_ = fs::temp_directory_path() /
           ("idmpc_cli_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
    else std::printf("kept %s for inspection\n", dir_.c_str());
  }

  // runs `idmpc <args>` from the test directory, stdout and stderr captured to files
  Result idmpc(const std::string& args) {
    const fs::path out = dir_ / ".stdout", err = dir_ / ".stderr";
    const std::string cmd = "cd " + quote(dir_.string()) + " && " + quote(kBinary) + " " + args +
                            " > " + quote(out.string()) + " 2> " + quote(err.string());
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    fs::remove(out);
    fs::remove(err);
    return r;
  }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  // names of the files in the test directory (the captured outputs excluded)
  std::vector<std::string> files() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    return names;
  }

  // no temporary of an atomic write survives
  void expect_no_temporaries() const {
    for (const std::string& name : files()) {
      EXPECT_EQ(name.find(".tmp."), std::string::npos) << "left behind: " << name;
    }
  }

  // a failed command: non-zero exit, one "idmpc: error:" line that contains every needle
  void expect_error(const Result& r, const std::vector<std::string>& needles) const {
    EXPECT_NE(r.code, 0);
    EXPECT_NE(r.err.find("error"), std::string::npos) << "stderr: " << r.err;
    for (const std::string& needle : needles) {
      EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr does not name '" << needle << "': " << r.err;
    }
  }

  fs::path dir_;
};

// ---------------------------------------------------------------------------------------------
// check

TEST_F(Cli, CheckPassesOnArm4) {
  const Result r = idmpc("check " + quote(kArm4) + " --samples 3");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(std::regex_search(r.out, std::regex("all [0-9]+ checks passed at 3 random states")))
      << r.out;
  EXPECT_EQ(r.out.find("FAIL"), std::string::npos) << r.out;
}

TEST_F(Cli, CheckNamesTheMissingModelFile) {
  const std::string missing = (dir_ / "no_such_model.xml").string();
  const Result r = idmpc("check " + quote(missing));
  expect_error(r, {missing});
}

TEST_F(Cli, CheckNamesTheBallJoint) {
  const fs::path model = write("ball.xml", kBallJointModel);
  const Result r = idmpc("check " + quote(model.string()));
  expect_error(r, {"shoulder_ball", "ball"});
}

// ---------------------------------------------------------------------------------------------
// dynamics

struct StateRows {
  std::string csv;
  std::vector<VecX<double>> q, v, x;
};

StateRows random_rows(int n, int rows, unsigned seed, bool header) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  StateRows s;
  std::ostringstream o;
  o.precision(17);
  if (header) {
    for (int i = 0; i < n; ++i) o << (i ? "," : "") << "q" << i;
    for (const char* p : {"v", "x"}) {
      for (int i = 0; i < n; ++i) o << ',' << p << i;
    }
    o << '\n';
  }
  for (int r = 0; r < rows; ++r) {
    VecX<double> q(n), v(n), x(n);
    for (auto* vec : {&q, &v, &x}) {
      for (int i = 0; i < n; ++i) (*vec)[i] = u(rng);
    }
    for (int i = 0; i < 3 * n; ++i) o << (i ? "," : "") << (i < n ? q[i] : i < 2 * n ? v[i - n] : x[i - 2 * n]);
    o << '\n';
    s.q.push_back(q);
    s.v.push_back(v);
    s.x.push_back(x);
  }
  s.csv = o.str();
  return s;
}

class CliDynamics : public Cli, public ::testing::WithParamInterface<std::string> {};

TEST_P(CliDynamics, RowsMatchOurDynamicsAndMuJoCo) {
  const std::string path = GetParam();
  const mj::ModelPtr m = mj::load_model(path);
  const Model model = mj::import_model(m.get(), path).model;
  const int n = model.n, rows = 5;
  const unsigned seed = 7;
  SCOPED_TRACE("seed " + std::to_string(seed));
  const StateRows in = random_rows(n, rows, seed, true);
  write("states.csv", in.csv);
  const Result r = idmpc("dynamics " + quote(path) + " --in states.csv --out out.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "out.csv"));
  ASSERT_EQ(lines.size(), static_cast<size_t>(rows + 1));

  std::string header;
  for (int i = 0; i < n; ++i) header += (i ? "," : "") + std::string("tau") + std::to_string(i);
  for (int i = 0; i < n; ++i) header += ",qacc" + std::to_string(i);
  EXPECT_EQ(lines[0], header);

  Data data(model);
  mj::Reference reference(m.get());
  for (int k = 0; k < rows; ++k) {
    SCOPED_TRACE("row " + std::to_string(k));
    const std::vector<std::string> f = split(lines[k + 1]);
    ASSERT_EQ(f.size(), static_cast<size_t>(2 * n));
    VecX<double> tau(n), qacc(n);
    for (int i = 0; i < n; ++i) {
      tau[i] = std::stod(f[i]);
      qacc[i] = std::stod(f[n + i]);
    }
    const VecX<double> tau_ours = rnea(model, data, in.q[k], in.v[k], in.x[k]);
    const VecX<double> qacc_ours = aba(model, data, in.q[k], in.v[k], in.x[k]);
    const VecX<double> tau_mj = reference.inverse(in.q[k], in.v[k], in.x[k]);
    const VecX<double> qacc_mj = reference.forward(in.q[k], in.v[k], in.x[k]);
    EXPECT_LE(mj::relative_error(tau, tau_ours), kSameDynamics);
    EXPECT_LE(mj::relative_error(qacc, qacc_ours), kSameDynamics);
    EXPECT_LE(mj::relative_error(tau, tau_mj), kSameDynamics);
    EXPECT_LE(mj::relative_error(qacc, qacc_mj), kSameDynamics);
  }
  expect_no_temporaries();
}

INSTANTIATE_TEST_SUITE_P(Models, CliDynamics, ::testing::Values(kArm4, kTree), [](const auto& info) {
  return info.param == kArm4 ? std::string("arm4") : std::string("tree");
});

TEST_F(Cli, DynamicsAcceptsRowsWithoutHeader) {
  write("states.csv", random_rows(4, 2, 3, false).csv);
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(lines_of(slurp(dir_ / "out.csv")).size(), 3u);
}

TEST_F(Cli, DynamicsRejectsWrongColumnCountNamingTheLine) {
  std::vector<std::string> lines = lines_of(random_rows(4, 3, 5, true).csv);
  lines[2] += ",0.5";  // line 3: 13 values
  std::string csv;
  for (const auto& l : lines) csv += l + "\n";
  write("states.csv", csv);
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 3", "13", "12"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsRejectsANonNumberNamingTheLine) {
  std::vector<std::string> lines = lines_of(random_rows(4, 3, 6, true).csv);
  lines[2].replace(0, lines[2].find(','), "abc");  // line 3 starts with a word
  std::string csv;
  for (const auto& l : lines) csv += l + "\n";
  write("states.csv", csv);
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 3", "not a number"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsNamesTheMissingModelFile) {
  write("states.csv", random_rows(4, 1, 1, false).csv);
  const std::string missing = (dir_ / "absent.xml").string();
  const Result r = idmpc("dynamics " + quote(missing) + " --in states.csv --out out.csv");
  expect_error(r, {missing});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsNamesTheBallJoint) {
  const fs::path model = write("ball.xml", kBallJointModel);
  write("states.csv", random_rows(4, 1, 1, false).csv);
  const Result r = idmpc("dynamics " + quote(model.string()) + " --in states.csv --out out.csv");
  expect_error(r, {"shoulder_ball"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

// ---------------------------------------------------------------------------------------------
// swingup

// a failed swingup leaves neither its log nor its summary nor any temporary
class CliSwingupRefuses
    : public Cli, public ::testing::WithParamInterface<std::pair<std::string, std::vector<std::string>>> {};

TEST_P(CliSwingupRefuses, WithAClearErrorAndNothingWritten) {
  const auto& [options, needles] = GetParam();
  std::string args = options;
  const std::string ball = "BALL";
  if (args.find(ball) != std::string::npos) {
    args.replace(args.find(ball), ball.size(), quote(write("ball.xml", kBallJointModel).string()));
  } else {
    args = quote(kArm4) + " " + args;
  }
  const Result r = idmpc("swingup " + args + " --duration 0.2 --log log.csv --summary summary.json");
  SCOPED_TRACE("idmpc swingup " + args);
  expect_error(r, needles);
  EXPECT_FALSE(fs::exists(dir_ / "log.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "summary.json"));
  expect_no_temporaries();
  EXPECT_EQ(r.out.find("completed"), std::string::npos) << r.out;
}

using BadInput = std::pair<std::string, std::vector<std::string>>;  // options, needles

const std::vector<BadInput>& bad_inputs() {
  static const std::vector<BadInput> inputs = {
      {"--formulation xyz", {"formulation", "'xyz'"}},
      {"--derivatives exact", {"derivative", "'exact'"}},
      {"--N 0", {"N", "0"}},
      {"--kmax 0", {"kmax", "0"}},
      {"--dt 0", {"dt", "0"}},
      {"--Qq 1 2 3", {"--Qq", "3 values"}},
      {"--R -1", {"--R", "non-negative"}},
      {"--q0 0 0", {"--q0", "2 values"}},
      {"BALL", {"shoulder_ball", "ball"}}};
  return inputs;
}

std::string bad_input_name(const ::testing::TestParamInfo<BadInput>& info) {
  static const std::vector<std::string> names = {"formulation", "derivatives", "N",  "kmax",      "dt",
                                                 "Qq",          "R",           "q0", "ball_joint"};
  return names.at(info.index);
}

INSTANTIATE_TEST_SUITE_P(BadInputs, CliSwingupRefuses, ::testing::ValuesIn(bad_inputs()), bad_input_name);

TEST_F(Cli, SwingupRefusesAMissingModel) {
  const std::string missing = (dir_ / "absent.xml").string();
  const Result r = idmpc("swingup " + quote(missing) + " --duration 0.2 --log log.csv --summary summary.json");
  expect_error(r, {missing});
  EXPECT_FALSE(fs::exists(dir_ / "log.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "summary.json"));
  expect_no_temporaries();
}

TEST_F(Cli, SwingupRefusesAnUnwritableLogBeforeRunning) {
  // the default 10 s run would print a summary if it started
  const Result r = idmpc("swingup " + quote(kArm4) + " --log /nonexistent_dir/x.csv --summary summary.json");
  expect_error(r, {"/nonexistent_dir/x.csv"});
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(dir_ / "summary.json"));
  expect_no_temporaries();
}

TEST_F(Cli, SwingupRefusesAnUnwritableSummaryBeforeRunning) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --log log.csv --summary /nonexistent_dir/s.json");
  expect_error(r, {"/nonexistent_dir/s.json"});
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(dir_ / "log.csv"));
  expect_no_temporaries();
}

TEST_F(Cli, SwingupWritesLogAndSummary) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.2 --log log.csv --summary summary.json");
  ASSERT_EQ(r.code, 0) << r.err;
  expect_no_temporaries();

  // the log: the documented header, one row per 1 ms control step, all numbers
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "log.csv"));
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines[0], "t,q0,q1,q2,q3,v0,v1,v2,v3,u0,u1,u2,u3,residual,update_ms");
  EXPECT_EQ(lines.size(), 201u);
  for (size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> f = split(lines[k]);
    ASSERT_EQ(f.size(), 15u) << "row " << k;
    EXPECT_NEAR(std::stod(f[0]), 1e-3 * static_cast<double>(k - 1), 1e-9) << "row " << k;
    for (const auto& x : f) ASSERT_TRUE(std::isfinite(std::stod(x))) << "row " << k << ": " << x;
  }
  EXPECT_NEAR(std::stod(split(lines[1])[1]), -M_PI, 1e-9);  // q0(0) = −π

  // the summary
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "summary.json"));
  for (const char* key : {"schema", "task", "n", "diverged", "diverged_at", "mean_update_ms", "p50_update_ms",
                          "p95_update_ms", "max_update_ms", "final_q_error", "final_v_norm", "mean_residual"}) {
    EXPECT_TRUE(s.contains(key)) << "summary lacks '" << key << "'";
  }
  EXPECT_EQ(s["schema"], 1);
  // the task as run: the paper's swing-up with the options given
  const nlohmann::json& task = s["task"];
  EXPECT_EQ(task["model"], kArm4);
  EXPECT_EQ(s["n"], 4);
  EXPECT_EQ(task["formulation"], "id");
  EXPECT_EQ(task["derivatives"], "adjoint");
  EXPECT_EQ(task["cgmres"]["N"], 25);
  EXPECT_EQ(task["cgmres"]["kmax"], 10);
  EXPECT_EQ(task["weights"]["Qa"], nlohmann::json(std::vector<double>{0.0}));
  EXPECT_DOUBLE_EQ(task["duration"].get<double>(), 0.2);
  EXPECT_EQ(s["diverged"], false);
  EXPECT_TRUE(s["diverged_at"].is_null());
  for (const char* key : {"mean_update_ms", "p50_update_ms", "p95_update_ms", "max_update_ms"}) {
    EXPECT_GT(s[key].get<double>(), 0.0) << key;
  }
  EXPECT_LE(s["p50_update_ms"].get<double>(), s["p95_update_ms"].get<double>());
  EXPECT_LE(s["p95_update_ms"].get<double>(), s["max_update_ms"].get<double>());
  EXPECT_GE(s["final_q_error"].get<double>(), 0.0);
  EXPECT_GE(s["final_v_norm"].get<double>(), 0.0);
  EXPECT_GE(s["mean_residual"].get<double>(), 0.0);
  // the human summary names the run and where its files are
  EXPECT_NE(r.out.find("completed 200 control steps"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("log.csv"), std::string::npos) << r.out;
}

TEST_F(Cli, SwingupReportsDivergenceWithExitZeroAndKeepsTheLog) {
  const Result r = idmpc("swingup " + quote(kArm4) +
                         " --formulation fd --zeta 1e9 --duration 0.2 --log log.csv --summary summary.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "summary.json"));
  EXPECT_EQ(s["diverged"], true);
  ASSERT_TRUE(s["diverged_at"].is_number());
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "log.csv"));
  // rows up to and including the diverging step
  EXPECT_EQ(lines.size(), static_cast<size_t>(std::lround(s["diverged_at"].get<double>() / 1e-3) + 2));
  EXPECT_NE(r.out.find("DIVERGED"), std::string::npos) << r.out;
  expect_no_temporaries();
}

// ---------------------------------------------------------------------------------------------
// sweep

TEST_F(Cli, SweepIsResumable) {
  const std::string args = "sweep --tables 3 --duration 0.05 --out sweep";
  const Result first = idmpc(args);
  ASSERT_EQ(first.code, 0) << first.err;
  const fs::path csv = dir_ / "sweep" / "sweep.csv";
  EXPECT_TRUE(fs::exists(dir_ / "sweep" / "sweep.md"));
  std::vector<std::string> lines = lines_of(slurp(csv));
  ASSERT_EQ(lines.size(), 9u) << "header and 8 cells (n = 8, 16, 24, 32 × FD, ID)";
  const std::vector<std::string> before = lines;
  for (size_t k = 1; k < lines.size(); ++k) EXPECT_EQ(split(lines[k]).size(), split(lines[0]).size());

  // an interrupted sweep: the last three cells are missing
  lines.resize(lines.size() - 3);
  std::string kept;
  for (const auto& l : lines) kept += l + "\n";
  std::ofstream(csv) << kept;

  const Result second = idmpc(args);
  ASSERT_EQ(second.code, 0) << second.err;
  size_t done = 0;
  for (size_t pos = second.err.find("done earlier"); pos != std::string::npos;
       pos = second.err.find("done earlier", pos + 1)) {
    ++done;
  }
  EXPECT_EQ(done, 5u) << second.err;
  const std::vector<std::string> after = lines_of(slurp(csv));
  ASSERT_EQ(after.size(), 9u);
  // the kept cells are carried over unchanged
  for (size_t k = 0; k < 6; ++k) EXPECT_EQ(after[k], before[k]) << "line " << k + 1;
  EXPECT_TRUE(fs::exists(dir_ / "sweep" / "sweep.md"));
  for (const auto& e : fs::directory_iterator(dir_ / "sweep")) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
}

}  // namespace
}  // namespace idmpc
