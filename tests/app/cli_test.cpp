// The idmpc command line as a user meets it: exit codes, one clear error line naming what is
// wrong, outputs in the promised format, and no half-written file left behind by a failure.
#include <gtest/gtest.h>
#include <sys/file.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <iterator>
#include <map>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/experiment/run_record.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"
#include "idmpc/mujoco/reference.hpp"
#include "support/command.hpp"
#include "support/sanitizers.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

// IDMPC_TEST_BINARY runs these tests against another build (e.g. an older one, to see a test
// fail without its fix)
const std::string kBinary = std::getenv("IDMPC_TEST_BINARY") ? std::getenv("IDMPC_TEST_BINARY") : IDMPC_BINARY;
const std::string kArm4 = IDMPC_SOURCE_DIR "/mjcf/arm4.xml";
const std::string kTree = IDMPC_SOURCE_DIR "/mjcf/tree.xml";

// a cap on virtual memory (KiB) for commands that, without their fix, would exhaust memory;
// none under AddressSanitizer, which reserves terabytes of address space for its shadow
#if IDMPC_TEST_ASAN
const std::string kMemoryCap;
#else
const std::string kMemoryCap = "ulimit -v 3000000;";
#endif

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

using Result = test::CommandResult;
using test::quote;
using test::lines_of;
using test::slurp;
using test::split;


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

  // runs `idmpc <args>` from the test directory, stdout and stderr captured to files; `shell`
  // (e.g. "ulimit -v 3000000;") runs first in the same shell
  Result idmpc(const std::string& args, const std::string& shell = "") {
    return test::run_command(shell + " " + quote(kBinary) + " " + args, dir_);
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
      {"BALL", {"shoulder_ball", "ball"}},
      // kmax + 1 overflowed an int in the GMRES workspace; kmax > n·N is meaningless anyway
      {"--kmax 2147483647", {"kmax", "2147483647", "exceed"}},
      {"--kmax 101", {"kmax", "101", "100"}},
      // a problem not strictly convex in its decision variable
      {"--formulation fd --R 0", {"--R", "positive with FD"}},
      {"--R 0", {"--R and --Qa", "both 0"}},
      {"--shooting double", {"shooting", "'double'", "single", "multiple"}},
      {"--products finite", {"--products (cgmres.products)", "'finite'", "difference", "exact"}},
      {"--solver newton", {"--solver", "'newton'"}},
      {"--solver riccati --iterations 0", {"riccati", "iterations", "0"}}};
  return inputs;
}

std::string bad_input_name(const ::testing::TestParamInfo<BadInput>& info) {
  static const std::vector<std::string> names = {"formulation", "derivatives", "N",  "kmax",      "dt",
                                                 "Qq",          "R",           "q0", "ball_joint",
                                                 "kmax_int_max", "kmax_above_dimension", "fd_R_zero",
                                                 "id_R_and_Qa_zero", "shooting", "products", "solver",
                                                 "riccati_iterations"};
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

// the Riccati solver runs the same task through the same command: its record names it and says
// what it did
TEST_F(Cli, SwingupWithTheRiccatiSolver) {
  const Result r = idmpc("swingup " + quote(kArm4) +
                         " --solver riccati --iterations 2 --duration 0.2 --log log.csv --summary summary.json");
  ASSERT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.out.find("Riccati (ID)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("iterations = 2"), std::string::npos) << r.out;
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "summary.json"));
  EXPECT_EQ(s["task"]["solver"], "riccati");
  EXPECT_EQ(s["task"]["riccati"]["iterations"], 2);
  EXPECT_EQ(s["diverged"], false);
  EXPECT_EQ(lines_of(slurp(dir_ / "log.csv")).size(), 201u);
  // the same from a task file; a bad field there is named
  write("riccati.json", "{\"schema\": \"idmpc-task/1\", \"model\": \"" + kArm4 +
                            "\", \"q0\": \"swingup\", \"qref\": 0, \"solver\": \"riccati\", \"riccati\": {\"barrier\": 1e-2}}");
  const Result file = idmpc("swingup --task riccati.json --duration 0.1 --summary file.json");
  EXPECT_NE(file.code, 1) << file.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "file.json"))["task"]["riccati"]["barrier"], 1e-2);
  write("bad.json", "{\"schema\": \"idmpc-task/1\", \"model\": \"" + kArm4 +
                        "\", \"q0\": \"swingup\", \"qref\": 0, \"solver\": \"riccati\", \"riccati\": {\"barrier\": -1}}");
  expect_error(idmpc("swingup --task bad.json --duration 0.1"), {"barrier", "-1"});
}

// While it runs, swingup says how far it is on standard error (--progress: the wall time between
// lines; 0: every step and every iteration of the start), from the start on; --quiet says neither
// that nor the notices, and keeps the warnings
TEST_F(Cli, SwingupSaysHowFarItIsUnlessQuiet) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.003 --progress 0");
  ASSERT_EQ(r.code, 2) << r.err;
  for (const char* said : {"idmpc: still solving the start at t = 0 (", "idmpc: t = 0.001 s of 0.003 s (33 %), max|q - qref| 3.14 rad",
                           "idmpc: t = 0.002 s of 0.003 s (67 %)", "no torque limit is declared"}) {
    EXPECT_NE(r.err.find(said), std::string::npos) << said << " not in: " << r.err;
  }
  ASSERT_NE(r.err.find("idmpc: t = 0 s of 0.003 s (0 %)"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(" rad, "), std::string::npos) << "then the control steps per second of wall time: " << r.err;
  EXPECT_NE(r.err.find(" steps/s\n"), std::string::npos) << r.err;
  EXPECT_LT(r.err.find("still solving the start"), r.err.find("idmpc: t = 0 s"));
  const Result quiet = idmpc("swingup " + quote(kArm4) + " --duration 0.003 --progress 0 --quiet");
  ASSERT_EQ(quiet.code, 2) << quiet.err;
  EXPECT_EQ(quiet.err.find("still solving"), std::string::npos) << quiet.err;
  EXPECT_EQ(quiet.err.find("idmpc: t = "), std::string::npos) << quiet.err;
  EXPECT_NE(quiet.err.find("no torque limit is declared"), std::string::npos) << "warnings stay: " << quiet.err;
  // a frame target: its position error; the notices (servos replaced) unless quiet
  const std::string circle = quote(std::string(IDMPC_SOURCE_DIR) + "/mjcf/lite6_circle.json");
  const Result frame = idmpc("swingup --task " + circle + " --duration 0.002 --progress 0");
  ASSERT_NE(frame.code, 1) << frame.err;
  EXPECT_NE(frame.err.find("s (50 %), frame position error "), std::string::npos) << frame.err;
  EXPECT_NE(frame.err.find("servos"), std::string::npos) << frame.err;
  const Result silent = idmpc("swingup --task " + circle + " --duration 0.002 --quiet");
  ASSERT_NE(silent.code, 1) << silent.err;
  EXPECT_EQ(silent.err.find("servos"), std::string::npos) << silent.err;
  expect_error(idmpc("swingup " + quote(kArm4) + " --progress -1"), {"--progress", "-1"});
}

TEST_F(Cli, SwingupWritesLogAndSummary) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.2 --log log.csv --summary summary.json");
  ASSERT_EQ(r.code, 2) << r.err;
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
  // the model and the log as hashed bytes: render checks a log's model and summary by them
  EXPECT_EQ(s.value("model_hash", ""), file_hash(kArm4));
  EXPECT_EQ(s.value("log_hash", ""), file_hash((dir_ / "log.csv").string()));
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

// the exit code says whether the target was reached (0), not reached (2) or the run diverged (3,
// above); the summary and the screen say the same, with the tolerance
TEST_F(Cli, SwingupExitCodeSaysWhetherTheTargetWasReached) {
  const Result held = idmpc("swingup " + quote(kArm4) + " --q0 0 0 0 0 --qref 0 --duration 0.05 --summary a.json");
  EXPECT_EQ(held.code, 0) << held.err;
  EXPECT_NE(held.out.find("target REACHED (max|q - qref| < 0.001 at the end)"), std::string::npos) << held.out;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "a.json"))["reached"], true);
  const Result strict = idmpc("swingup " + quote(kArm4) +
                              " --q0 0 0 0 0 --qref 0.01 --duration 0.05 --reach-tolerance 1e-3 --summary b.json");
  EXPECT_EQ(strict.code, 2) << strict.err;
  EXPECT_NE(strict.out.find("target NOT reached (max|q - qref| < 0.001 at the end)"), std::string::npos) << strict.out;
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "b.json"))["reached"], false);
  const Result loose = idmpc("swingup " + quote(kArm4) +
                             " --q0 0 0 0 0 --qref 0.01 --duration 0.05 --reach-tolerance 0.1 --summary c.json");
  EXPECT_EQ(loose.code, 0) << loose.err;
}

TEST_F(Cli, SwingupReportsDivergenceWithItsExitCodeAndKeepsTheLog) {
  const Result r = idmpc("swingup " + quote(kArm4) +
                         " --formulation fd --zeta 1e9 --duration 0.2 --log log.csv --summary summary.json");
  ASSERT_EQ(r.code, 3) << r.err;
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "summary.json"));
  EXPECT_EQ(s["diverged"], true);
  ASSERT_TRUE(s["diverged_at"].is_number());
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "log.csv"));
  // rows up to and including the diverging step
  EXPECT_EQ(lines.size(), static_cast<size_t>(std::lround(s["diverged_at"].get<double>() / 1e-3) + 2));
  EXPECT_NE(r.out.find("DIVERGED"), std::string::npos) << r.out;
  expect_no_temporaries();
}

// a start without a finite torque is a divergence at t = 0: reported, hinted, log and summary
// written (0 rows); settings under which the continuation cannot act are divergences too
TEST_F(Cli, SwingupReportsDivergencesTheControllerCannotActOn) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"--R 1e300", "initialization"}, {"--zeta 1e300", "right-hand side"}, {"--h 1e-300", "below the resolution"}};
  for (const auto& [option, reason] : cases) {
    SCOPED_TRACE(option);
    const Result r = idmpc("swingup " + quote(kArm4) + " " + option + " --duration 0.2 --log log.csv --summary s.json");
    ASSERT_EQ(r.code, 3) << r.err;
    const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "s.json"));
    EXPECT_EQ(s["diverged"], true);
    EXPECT_NE(s["divergence_reason"].get<std::string>().find(reason), std::string::npos) << s["divergence_reason"];
    EXPECT_EQ(s["divergence_hint"].get<std::string>().rfind("try ", 0), 0u) << s["divergence_hint"];
    EXPECT_NE(r.out.find("hint: try"), std::string::npos) << r.out;
    EXPECT_LT(s["diverged_at"].get<double>(), 0.01);
    EXPECT_GE(lines_of(slurp(dir_ / "log.csv")).size(), 1u);  // the header at least
    if (option == "--R 1e300") {
      EXPECT_EQ(s["steps"], 0);
      EXPECT_EQ(s["diverged_at"], 0.0);
      EXPECT_DOUBLE_EQ(s["final_q_error"].get<double>(), M_PI);  // the start, not a reset state
    }
  }
}

// the hint names the options that apply to the task; --fallback applies the paper's Q_a rule
TEST_F(Cli, SwingupFallbackRerunsADivergedIdRunWithTheTasksQa) {
  const Result plain = idmpc("swingup " + quote(kArm4) + " --R 1e-9 --duration 0.05 --summary a.json");
  ASSERT_EQ(plain.code, 3) << plain.err;
  const nlohmann::json a = nlohmann::json::parse(slurp(dir_ / "a.json"));
  ASSERT_EQ(a["diverged"], true);
  const std::string hint = a["divergence_hint"];
  for (const char* option : {"--Qa 0.0001", "--fallback", "--alpha 0 --init-full-horizon true", "--R", "--zeta", "--N"}) {
    EXPECT_NE(hint.find(option), std::string::npos) << option << " not in: " << hint;
  }
  const Result r = idmpc("swingup " + quote(kArm4) + " --R 1e-9 --duration 0.05 --fallback --summary b.json");
  ASSERT_EQ(r.code, 2) << r.err;
  const nlohmann::json b = nlohmann::json::parse(slurp(dir_ / "b.json"));
  EXPECT_EQ(b["diverged"], false);
  EXPECT_EQ(b["task"]["weights"]["Qa"], nlohmann::json::array({1e-4}));
  EXPECT_NE(b["warnings"].back().get<std::string>().find("rerun with Qa = 0.0001"), std::string::npos) << b["warnings"];
  EXPECT_NE(r.err.find("rerun with Qa"), std::string::npos) << r.err;
}

// a run has at least one control step and at most 1e9; memory does not grow with it
TEST_F(Cli, SwingupRefusesDurationsOfNoStepOrBeyondAnyUse) {
  for (const auto& [duration, needle] : std::vector<std::pair<std::string, std::string>>{
           {"1e-5", "shorter than one control step"}, {"1e300", "more than 1e9 control steps"},
           {"1e7", "more than 1e9 control steps"}}) {
    SCOPED_TRACE(duration);
    const Result r = idmpc("swingup " + quote(kArm4) + " --duration " + duration + " --log log.csv --summary s.json");
    expect_error(r, {"--duration", needle});
    EXPECT_FALSE(fs::exists(dir_ / "log.csv"));
    EXPECT_FALSE(fs::exists(dir_ / "s.json"));
  }
}

// what the run does not model or had to change is said before it starts, and kept in the summary
TEST_F(Cli, SwingupWarnsAboutUnmodeledFeaturesRangesAndTheTimestep) {
  const Result r = idmpc("swingup " + quote(std::string(IDMPC_SOURCE_DIR) + "/mjcf/panda.xml") +
                         " --q0 0 0 0 0 0 5 0 --qref 0 0 0 -4 0 1 0 --dt 0.0015 --duration 0.003 --summary s.json");
  ASSERT_EQ(r.code, 2) << r.err;
  const std::vector<std::string> expected = {
      "does not model: range limits on joint(s) 'joint1'…'joint7' (7)", "q0 of joint 'joint4' of body 'link4' is 0, outside its range",
      "q0 of joint 'joint6' of body 'link6' is 5, outside its range", "qref of joint 'joint4' of body 'link4' is -4",
      "the control period 0.0015 s is not a whole multiple of the model's timestep 0.001 s: the plant steps at "
      "0.0015 s instead (coarser)"};
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "s.json"));
  for (const std::string& w : expected) {
    EXPECT_NE(r.err.find(w), std::string::npos) << w << " not in: " << r.err;
    EXPECT_NE(s["warnings"].dump().find(w), std::string::npos) << w;
  }
  EXPECT_LT(r.err.find("idmpc: warning:"), r.err.find("q0 of joint"));  // before the run, prefixed
}

// a heavily damped arm (the UR5e with Menagerie's 200 N m s/rad on its big joints): explicit
// Euler in FD's horizon is unstable at N = 25 (Δτ·eig(M⁻¹D) ≈ 7–15, measured), so the
// full-horizon start has no finite solution; with the damping integrated implicitly FD runs.
// ID needs no such option (its damping enters only the torque).
TEST_F(Cli, SwingupImplicitDampingLetsFdRunAHeavilyDampedArm) {
  std::string xml = slurp(std::string(IDMPC_SOURCE_DIR) + "/mjcf/ur5e.xml");
  const std::string light = R"(armature="0.1" damping="2")";
  ASSERT_NE(xml.find(light), std::string::npos);
  xml.replace(xml.find(light), light.size(), R"(armature="0.1" damping="200")");
  write("ur5e_damped.xml", xml);
  write("task.json", R"({"model": "ur5e_damped.xml", "q0": "home", "qref": [-0.3, -2.5, 0.3, -1.6, -1.571, 0],
    "formulation": "fd", "solver": "cgmres", "weights": {"Qq": 100, "Qv": 10, "R": 1e-3},
    "cgmres": {"Tf": 0.5, "alpha": 0, "init_full_horizon": true}})");
  // explicit: FD fails at t = 0, and the hint names the fix
  const Result exp = idmpc("swingup --task task.json --implicit-damping off --duration 0.05 --summary explicit.json");
  ASSERT_EQ(exp.code, 3) << exp.err;
  const nlohmann::json e = nlohmann::json::parse(slurp(dir_ / "explicit.json"));
  EXPECT_EQ(e["diverged"], true);
  EXPECT_EQ(e["diverged_at"], 0.0);
  EXPECT_EQ(e["divergence_hint"].get<std::string>().rfind("try --implicit-damping on", 0), 0u) << e["divergence_hint"];
  // the default, "auto", sees the unstable step and integrates the damping implicitly, and says so
  const Result aut = idmpc("swingup --task task.json --duration 0.05 --summary auto.json");
  ASSERT_EQ(aut.code, 2) << aut.err;
  EXPECT_NE(aut.err.find("joint damping integrated implicitly"), std::string::npos) << aut.err;
  const nlohmann::json a = nlohmann::json::parse(slurp(dir_ / "auto.json"));
  EXPECT_EQ(a["diverged"], false) << a["divergence_reason"];
  EXPECT_EQ(a["implicit_damping"], true);
  EXPECT_EQ(a["task"]["implicit_damping"], "auto");
  const Result imp = idmpc("swingup --task task.json --implicit-damping on --duration 0.05 --summary implicit.json");
  ASSERT_EQ(imp.code, 2) << imp.err;
  const nlohmann::json i = nlohmann::json::parse(slurp(dir_ / "implicit.json"));
  EXPECT_EQ(i["diverged"], false) << i["divergence_reason"];
  EXPECT_EQ(i["task"]["implicit_damping"], true);
  expect_error(idmpc("swingup --task task.json --implicit-damping on --alpha 1 --init-full-horizon false --duration 0.05"),
               {"--implicit-damping", "alpha = 0"});
  // the Riccati solver's horizon is always fixed: under "auto", on this fully actuated arm the
  // Riccati recursion, alpha does not matter
  const Result ric = idmpc("swingup --task task.json --solver auto --implicit-damping on --alpha 1 "
                           "--init-full-horizon false --duration 0.05 --summary riccati.json");
  ASSERT_EQ(ric.code, 2) << ric.err;
  const nlohmann::json rj = nlohmann::json::parse(slurp(dir_ / "riccati.json"));
  EXPECT_EQ(rj["solver"], "riccati");
  EXPECT_EQ(rj["implicit_damping"], true);
  expect_error(idmpc("swingup --task task.json --implicit-damping sometimes --duration 0.05"),
               {"--implicit-damping", "sometimes"});
}

TEST_F(Cli, SwingupWarnsThatQaDoesNothingInFd) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --formulation fd --Qa 1 --duration 0.01 --summary s.json");
  ASSERT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("--Qa (weights.Qa) has no effect with FD"), std::string::npos) << r.err;
  const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "s.json"));
  EXPECT_NE(s["warnings"].dump().find("no effect with FD"), std::string::npos);
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

// a resumed sweep never mixes settings, reads CRLF files, and refuses a directory another
// sweep is writing into
TEST_F(Cli, SweepResumeChecksSettingsAndTheDirectory) {
  const std::string args = "sweep --tables 3 --duration 0.02 --out sweep";
  ASSERT_EQ(idmpc(args).code, 0);
  const fs::path csv = dir_ / "sweep" / "sweep.csv";
  const std::string before = slurp(csv);

  const Result other = idmpc("sweep --tables 3 --duration 0.03 --out sweep");
  expect_error(other, {"sweep.csv", "other settings"});
  EXPECT_EQ(slurp(csv), before) << "the earlier results must be kept";

  std::string crlf;
  for (const std::string& l : lines_of(before)) crlf += l + "\r\n";
  std::ofstream(csv, std::ios::binary) << crlf;
  const Result again = idmpc(args);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.err.find("ms per update"), std::string::npos) << "every cell was done earlier: " << again.err;

  std::ofstream(csv) << "something,else\n1,2\n";
  expect_error(idmpc(args), {"sweep.csv", "something other than"});

  fs::remove(csv);
  const int fd = ::open((dir_ / "sweep").c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  expect_error(idmpc(args), {"another sweep", "sweep"});
  ::close(fd);
  EXPECT_FALSE(fs::exists(csv));
}

// the real-arm sweep: each task of arms.json under FD and ID, with time, outcome and saturation
TEST_F(Cli, SweepRunsTheRealArmsTasks) {
  write("reach.json", R"({"model": ")" + std::string(IDMPC_SOURCE_DIR) +
                          R"(/mjcf/panda.xml", "q0": "home", "qref": [1.5, 0.6, 0, -1.3, 0, 1.9, 0.785],
                          "duration": 5, "cgmres": {"alpha": 0, "init_full_horizon": true}})");
  write("arms.json", R"({"tasks": ["reach.json"]})");
  const Result r = idmpc("sweep --tables arms --derivatives adjoint --duration 0.03 --models . --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "out" / "arms.csv"));
  ASSERT_EQ(lines.size(), 3u) << "header, FD and ID";
  const std::vector<std::string> header = split(lines[0]);
  auto column = [&](const std::string& name) {
    return static_cast<size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  for (size_t k : {size_t{1}, size_t{2}}) {
    const std::vector<std::string> row = split(lines[k]);
    ASSERT_EQ(row.size(), header.size());
    EXPECT_EQ(row[column("table")], "arms");
    EXPECT_EQ(row[column("model")], "reach.json");
    EXPECT_EQ(row[column("n")], "7");
    EXPECT_EQ(row[column("formulation")], k == 1 ? "fd" : "id");
    EXPECT_EQ(row[column("steps")], "30");  // --duration overrides the task's 5 s
    EXPECT_EQ(row[column("diverged")], "0");
  }
  const std::string md = slurp(dir_ / "out" / "arms.md");
  EXPECT_NE(md.find("| reach.json | 7 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| reach.json | ID adjoint | no |"), std::string::npos) << md;  // 30 ms do not reach
  EXPECT_NE(md.find("steps with a clamped torque"), std::string::npos) << md;
}

// multiple shooting through the CLI: the run records its scheme, and it swings the arm like
// single shooting does (the first 0.3 s of the swing-up, both formulations)
TEST_F(Cli, SwingupRunsMultipleShootingAndRecordsIt) {
  for (const char* f : {"fd", "id"}) {
    SCOPED_TRACE(f);
    std::vector<double> q_end[2];
    for (const char* scheme : {"single", "multiple"}) {
      const Result r = idmpc("swingup " + quote(kArm4) + " --formulation " + f + " --shooting " + scheme +
                             " --duration 0.3 --log log.csv --summary s.json");
      ASSERT_EQ(r.code, 2) << r.err;
      const nlohmann::json s = nlohmann::json::parse(slurp(dir_ / "s.json"));
      EXPECT_EQ(s["task"]["cgmres"]["shooting"], scheme);
      EXPECT_EQ(s["diverged"], false);
      const std::vector<std::string> f_last = split(lines_of(slurp(dir_ / "log.csv")).back());
      for (int j = 1; j <= 4; ++j) q_end[std::string(scheme) == "multiple"].push_back(std::stod(f_last[j]));
    }
    // the arm has swung (q0 from −π by more than 0.3 rad), the same way under both schemes
    EXPECT_GT(q_end[0][0] + M_PI, 0.3);
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(q_end[1][j], q_end[0][j], 0.05) << "joint " << j;
  }
}

// the sweep's shooting axis: a column of its own, cells keyed by it, one table per scheme
TEST_F(Cli, SweepHasAShootingAxis) {
  const Result r = idmpc("sweep --tables 3 --shooting both --duration 0.02 --out sweep");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "sweep" / "sweep.csv"));
  ASSERT_EQ(lines.size(), 17u) << "header and 16 cells (n = 8 … 32 × FD, ID × single, multiple)";
  const std::vector<std::string> header = split(lines[0]);
  const size_t column = static_cast<size_t>(std::find(header.begin(), header.end(), "shooting") - header.begin());
  ASSERT_LT(column, header.size());
  int multiple = 0;
  for (size_t k = 1; k < lines.size(); ++k) multiple += split(lines[k])[column] == "multiple";
  EXPECT_EQ(multiple, 8);
  const std::string md = slurp(dir_ / "sweep" / "sweep.md");
  EXPECT_NE(md.find("## Table 3: N = 25, kmax = 10, derivatives: matrix\n"), std::string::npos) << md;
  EXPECT_NE(md.find("## Table 3: N = 25, kmax = 10, derivatives: matrix, multiple shooting\n"), std::string::npos) << md;
  // each formulation's fastest variant that did not diverge, side by side
  EXPECT_NE(md.find("## Best with best: ID/FD of each formulation's fastest variant"), std::string::npos) << md;
  EXPECT_NE(md.find("| best ID / best FD |"), std::string::npos) << md;
  // resumed: every cell, of either scheme, was done
  const Result again = idmpc("sweep --tables 3 --shooting both --duration 0.02 --out sweep");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.err.find("ms per update"), std::string::npos) << again.err;
}

// --no-simd-stages: every run of the sweep stage by stage (matrix mode is then the paper's
// arithmetic), said in the tables, and part of each cell's settings
TEST_F(Cli, SweepRunsStageByStageOnRequest) {
  const Result r = idmpc("sweep --tables 3 --no-simd-stages --duration 0.02 --out paper");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string md = slurp(dir_ / "paper" / "sweep.md");
  EXPECT_NE(md.find("Every run evaluates its stages one by one (`--no-simd-stages`)"), std::string::npos) << md;
  // the cells were run with other settings than a default sweep's: resuming with lanes is refused
  expect_error(idmpc("sweep --tables 3 --duration 0.02 --out paper"), {"sweep.csv", "other settings"});
  ASSERT_EQ(idmpc("sweep --tables 3 --duration 0.02 --out lanes").code, 0);
  const std::string lanes = slurp(dir_ / "lanes" / "sweep.md");
  EXPECT_NE(lanes.find("Matrix mode runs its stage derivatives in SIMD lanes"), std::string::npos) << lanes;
}

// a one-joint arm hanging onto a floor it touches from the start (a contact at every step),
// torque-limited; its task asks for 3 mrad in 0.05 s, reached within its own tolerance of 0.02
// rad (not within the 1e-3 rad of the paper's swing-up), offset-free as real arms are by default
const char* kTouchModel = R"(<mujoco model="touch">
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="link" pos="0 0 0.5">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.46" size="0.05" mass="1"/>
    </body>
  </worldbody>
  <actuator><motor joint="hinge" ctrllimited="true" ctrlrange="-5 5"/></actuator>
</mujoco>
)";
const char* kTouchTask =
    R"({"model": "touch.xml", "q0": [0], "qref": [0.003], "reach_tolerance": 0.02, "duration": 0.05})";

// the CSV of a sweep as rows of named fields
std::vector<std::map<std::string, std::string>> csv_rows(const fs::path& csv) {
  const std::vector<std::string> lines = lines_of(slurp(csv));
  std::vector<std::map<std::string, std::string>> rows;
  if (lines.empty()) return rows;
  const std::vector<std::string> header = split(lines[0]);
  for (size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> f = split(lines[k]);
    EXPECT_EQ(f.size(), header.size()) << "line " << k + 1;
    std::map<std::string, std::string> row;
    for (size_t i = 0; i < std::min(f.size(), header.size()); ++i) row[header[i]] = f[i];
    rows.push_back(row);
  }
  return rows;
}

// a user's own list of arm tasks (--arms-tasks, which implies --tables arms): each task as its
// file says (its duration, its reach tolerance, offset-free on), paths relative to the list,
// with whether it reached the target, offset-free tracking and the contacts in both tables
TEST_F(Cli, SweepRunsAUsersListOfArmTasks) {
  fs::create_directories(dir_ / "mine");
  write("mine/touch.xml", kTouchModel);
  write("mine/touch.json", kTouchTask);
  write("mine/list.json", R"({"description": "one arm on a floor", "tasks": ["touch.json"]})");
  const Result r = idmpc("sweep --arms-tasks mine/list.json --derivatives adjoint --out out");
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(dir_ / "out" / "arms.csv");
  ASSERT_EQ(rows.size(), 2u) << "FD and ID";
  for (const auto& row : rows) {
    SCOPED_TRACE(row.at("formulation"));
    EXPECT_EQ(row.at("table"), "arms");
    EXPECT_EQ(row.at("model"), "touch.json");
    EXPECT_EQ(row.at("steps"), "50");  // the task's own 0.05 s
    EXPECT_EQ(row.at("diverged"), "0");
    EXPECT_EQ(row.at("offset_free"), "1");
    EXPECT_GT(std::stod(row.at("max_final_disturbance")), 0) << "the observer ran";
    EXPECT_EQ(row.at("reach_tolerance"), "0.02");
    EXPECT_GT(std::stod(row.at("final_q_error")), 1e-3);
    EXPECT_EQ(row.at("reached"), "1");
    EXPECT_EQ(row.at("contact_steps"), "50");
    EXPECT_GT(std::stod(row.at("max_contact_force")), 0);
  }
  const std::string md = slurp(dir_ / "out" / "arms.md");
  EXPECT_NE(md.find("Each task of `mine/list.json`"), std::string::npos) << md;
  EXPECT_NE(md.find("`°` did not end within 0.02 rad of the target"), std::string::npos) << md;
  EXPECT_NE(md.find("| task | n | offset-free | FD adjoint | ID adjoint | ID/FD | best ID / best FD |"),
            std::string::npos) << md;
  EXPECT_NE(md.find("| touch.json | 1 | on |"), std::string::npos) << md;
  EXPECT_NE(md.find("| reached (< 0.02 rad) |"), std::string::npos) << md;
  EXPECT_NE(md.find("steps with a contact (largest normal force [N])"), std::string::npos) << md;
  // reached, final error, offset-free (d̂), contact steps (force), clamped steps
  const std::regex outcome(R"(\| touch\.json \| ID adjoint \| yes \| 0\.003 \| on \([0-9.e+-]+\) \| )"
                           R"(50 \([0-9.e+-]+\) \| 0 of 50 \|)");
  EXPECT_TRUE(std::regex_search(md, outcome)) << md;
}

// --tables work-precision: the runs of work_precision.json of --models (the paper's task on a
// model, a task file) over its kmax values, each with both kinds of products: the CSV has each
// cell's residual and closed-loop cost, the tables each formulation's time against them and the
// verdict at equal accuracy
TEST_F(Cli, SweepHasAWorkPrecisionTable) {
  fs::create_directories(dir_ / "mine");
  fs::copy_file(kArm4, dir_ / "mine" / "arm4.xml");
  write("mine/touch.xml", kTouchModel);
  write("mine/touch.json", kTouchTask);
  write("mine/work_precision.json", R"({"models": ["arm4.xml"], "tasks": ["touch.json"], "kmax": [1, 3]})");
  const std::string options = "sweep --tables work-precision --models mine --derivatives adjoint --products both "
                              "--duration 0.02 --out wp";
  const Result r = idmpc(options);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(dir_ / "wp" / "work_precision.csv");
  ASSERT_EQ(rows.size(), 16u) << "2 runs x FD, ID x 2 kinds of products x 2 kmax";
  int exact = 0;
  for (const auto& row : rows) {
    SCOPED_TRACE(row.at("model") + " " + row.at("formulation") + " " + row.at("products") + " " + row.at("kmax"));
    EXPECT_EQ(row.at("table"), "work-precision");
    exact += row.at("products") == "exact";
    EXPECT_EQ(row.at("diverged"), "0");
    EXPECT_EQ(row.at("steps"), "20");
    EXPECT_GT(std::stod(row.at("mean_residual")), 0);
    EXPECT_GT(std::stod(row.at("closed_loop_cost")), 0);
  }
  EXPECT_EQ(exact, 8);
  const std::string md = slurp(dir_ / "wp" / "work_precision.md");
  EXPECT_NE(md.find("## arm4.xml (n = 4), derivatives: adjoint\n"), std::string::npos) << md;
  EXPECT_NE(md.find("## touch.json (n = 1), derivatives: adjoint\n"), std::string::npos) << md;
  EXPECT_NE(md.find("| kmax | FD difference | FD exact | ID difference | ID exact |"), std::string::npos) << md;
  EXPECT_NE(md.find("## Verdict at equal accuracy"), std::string::npos) << md;
  EXPECT_TRUE(std::regex_search(md, std::regex(R"(\| arm4\.xml \| adjoint \| cost ≤ [0-9.e+-]+ \(\+10 %\) \| )")))
      << md;
  // every cell listed once, and an unknown kind of products refused naming it
  const Result list = idmpc(options + " --list-cells");
  ASSERT_EQ(list.code, 0) << list.err;
  EXPECT_EQ(lines_of(list.out).size(), 16u);
  const Result bad = idmpc("sweep --tables work-precision --products finite --out bad");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("products must be 'difference' or 'exact', got 'finite'"), std::string::npos) << bad.err;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  // a sweep compares named solver families: "auto", swingup's choice per model, is refused
  expect_error(idmpc("sweep --tables work-precision --solver auto --out bad"), {"--solver auto", "cgmres, riccati or both"});
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

// a list that cannot be read, or that names a task that cannot run, is refused with one line
// naming it, before any cell runs and before any output is made
TEST_F(Cli, SweepRefusesABadListOfArmTasksBeforeAnyCell) {
  write("touch.xml", kTouchModel);
  write("touch.json", kTouchTask);
  write("no_model.json", R"({"model": "absent.xml", "qref": [0]})");
  write("two_joints.json", R"({"model": "touch.xml", "q0": [0], "qref": [0, 0]})");
  write("missing.json", R"({"tasks": ["touch.json", "absent.json"]})");
  write("modelless.json", R"({"tasks": ["touch.json", "no_model.json"]})");
  write("misfit.json", R"({"tasks": ["touch.json", "two_joints.json"]})");
  write("empty.json", R"({"tasks": []})");
  write("twice.json", R"({"tasks": ["touch.json", "touch.json"]})");
  const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
      {"--arms-tasks none.json", {"'none.json'", "--arms-tasks"}},
      {"--arms-tasks missing.json", {"'missing.json'", "'absent.json'"}},
      {"--arms-tasks modelless.json", {"'modelless.json'", "'no_model.json'", "absent.xml"}},
      {"--arms-tasks misfit.json", {"'misfit.json'", "'two_joints.json'", "qref"}},
      {"--arms-tasks empty.json", {"'empty.json'", "no task"}},
      {"--arms-tasks twice.json", {"'twice.json'", "'touch.json' twice"}},
      {"--tables 3 --arms-tasks touch.json", {"--arms-tasks", "--tables arms"}},
      {"--tables 3 --offset-free off", {"--offset-free", "--tables arms"}},
      {"--arms-tasks twice.json --offset-free sometimes", {"--offset-free", "sometimes"}}};
  for (const auto& [args, needles] : cases) {
    SCOPED_TRACE(args);
    const Result r = idmpc("sweep " + args + " --out out");
    EXPECT_EQ(r.code, 1);
    EXPECT_EQ(r.err.rfind("idmpc: error: ", 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    for (const std::string& needle : needles) EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << "no output before the cells";
  }
}

// the offset-free axis: each arm with offset-free tracking on and off side by side, part of each
// cell's settings (a resume with another axis is refused)
TEST_F(Cli, SweepHasAnOffsetFreeAxis) {
  write("touch.xml", kTouchModel);
  write("touch.json", kTouchTask);
  write("list.json", R"({"tasks": ["touch.json"]})");
  const std::string args = "sweep --arms-tasks list.json --derivatives adjoint --offset-free both --out out";
  const Result r = idmpc(args);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto rows = csv_rows(dir_ / "out" / "arms.csv");
  ASSERT_EQ(rows.size(), 4u) << "FD and ID, each with offset-free tracking on and off";
  for (const char* f : {"fd", "id"}) {
    std::multiset<std::string> offset_free;
    for (const auto& row : rows) {
      if (row.at("formulation") != f) continue;
      offset_free.insert(row.at("offset_free"));
      // the observer runs exactly in the cells that say so
      if (row.at("offset_free") == "1") EXPECT_GT(std::stod(row.at("max_final_disturbance")), 0) << f;
      else EXPECT_EQ(row.at("max_final_disturbance"), "0") << f;
    }
    EXPECT_EQ(offset_free, (std::multiset<std::string>{"0", "1"})) << f;
  }
  const std::string md = slurp(dir_ / "out" / "arms.md");
  EXPECT_NE(md.find("on and off for every task, side by side (`--offset-free both`)"), std::string::npos) << md;
  const size_t on = md.find("| touch.json | 1 | on |"), off = md.find("| touch.json | 1 | off |");
  ASSERT_NE(on, std::string::npos) << md;
  ASSERT_NE(off, std::string::npos) << md;
  EXPECT_EQ(md.find('\n', on) + 1, off) << "the two rows of the arm follow each other: " << md;
  EXPECT_NE(md.find("| touch.json | ID adjoint | yes | 0.003 | off |"), std::string::npos) << md;

  // resumed: every cell was done; with the task's own setting (on), the cells with it off are
  // of other settings
  const Result again = idmpc(args);
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.err.find("ms per update"), std::string::npos) << again.err;
  expect_error(idmpc("sweep --arms-tasks list.json --derivatives adjoint --out out"),
               {"arms.csv", "other settings", "offset-free off"});
  const Result only_off = idmpc("sweep --arms-tasks list.json --derivatives adjoint --offset-free off --out off");
  ASSERT_EQ(only_off.code, 0) << only_off.err;
  const auto off_rows = csv_rows(dir_ / "off" / "arms.csv");
  ASSERT_EQ(off_rows.size(), 2u);
  for (const auto& row : off_rows) EXPECT_EQ(row.at("offset_free"), "0");
}

// ---------------------------------------------------------------------------------------------
// the command line itself: parse errors, --help, --version, numbers

class CliParseError : public Cli, public ::testing::WithParamInterface<BadInput> {};

TEST_P(CliParseError, ExitsOneWithOneErrorLine) {
  const auto& [args, needles] = GetParam();
  std::string expanded = args;
  const std::string arm = "ARM";
  if (expanded.find(arm) != std::string::npos) expanded.replace(expanded.find(arm), arm.size(), quote(kArm4));
  const Result r = idmpc(expanded);
  SCOPED_TRACE("idmpc " + expanded);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(r.err.rfind("idmpc: error: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  for (const std::string& needle : needles) {
    EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr does not name '" << needle << "': " << r.err;
  }
  EXPECT_EQ(r.out, "");
}

const std::vector<BadInput>& parse_errors() {
  static const std::vector<BadInput> inputs = {
      {"swingup ARM --horizon 10", {"'--horizon 10'", "swingup --help"}},
      {"check", {"model", "required"}},
      {"check ARM --samples abc", {"--samples", "abc"}},
      {"", {"subcommand"}},
      {"frobnicate", {"frobnicate"}},
      {"dynamics ARM --in", {"--in"}}};
  return inputs;
}

std::string parse_error_name(const ::testing::TestParamInfo<BadInput>& info) {
  static const std::vector<std::string> names = {"unknown_option", "missing_model", "not_a_number",
                                                 "no_subcommand", "unknown_subcommand", "missing_value"};
  return names.at(info.index);
}

INSTANTIATE_TEST_SUITE_P(Options, CliParseError, ::testing::ValuesIn(parse_errors()), parse_error_name);

TEST_F(Cli, HelpAndVersionExitZero) {
  for (const std::string args : {"--help", "swingup --help", "dynamics --help"}) {
    const Result r = idmpc(args);
    EXPECT_EQ(r.code, 0) << args << ": " << r.err;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << args << ": " << r.out;
    EXPECT_EQ(r.err, "") << args;
  }
  const Result v = idmpc("--version");
  EXPECT_EQ(v.code, 0) << v.err;
  EXPECT_TRUE(std::regex_search(v.out, std::regex("^idmpc [0-9.]+ \\(MuJoCo [0-9.]+\\)\n$"))) << v.out;
}

// the synopsis of docs/cli.md and each command's --help list the same options
class CliSynopsis : public Cli, public ::testing::WithParamInterface<std::string> {};

std::set<std::string> long_options(const std::string& text) {
  std::set<std::string> names;
  const std::regex option("--[A-Za-z][A-Za-z0-9-]*");
  for (std::sregex_iterator it(text.begin(), text.end(), option), end; it != end; ++it) names.insert(it->str());
  return names;
}

// the options `idmpc <command> --help` lists: the first field of each line of its Options section
std::set<std::string> help_options(const std::string& help) {
  std::set<std::string> names;
  bool in_options = false;
  for (const std::string& line : lines_of(help)) {
    if (line.rfind("Options:", 0) == 0) in_options = true;
    else if (!line.empty() && line[0] != ' ') in_options = false;
    if (!in_options || line.rfind("  -", 0) != 0) continue;
    const std::string first = line.substr(2, line.find(' ', 2) - 2);  // "-h,--help", "--no-simd-stages{false}"
    for (const std::string& name : long_options(first)) names.insert(name);
  }
  names.erase("--help");
  return names;
}

// the options of `idmpc <command> ...` in the synopsis of docs/cli.md (the sh block of "## Synopsis")
std::set<std::string> synopsis_options(const std::string& command) {
  const std::string synopsis_doc = slurp(IDMPC_SOURCE_DIR "/docs/cli.md");
  const std::size_t section = synopsis_doc.find("\n## Synopsis");
  const std::size_t block = synopsis_doc.find("```sh\n", section);
  const std::size_t block_end = synopsis_doc.find("```", block + 6);
  if (section == std::string::npos || block == std::string::npos || block_end == std::string::npos) return {};
  std::string synopsis;
  bool in_command = false;
  for (const std::string& line : lines_of(synopsis_doc.substr(block + 6, block_end - block - 6))) {
    if (line.rfind("idmpc ", 0) == 0) in_command = line.rfind("idmpc " + command + " ", 0) == 0 || line == "idmpc " + command;
    if (in_command) synopsis += line + "\n";
  }
  return long_options(synopsis);
}

std::string joined(const std::set<std::string>& names) {
  std::string text;
  for (const std::string& n : names) text += (text.empty() ? "" : " ") + n;
  return text;
}

TEST_P(CliSynopsis, ListsTheOptionsOfTheHelp) {
  const std::string& command = GetParam();
  const Result r = idmpc(command + " --help");
  ASSERT_EQ(r.code, 0) << r.err;
  const std::set<std::string> help = help_options(r.out);
  const std::set<std::string> documented = synopsis_options(command);
  ASSERT_FALSE(help.empty()) << r.out;
  std::set<std::string> missing, extra;
  std::set_difference(help.begin(), help.end(), documented.begin(), documented.end(), std::inserter(missing, missing.end()));
  std::set_difference(documented.begin(), documented.end(), help.begin(), help.end(), std::inserter(extra, extra.end()));
  EXPECT_TRUE(missing.empty()) << "docs/cli.md synopsis of 'idmpc " << command << "' lacks: " << joined(missing);
  EXPECT_TRUE(extra.empty()) << "docs/cli.md synopsis of 'idmpc " << command << "' has options --help does not: " << joined(extra);
}

INSTANTIATE_TEST_SUITE_P(Commands, CliSynopsis, ::testing::Values("check", "dynamics", "swingup", "sweep", "render"));

TEST_F(Cli, NegativeNumbersParseInEveryForm) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --q0 .4 -.4 -1e-3 -.5 --qref -.25 0 0 0 --duration 0.002 --log log.csv");
  ASSERT_EQ(r.code, 2) << r.err;
  const std::vector<std::string> lines = lines_of(slurp(dir_ / "log.csv"));
  ASSERT_GE(lines.size(), 2u);
  const std::vector<std::string> f = split(lines[1]);
  ASSERT_GE(f.size(), 5u);
  const double q0[] = {0.4, -0.4, -1e-3, -0.5};
  for (int i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(std::stod(f[1 + i]), q0[i]) << "q" << i;
}

// ---------------------------------------------------------------------------------------------
// outputs: never destroy what is not ours, never report success on a failed write

// states of arm4 (n = 4) with a header; `rows` random rows
std::string arm4_states(int rows = 3) { return random_rows(4, rows, 11, true).csv; }

bool is_named_pipe(const fs::path& p) { return fs::status(p).type() == fs::file_type::fifo; }
bool is_char_device(const fs::path& p) { return fs::status(p).type() == fs::file_type::character; }

TEST_F(Cli, DynamicsRefusesAnOutputThatIsAnInput) {
  const std::string states = arm4_states();
  write("states.csv", states);
  fs::create_symlink("states.csv", dir_ / "alias.csv");
  fs::copy_file(kArm4, dir_ / "arm4.xml");
  for (const std::string out : {"states.csv", "alias.csv", "./states.csv"}) {
    const Result r = idmpc("dynamics arm4.xml --in states.csv --out " + out);
    expect_error(r, {"--out '" + out + "'", "--in 'states.csv'", "same file"});
  }
  const Result r = idmpc("dynamics arm4.xml --in states.csv --out arm4.xml");
  expect_error(r, {"--out 'arm4.xml'", "model 'arm4.xml'"});
  EXPECT_EQ(slurp(dir_ / "states.csv"), states);
  EXPECT_EQ(slurp(dir_ / "arm4.xml"), slurp(kArm4));
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsRefusesADirectoryOutput) {
  write("states.csv", arm4_states());
  fs::create_directory(dir_ / "results");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out results");
  expect_error(r, {"--out 'results'", "directory"});
  EXPECT_TRUE(fs::is_directory(dir_ / "results"));
}

TEST_F(Cli, DynamicsWritesThroughAFifo) {
  write("states.csv", arm4_states(3));
  const fs::path fifo = dir_ / "out.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(fifo); });
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.fifo");
  // release the reader if nothing ever opened the FIFO for writing
  const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
  if (fd >= 0) ::close(fd);
  reader.join();
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(is_named_pipe(fifo)) << "the FIFO was replaced";
  EXPECT_EQ(lines_of(received).size(), 4u) << received;
  expect_no_temporaries();
}

class CliDevice : public Cli {
 protected:
  // a character device node in the test directory: (1, 3) discards, (1, 7) is always full
  fs::path device(const std::string& name, unsigned minor) {
    const fs::path p = dir_ / name;
    if (::mknod(p.c_str(), S_IFCHR | 0666, makedev(1, minor)) != 0) return {};
    const int fd = ::open(p.c_str(), O_WRONLY);
    if (fd < 0) return {};  // e.g. a filesystem mounted nodev
    ::close(fd);
    return p;
  }
};

TEST_F(CliDevice, DynamicsWritesThroughACharacterDevice) {
  const fs::path null = device("null", 3);
  if (null.empty()) GTEST_SKIP() << "cannot create a device node here (needs root and a dev-capable filesystem)";
  write("states.csv", arm4_states());
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out null");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(is_char_device(null)) << "the device was replaced by a regular file";
  expect_no_temporaries();
}

TEST_F(CliDevice, DynamicsReportsWhyAWriteToAFullDeviceFailed) {
  const fs::path full = device("full", 7);
  if (full.empty()) GTEST_SKIP() << "cannot create a device node here (needs root and a dev-capable filesystem)";
  write("states.csv", arm4_states());
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out full");
  expect_error(r, {"'full'", "No space left on device"});
  EXPECT_TRUE(is_char_device(full)) << "the device was replaced by a regular file";
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsFollowsASymlinkedOutput) {
  write("states.csv", arm4_states());
  fs::create_directory(dir_ / "real");
  std::ofstream(dir_ / "real" / "target.csv") << "old\n";
  fs::create_symlink("real/target.csv", dir_ / "out.csv");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir_ / "out.csv")) << "the link was replaced by a regular file";
  EXPECT_EQ(slurp(dir_ / "real" / "target.csv").rfind("tau0,", 0), 0u);
  for (const auto& e : fs::directory_iterator(dir_ / "real")) {
    EXPECT_EQ(e.path().filename(), "target.csv") << "left behind: " << e.path();
  }
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsKeepsTheOutputsPermissions) {
  write("states.csv", arm4_states());
  write("out.csv", "old\n");
  fs::permissions(dir_ / "out.csv", fs::perms::owner_read | fs::perms::owner_write);
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(fs::status(dir_ / "out.csv").permissions(), fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(slurp(dir_ / "out.csv").rfind("tau0,", 0), 0u);
}

TEST_F(Cli, DynamicsSaysWhyAWriteFailedAndKeepsTheOldFile) {
  // a file-size limit of a few KiB (SIGXFSZ ignored) makes the write fail as a full disk would
  write("states.csv", arm4_states(200));
  write("out.csv", "old\n");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv", "ulimit -f 8; trap '' XFSZ;");
  expect_error(r, {"'out.csv'", "File too large"});
  EXPECT_EQ(slurp(dir_ / "out.csv"), "old\n");
  expect_no_temporaries();
}

// outputs that are inputs, or each other, are refused before anything runs (the default 10 s
// run would print its summary if it started)
class CliSwingupOutputs : public Cli, public ::testing::WithParamInterface<std::pair<std::string, std::vector<std::string>>> {};

TEST_P(CliSwingupOutputs, ThatAreInputsOrEachOtherAreRefusedBeforeTheRun) {
  const auto& [options, needles] = GetParam();
  fs::copy_file(kArm4, dir_ / "model.xml");
  write("task.json", R"({"model": "model.xml", "duration": 0.05})");
  write("run.csv", "old log\n");
  fs::create_symlink("run.csv", dir_ / "alias.csv");
  fs::create_directory(dir_ / "sub");
  const Result r = idmpc("swingup " + options);
  SCOPED_TRACE("idmpc swingup " + options);
  expect_error(r, needles);
  EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(slurp(dir_ / "model.xml"), slurp(kArm4));
  EXPECT_EQ(slurp(dir_ / "task.json"), R"({"model": "model.xml", "duration": 0.05})");
  EXPECT_EQ(slurp(dir_ / "run.csv"), "old log\n");
  EXPECT_FALSE(fs::exists(dir_ / "other.json"));
  EXPECT_FALSE(fs::exists(dir_ / "a.csv"));
  expect_no_temporaries();
}

std::string output_case_name(const ::testing::TestParamInfo<std::pair<std::string, std::vector<std::string>>>& info) {
  static const std::vector<std::string> names = {"log_is_summary",   "linked_log_is_summary", "log_is_video",
                                                 "summary_is_model", "log_is_task_file",      "video_is_the_tasks_model",
                                                 "new_log_is_dot_slash_summary", "new_log_is_absolute_summary",
                                                 "new_log_is_dot_dot_summary", "new_log_is_dot_slash_video"};
  return names.at(info.index);
}

INSTANTIATE_TEST_SUITE_P(
    Paths, CliSwingupOutputs,
    ::testing::Values(
        std::make_pair("model.xml --log run.csv --summary run.csv", std::vector<std::string>{"--summary 'run.csv'", "--log 'run.csv'"}),
        std::make_pair("model.xml --log alias.csv --summary run.csv", std::vector<std::string>{"--summary 'run.csv'", "--log 'alias.csv'"}),
        std::make_pair("model.xml --log run.csv --video run.csv", std::vector<std::string>{"--video 'run.csv'", "--log 'run.csv'"}),
        std::make_pair("model.xml --log other.csv --summary model.xml", std::vector<std::string>{"--summary 'model.xml'", "model 'model.xml'"}),
        std::make_pair("--task task.json --summary other.json --log task.json", std::vector<std::string>{"--log 'task.json'", "--task 'task.json'"}),
        std::make_pair("--task task.json --log run.csv --summary other.json --video model.xml", std::vector<std::string>{"--video 'model.xml'", "model.xml"}),
        // files not there yet, spelled in different ways
        std::make_pair("model.xml --log a.csv --summary ./a.csv", std::vector<std::string>{"--summary './a.csv'", "--log 'a.csv'"}),
        std::make_pair("model.xml --log a.csv --summary \"$PWD/a.csv\"", std::vector<std::string>{"--summary '/", "--log 'a.csv'"}),
        std::make_pair("model.xml --log a.csv --summary sub/../a.csv", std::vector<std::string>{"--summary 'sub/../a.csv'", "--log 'a.csv'"}),
        std::make_pair("model.xml --log a.csv --video ./a.csv", std::vector<std::string>{"--video './a.csv'", "--log 'a.csv'"})),
    output_case_name);

TEST_F(Cli, SwingupRefusesADirectoryLogBeforeRunning) {
  fs::create_directory(dir_ / "logs");
  const Result r = idmpc("swingup " + quote(kArm4) + " --log logs --summary summary.json");
  expect_error(r, {"--log 'logs'", "directory"});
  EXPECT_EQ(r.out, "");
  EXPECT_TRUE(fs::is_directory(dir_ / "logs"));
  EXPECT_FALSE(fs::exists(dir_ / "summary.json"));
  expect_no_temporaries();
}

TEST_F(Cli, SwingupRefusesAVideoWithoutFfmpegBeforeRunning) {
  // no ffmpeg on PATH (the binary itself is run by its full path)
  const Result r = idmpc("swingup " + quote(kArm4) + " --log log.csv --video run.mp4", "PATH=/nonexistent;");
  expect_error(r, {"--video 'run.mp4'", "ffmpeg"});
  EXPECT_EQ(r.out, "");
  EXPECT_FALSE(fs::exists(dir_ / "log.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "run.mp4"));
  expect_no_temporaries();
}

TEST_F(CliDevice, SwingupWritesThroughDevicesFollowsLinksAndKeepsModes) {
  const fs::path null = device("null", 3);
  if (null.empty()) GTEST_SKIP() << "cannot create a device node here (needs root and a dev-capable filesystem)";
  fs::create_directory(dir_ / "real");
  std::ofstream(dir_ / "real" / "log.csv") << "old\n";
  fs::permissions(dir_ / "real" / "log.csv", fs::perms::owner_read | fs::perms::owner_write);
  fs::create_symlink("real/log.csv", dir_ / "log.csv");
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.02 --log log.csv --summary null");
  ASSERT_EQ(r.code, 2) << r.err;
  EXPECT_TRUE(is_char_device(null)) << "the device was replaced by a regular file";
  EXPECT_TRUE(fs::is_symlink(dir_ / "log.csv")) << "the link was replaced by a regular file";
  EXPECT_EQ(slurp(dir_ / "real" / "log.csv").rfind("t,q0,", 0), 0u);
  EXPECT_EQ(fs::status(dir_ / "real" / "log.csv").permissions(), fs::perms::owner_read | fs::perms::owner_write);
  expect_no_temporaries();
}

// a dynamics run blocked on a FIFO input, then interrupted: its temporary output goes too
class CliInterrupted : public Cli, public ::testing::WithParamInterface<int> {};

TEST_P(CliInterrupted, DynamicsLeavesNoTemporary) {
  const int sig = GetParam();
  const fs::path fifo = dir_ / "in.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string cmd = "cd " + quote(dir_.string()) + " && ulimit -c 0 && exec " + quote(kBinary) + " dynamics " +
                          quote(kArm4) + " --in in.fifo --out out.csv 2> .stderr";
  const pid_t pid = test::start_command(cmd);
  ASSERT_GE(pid, 0);
  // open the FIFO once the command reads it, feed one row, wait for the temporary output
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::seconds(20);
  int fd = -1;
  while (fd < 0 && clock::now() < deadline) {
    fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd < 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  bool temporary = false;
  if (fd >= 0) {
    const std::string rows = arm4_states(1);
    EXPECT_EQ(::write(fd, rows.data(), rows.size()), static_cast<ssize_t>(rows.size()));
    while (!temporary && clock::now() < deadline) {
      for (const std::string& name : files()) temporary |= name.find(".tmp.") != std::string::npos;
      if (!temporary) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  ::kill(pid, sig);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (fd >= 0) ::close(fd);
  ASSERT_TRUE(temporary) << "the command never created its temporary output: " << slurp(dir_ / ".stderr");
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "status " << status;
  fs::remove(dir_ / ".stderr");
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

// every signal that ends the process and can be caught removes the temporaries (those of a
// fault of the process itself excepted)
INSTANTIATE_TEST_SUITE_P(Signals, CliInterrupted,
                         ::testing::Values(SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGXFSZ, SIGXCPU,
                                           SIGALRM),
                         [](const auto& info) { return std::string("SIG") + sigabbrev_np(info.param); });

// ---------------------------------------------------------------------------------------------
// dynamics: hostile inputs

std::string arm4_row(const std::string& v0 = "0.5") {
  return "0.1,0.2,0.3,0.4," + v0 + ",0,0,0,1,2,3,4";
}

TEST_F(Cli, DynamicsRejectsANonFiniteResultNamingTheRow) {
  write("states.csv", arm4_row() + "\n" + arm4_row("1e308") + "\n");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 2", "not finite"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

TEST_F(Cli, DynamicsRejectsNonFiniteInputsNamingTheField) {
  for (const std::string bad : {"nan", "inf", "1e999"}) {
    write("states.csv", arm4_row() + "\n" + arm4_row(bad) + "\n");
    const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
    expect_error(r, {"line 2", "field 5", "'" + bad + "'"});
  }
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

TEST_F(Cli, DynamicsDoesNotTakeABadFirstRowForAHeader) {
  write("states.csv", "abc,0.2,0.3,0.4,0.5,0,0,0,1,2,3,4\n" + arm4_row() + "\n");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 1", "field 1", "'abc'", "not a number"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

TEST_F(Cli, DynamicsRejectsANulByte) {
  std::string row = arm4_row();
  row.insert(row.find(",0,0,0") + 2, std::string(1, '\0'));  // "0\0" in field 6
  write("states.csv", arm4_row() + "\n" + row + "\n");
  ASSERT_EQ(fs::file_size(dir_ / "states.csv"), 2 * (arm4_row().size() + 1) + 1);
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 2", "NUL"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
}

TEST_F(Cli, DynamicsNamesTheSeparatorOfASemicolonFile) {
  std::string row = arm4_row();
  std::replace(row.begin(), row.end(), ',', ';');
  write("states.csv", row + "\n" + row + "\n");
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in states.csv --out out.csv");
  expect_error(r, {"line 1", "1 field", "expected 3n = 12", "';'"});
}

TEST_F(Cli, DynamicsEndsAnEndlessLineWithAnError) {
  // without a bound, reading /dev/zero grows one line until memory runs out (capped here)
  const Result r = idmpc("dynamics " + quote(kArm4) + " --in /dev/zero --out out.csv", kMemoryCap);
  expect_error(r, {"'/dev/zero' line 1", "longer than 1048576 bytes"});
  EXPECT_FALSE(fs::exists(dir_ / "out.csv"));
  expect_no_temporaries();
}

// a servo model loads without --direct-torque: its servo is replaced by joint torques
TEST_F(Cli, DynamicsReplacesServosByJointTorques) {
  const fs::path model = write("servo.xml", R"(<mujoco>
  <worldbody><body pos="0 0 1"><joint name="j" type="hinge" axis="0 1 0"/>
    <geom type="sphere" size="0.1" mass="1" contype="0" conaffinity="0"/></body></worldbody>
  <actuator><position name="servo" joint="j" kp="10"/></actuator>
</mujoco>)");
  write("states.csv", "0.1,0.2,0.3\n");
  const Result r = idmpc("dynamics servo.xml --in states.csv --out out.csv");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("position servos 'servo' replaced by joint torques"), std::string::npos) << r.err;
  const Result direct = idmpc("dynamics servo.xml --in states.csv --out out.csv --direct-torque");
  EXPECT_EQ(direct.code, 0) << direct.err;
  EXPECT_EQ(slurp(dir_ / "out.csv").empty(), false);
}

// an acrobot: one motor on the elbow, the shoulder passive
const std::string kAcrobotModel = slurp(IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/acrobot.xml");

TEST_F(Cli, DirectTorquesOnAnUnderActuatedModelNeedTheConfirmation) {
  write("acrobot.xml", kAcrobotModel);
  write("states.csv", "0.1,0.2,0,0,0.5,0.5\n");
  // without the confirmation the shoulder stays passive, and the command says so
  const Result passive = idmpc("dynamics acrobot.xml --in states.csv --out out.csv --direct-torque");
  EXPECT_EQ(passive.code, 0) << passive.err;
  EXPECT_NE(passive.err.find("under-actuated: joint(s) 'shoulder' have no actuator"), std::string::npos)
      << passive.err;
  const Result confirmed =
      idmpc("dynamics acrobot.xml --in states.csv --out out.csv --direct-torque --actuate-every-joint");
  EXPECT_EQ(confirmed.code, 0) << confirmed.err;
  EXPECT_TRUE(fs::exists(dir_ / "out.csv"));
  const Result checked = idmpc("check acrobot.xml --samples 2 --direct-torque --actuate-every-joint");
  EXPECT_EQ(checked.code, 0) << checked.err;
  EXPECT_NE(checked.out.find("joints without an actuator driven too: 'shoulder'"), std::string::npos) << checked.out;
}

// check names the passive joints of an under-actuated model, and compares its dynamics; actuators
// the controller cannot use are reported instead of refused
TEST_F(Cli, CheckNamesUnactuatedJointsAndRefusesActuatorsTheControllerCannotUse) {
  write("acrobot.xml", kAcrobotModel);
  const Result r = idmpc("check acrobot.xml --samples 2");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("under-actuated: joint(s) 'shoulder' have no actuator"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("shoulder         hinge"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("UNACTUATED"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("elbow            hinge  axis (+0.000 +1.000 +0.000)  parent  0  mass 1  q [rad], tau [N m]  UNACTUATED"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("all 16 checks passed"), std::string::npos) << r.out;
  // a tendon actuator
  std::string tendon = kAcrobotModel;
  tendon.replace(tendon.find("<actuator>"), 0,
                 R"(<tendon><fixed name="t"><joint joint="shoulder" coef="1"/><joint joint="elbow" coef="1"/></fixed></tendon>)");
  tendon.replace(tendon.find(R"(joint="elbow" gear="2")"), 22, R"(tendon="t")");
  write("tendon.xml", tendon);
  const Result t = idmpc("check tendon.xml --samples 2");
  // the dynamics are still compared, then check refuses the file as swingup does, with its line
  EXPECT_NE(t.out.find("does not act on a joint"), std::string::npos) << t.out;
  EXPECT_NE(t.out.find("all 16 checks passed"), std::string::npos) << t.out;
  expect_error(t, {"does not act on a joint"});
  const Result s = idmpc("swingup tendon.xml --duration 0.01 --quiet");
  expect_error(s, {"does not act on a joint"});
  EXPECT_EQ(t.err, s.err) << "check and swingup refuse the file alike";
}

// a Menagerie arm written for MuJoCo 3: translated, servos replaced, limits from the file
TEST_F(Cli, CheckTranslatesAMujoco3ArmAndSummarisesItsActuation) {
  const std::string fixture = IDMPC_SOURCE_DIR "/tests/mujoco/fixtures/fr3_translate.xml";
  const Result r = idmpc("check " + quote(fixture) + " --samples 2");
  EXPECT_EQ(r.code, 0) << r.err << r.out;
  for (const std::string part : {"is written for a newer MuJoCo; translated in memory for MuJoCo",
                                 "integrator implicitfast replaced by implicit",
                                 "actuation: servos 'fr3_joint1', 'fr3_joint2', 'fr3_joint4' replaced by joint torques",
                                 "every joint's torque is bounded", "all 16 checks passed"}) {
    EXPECT_NE(r.out.find(part), std::string::npos) << "lacks '" << part << "': " << r.out;
  }
}

// ---------------------------------------------------------------------------------------------
// check: NaN, degenerate gears, unmodeled features, units, newer MuJoCo, huge assets

// a hinge carrying a slide, a motor on each; spliced: <option> attributes, hinge attributes,
// attributes of the hinge's motor, and MJCF inside <mujoco>
std::string hinge_slide_mjcf(const std::string& option = "", const std::string& hinge = R"(axis="0 1 0")",
                             const std::string& motor = "", const std::string& extra = "") {
  return R"(<mujoco model="hinge_slide">
  <option timestep="0.001" )" + option + R"(/>
  )" + extra + R"(
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="shoulder" type="hinge" )" + hinge + R"(/>
      <geom type="capsule" fromto="0 0 0 0.4 0 0" size="0.04" mass="1" contype="0" conaffinity="0"/>
      <body name="carriage" pos="0.4 0 0">
        <joint name="rail" type="slide" axis="1 0 0"/>
        <geom type="box" size="0.05 0.04 0.03" mass="0.5" contype="0" conaffinity="0"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="shoulder_motor" joint="shoulder" )" + motor + R"(/><motor name="rail_motor" joint="rail"/></actuator>
</mujoco>
)";
}

TEST_F(Cli, CheckPassesOnAHingeAndASlide) {
  write("model.xml", hinge_slide_mjcf());
  const Result r = idmpc("check model.xml --samples 3");
  EXPECT_EQ(r.code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("all 16 checks passed"), std::string::npos) << r.out;
}

TEST_F(Cli, CheckGivesSlideJointsInMetresAndNewtons) {
  write("model.xml", hinge_slide_mjcf());
  const Result r = idmpc("check model.xml --samples 1");
  ASSERT_EQ(r.code, 0) << r.err;
  std::string shoulder, rail;
  for (const std::string& line : lines_of(r.out)) {
    if (line.find(" shoulder ") != std::string::npos) shoulder = line;
    if (line.find(" rail ") != std::string::npos) rail = line;
  }
  EXPECT_NE(shoulder.find("q [rad], tau [N m]"), std::string::npos) << shoulder;
  EXPECT_NE(rail.find("q [m], tau [N]"), std::string::npos) << rail;
  EXPECT_EQ(rail.find("rad"), std::string::npos) << rail;
}

TEST_F(Cli, CheckRejectsANanAxisNamingTheJoint) {
  write("model.xml", hinge_slide_mjcf("", R"(axis="nan 1 0")"));
  const Result r = idmpc("check model.xml --samples 2");
  expect_error(r, {"'shoulder'", "axis", "nan"});
  EXPECT_EQ(r.out.find("checks passed"), std::string::npos) << r.out;
}

TEST_F(Cli, CheckRejectsADenormalGearNamingTheActuator) {
  for (const std::string gear : {"1e-320", "0"}) {
    write("model.xml", hinge_slide_mjcf("", R"(axis="0 1 0")", "gear=\"" + gear + "\""));
    const Result r = idmpc("check model.xml --samples 2");
    SCOPED_TRACE("gear " + gear);
    expect_error(r, {"'shoulder_motor'", "gear"});
    EXPECT_EQ(r.out.find("checks passed"), std::string::npos) << r.out;
  }
}

// features `check` lists as unmodeled are switched off in its MuJoCo reference, and it says so
class CliCheckUnmodeled : public Cli, public ::testing::WithParamInterface<std::pair<std::string, std::string>> {};

TEST_P(CliCheckUnmodeled, IsComparedWithoutIt) {
  const auto& [model, feature] = GetParam();
  write("model.xml", model);
  const Result r = idmpc("check model.xml --samples 3");
  EXPECT_EQ(r.code, 0) << r.err << r.out;
  EXPECT_NE(r.out.find("all 16 checks passed"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("  - " + feature + " switched off"), std::string::npos) << r.out;
}

INSTANTIATE_TEST_SUITE_P(
    Features, CliCheckUnmodeled,
    ::testing::Values(
        std::make_pair(hinge_slide_mjcf(R"(density="1000" viscosity="0.5" wind="1 0 0")"),
                       std::string("fluid forces (density/viscosity)")),
        std::make_pair(hinge_slide_mjcf("", R"(axis="0 1 0")", "",
                                        R"(<tendon><fixed name="spring" stiffness="50" damping="3">
      <joint joint="shoulder" coef="1"/><joint joint="rail" coef="0.5"/></fixed></tendon>)"),
                       std::string("tendon springs and dampers"))),
    [](const auto& info) { return std::string(info.index == 0 ? "fluid" : "tendon_spring"); });

// attributes, values and elements that MuJoCo 2.2 does not know: one line naming them and the
// version of this build, not the parser's text
class CliNewerMujoco : public Cli, public ::testing::WithParamInterface<std::pair<std::string, std::string>> {};

TEST_P(CliNewerMujoco, IsNamedInOneLine) {
  const auto& [model, needle] = GetParam();
  write("model.xml", model);
  const Result r = idmpc("check model.xml");
  expect_error(r, {needle, "needs a newer MuJoCo", "this build uses MuJoCo 2.2"});
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.find("Schema violation"), std::string::npos) << r.err;
}

std::string newer_mujoco_name(const ::testing::TestParamInfo<std::pair<std::string, std::string>>& info) {
  static const std::vector<std::string> names = {"actuatorgravcomp", "actearly", "replicate"};
  return names.at(info.index);
}

INSTANTIATE_TEST_SUITE_P(
    Models, CliNewerMujoco,
    ::testing::Values(std::make_pair(hinge_slide_mjcf("", R"(axis="0 1 0" actuatorgravcomp="true" actuatorfrcrange="-1 1")"),
                                     std::string("'actuatorgravcomp'")),
                      std::make_pair(hinge_slide_mjcf("", R"(axis="0 1 0")", R"(actearly="true")"),
                                     std::string("'actearly'")),
                      std::make_pair(hinge_slide_mjcf("", R"(axis="0 1 0")", "", "<replicate count=\"2\"/>"),
                                     std::string("<replicate>"))),
    newer_mujoco_name);

TEST_F(Cli, CheckNamesAMissingMeshFile) {
  write("model.xml", hinge_slide_mjcf("", R"(axis="0 1 0")", "",
                                      R"(<compiler meshdir="meshes"/><asset><mesh name="link" file="link.stl"/></asset>)"));
  const Result r = idmpc("check model.xml");
  expect_error(r, {"mesh file 'meshes/link.stl' does not exist"});
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(Cli, CheckRefusesAHugeTextureBeforeLoadingIt) {
  // MuJoCo 2.2 would need ~5 GB for it (or crash inside mj_loadXML); memory capped here
  write("model.xml", hinge_slide_mjcf("", R"(axis="0 1 0")", "",
                                      R"(<asset><texture name="sky" type="skybox" builtin="gradient" width="40000" height="40000"/></asset>)"));
  const Result r = idmpc("check model.xml", kMemoryCap);
  expect_error(r, {"'sky'", "40000x40000", "8192x8192"});
}

// ---------------------------------------------------------------------------------------------
// nothing lost: outputs checked before any work, failed writes reported, no stray files

// a model that includes part.xml (arm4): the included file is an input too
TEST_F(Cli, SwingupRefusesAnOutputThatTheModelIncludes) {
  fs::copy_file(kArm4, dir_ / "part.xml");
  write("main.xml", R"(<mujoco model="main"><include file="part.xml"/></mujoco>)");
  const Result r = idmpc("swingup main.xml --duration 0.01 --log part.xml");
  expect_error(r, {"--log 'part.xml'", "include"});
  EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
  EXPECT_EQ(slurp(dir_ / "part.xml"), slurp(kArm4));
  expect_no_temporaries();
}

// render reads the summary beside its log: an output onto it is refused
TEST_F(Cli, RenderRefusesAnOutputThatIsTheSummaryOfItsLog) {
  ASSERT_EQ(idmpc("swingup " + quote(kArm4) + " --duration 0.01 --log run.csv --summary run.json").code, 2);
  const std::string summary = slurp(dir_ / "run.json");
  const Result r = idmpc("render " + quote(kArm4) + " --log run.csv --out run.json");
  if (r.err.find("without rendering") != std::string::npos) GTEST_SKIP() << "no renderer in this build";
  expect_error(r, {"--out 'run.json'", "--log's summary 'run.json'"});
  EXPECT_EQ(slurp(dir_ / "run.json"), summary);
  expect_no_temporaries();
}

// a file name that JSON cannot hold is refused before the run, not after it
TEST_F(Cli, SwingupRefusesALogNameItsSummaryCannotRecordBeforeRunning) {
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.01 --log $(printf 'run\\377.csv') --summary s.json");
  expect_error(r, {"--log 'run\\xFF.csv'", "UTF-8"});
  EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(files(), std::vector<std::string>{}) << "nothing written";
}

// empty output paths are refused, naming the option
TEST_F(Cli, EmptyOutputPathsAreRefused) {
  for (const std::string& args :
       {"swingup " + quote(kArm4) + " --duration 0.01 --log ''", "swingup " + quote(kArm4) + " --summary ''",
        "dynamics " + quote(kArm4) + " --in in.csv --out ''", std::string("sweep --tables 3 --out ''")}) {
    SCOPED_TRACE(args);
    const Result r = idmpc(args);
    expect_error(r, {"--", "''"});
    EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
    EXPECT_EQ(r.out, "");
  }
  EXPECT_EQ(files(), std::vector<std::string>{});
}

// a valid output name of 250 bytes is written (its temporary must fit NAME_MAX too)
TEST_F(Cli, SwingupWritesOutputsWithLongNames) {
  const std::string log = std::string(246, 'l') + ".csv", summary = std::string(245, 's') + ".json";
  const Result r = idmpc("swingup " + quote(kArm4) + " --duration 0.01 --log " + log + " --summary " + summary);
  ASSERT_EQ(r.code, 2) << r.err;
  EXPECT_EQ(slurp(dir_ / log).rfind("t,q0,", 0), 0u);
  EXPECT_NE(slurp(dir_ / summary).find("\"steps\""), std::string::npos);
  expect_no_temporaries();
}

// what a command prints must reach standard output, or the command fails
TEST_F(Cli, ACommandWhoseOutputCannotBeWrittenFails) {
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const Result r = test::run_command("( " + quote(kBinary) + " check " + quote(kArm4) + " > /dev/full )", dir_);
  expect_error(r, {"standard output", "No space left on device"});
  EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
}

// a video's temporaries (its log, the video being encoded, ffmpeg's log) go when a signal ends
// the command while it renders
TEST_F(Cli, SwingupVideoInterruptedLeavesNoTemporary) {
  const std::string cmd = "cd " + quote(dir_.string()) + " && exec " + quote(kBinary) + " swingup " + quote(kArm4) +
                          " --duration 0.5 --video v.mp4 > .stdout 2> .stderr";
  const pid_t pid = test::start_command(cmd);
  ASSERT_GE(pid, 0);
  // wait until ffmpeg has begun the video: its temporary beside v.mp4 has bytes
  using clock = std::chrono::steady_clock;
  const auto deadline = clock::now() + std::chrono::seconds(20);
  bool encoding = false;
  int status = 0;
  bool exited = false;
  while (!encoding && !exited && clock::now() < deadline) {
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string name = e.path().filename().string();
      std::error_code ec;
      encoding |= name.rfind(".v.mp4.tmp.", 0) == 0 && fs::file_size(e.path(), ec) > 0 && !ec;
    }
    exited = ::waitpid(pid, &status, WNOHANG) == pid;
    if (!encoding) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (!exited) {
    ::kill(pid, SIGTERM);
    ::waitpid(pid, &status, 0);
  }
  const std::string err = slurp(dir_ / ".stderr");
  if (err.find("no renderer") != std::string::npos) GTEST_SKIP() << "no renderer in this build";
  ASSERT_TRUE(encoding) << "the video was never begun: " << err;
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << "status " << status << ": " << err;
  fs::remove(dir_ / ".stdout");
  fs::remove(dir_ / ".stderr");
  EXPECT_EQ(files(), std::vector<std::string>{}) << "left behind in the output's directory";
  const std::string mark = ".tmp." + std::to_string(pid) + ".";
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path())) {
    EXPECT_EQ(e.path().filename().string().find(mark), std::string::npos) << "left behind: " << e.path();
  }
}

// a sweep whose row cannot be written (a file size limit; SIGXFSZ ignored, so the write fails
// with EFBIG) says so in one line, exits non-zero and keeps every finished row whole
TEST_F(Cli, SweepKeepsItsFinishedRowsWhenARowCannotBeWritten) {
  const std::string args = "sweep --tables 3 --duration 0.01 --out sweep";
  // a limit of 1024 bytes (two of the shell's 512-byte blocks): sweep.md (~760 bytes) passes,
  // sweep.csv (~1650 bytes for its 8 rows) does not
  const int blocks = 2;
  // the limit holds for the sweep only: its output goes through a pipe, its exit code to a file
  Result r = test::run_command("( trap '' XFSZ; ulimit -f " + std::to_string(blocks) + "; " + quote(kBinary) + " " +
                                   args + "; echo $? > .code ) 2>&1 | cat",
                               dir_);
  r.code = std::stoi("0" + slurp(dir_ / ".code"));
  r.err = r.out;  // stdout and stderr together
  fs::remove(dir_ / ".code");
  expect_error(r, {"cannot write 'sweep/sweep.csv'", "File too large"});
  EXPECT_EQ(r.err.find("written"), std::string::npos) << r.err;
  const std::vector<std::string> err = lines_of(r.err);
  ASSERT_FALSE(err.empty());
  EXPECT_EQ(err.back().rfind("idmpc: error: ", 0), 0u) << r.err;
  const std::vector<std::string> rows = lines_of(slurp(dir_ / "sweep" / "sweep.csv"));
  ASSERT_GE(rows.size(), 2u) << "the rows that fit are kept";
  ASSERT_LT(rows.size(), 9u);
  for (const std::string& row : rows) EXPECT_EQ(split(row).size(), split(rows[0]).size()) << row;
  EXPECT_EQ(slurp(dir_ / "sweep" / "sweep.csv").back(), '\n');
  for (const auto& e : fs::directory_iterator(dir_ / "sweep")) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
  // resumed without the limit: the kept rows are done
  const Result again = idmpc(args);
  ASSERT_EQ(again.code, 0) << again.err;
  size_t done = 0;
  for (size_t pos = again.err.find("done earlier"); pos != std::string::npos; pos = again.err.find("done earlier", pos + 1)) {
    ++done;
  }
  EXPECT_EQ(done, rows.size() - 1) << again.err;
}

// the settings of every cell are checked before any file is made; the error has its own line
TEST_F(Cli, SweepRefusesABadDurationBeforeMakingAnyFile) {
  const Result r = idmpc("sweep --tables 3 --duration 1e-9 --out sweep");
  expect_error(r, {"duration"});
  EXPECT_EQ(lines_of(r.err).size(), 1u) << r.err;
  EXPECT_EQ(r.err.rfind("idmpc: error: ", 0), 0u) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "sweep"));
}

// a resumed sweep removes the temporaries that a killed sweep left in its directory, and only those
TEST_F(Cli, SweepRemovesTheTemporariesOfAKilledSweep) {
  const pid_t dead = ::fork();
  ASSERT_GE(dead, 0);
  if (dead == 0) ::_exit(0);
  ::waitpid(dead, nullptr, 0);
  const std::string d = std::to_string(dead), alive = std::to_string(::getpid());
  fs::create_directory(dir_ / "sweep");
  const std::vector<std::string> stale = {".arms.csv.tmp." + d + ".0", ".arms.md.tmp." + d + ".3",
                                          "arms.csv.tmp." + d + ".1", ".log_arms_touch_fd_matrix_N10_k5.csv.tmp." + d + ".2"};
  const std::vector<std::string> kept = {".arms.md.tmp." + alive + ".0", "notes.tmp.txt", ".other.csv.tmp." + d + ".0"};
  for (const std::string& name : stale) std::ofstream(dir_ / "sweep" / name) << "half";
  for (const std::string& name : kept) std::ofstream(dir_ / "sweep" / name) << "keep";
  fs::create_directories(dir_ / "mine");
  write("mine/touch.xml", kTouchModel);
  write("mine/touch.json", kTouchTask);
  write("mine/list.json", R"({"tasks": ["touch.json"]})");
  const Result r = idmpc("sweep --arms-tasks mine/list.json --duration 0.01 --out sweep");
  ASSERT_EQ(r.code, 0) << r.err;
  for (const std::string& name : stale) EXPECT_FALSE(fs::exists(dir_ / "sweep" / name)) << name;
  for (const std::string& name : kept) EXPECT_TRUE(fs::exists(dir_ / "sweep" / name)) << name;
}

// a resumed sweep whose model file changed does not take the old cells for its own
TEST_F(Cli, SweepResumedWithAChangedModelKeepsNoOldCell) {
  fs::create_directories(dir_ / "mine");
  write("mine/touch.xml", kTouchModel);
  write("mine/touch.json", kTouchTask);
  write("mine/list.json", R"({"tasks": ["touch.json"]})");
  const std::string args = "sweep --arms-tasks mine/list.json --duration 0.01 --out sweep";
  ASSERT_EQ(idmpc(args).code, 0);
  const std::string before = slurp(dir_ / "sweep" / "arms.csv");
  // the same model with other masses: other results
  std::string model = kTouchModel;
  const size_t mass = model.find("mass=\"");
  ASSERT_NE(mass, std::string::npos);
  model.insert(mass + 6, "1");
  write("mine/touch.xml", model);
  const Result r = idmpc(args);
  expect_error(r, {"arms.csv", "other settings"});
  EXPECT_EQ(slurp(dir_ / "sweep" / "arms.csv"), before) << "the earlier results must be kept";
}

}  // namespace
}  // namespace idmpc
