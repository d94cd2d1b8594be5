// Experiments are data: task files over the paper's base task, the paper's tables, and the run
// record's one writer and one reader (a summary and a log survive a round trip unchanged).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <unistd.h>
#include <string>

#include "idmpc/experiment/run_record.hpp"
#include "idmpc/experiment/task.hpp"

namespace idmpc {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("idmpc_experiment_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string write(const std::string& name, const std::string& text) const {
    const fs::path p = path_ / name;
    std::ofstream(p) << text;
    return p.string();
  }

 private:
  fs::path path_;
};

template <typename Fn> std::string message_of(Fn&& fn) {
  try {
    fn();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(PaperTask, IsTheDesignsSetup) {
  const Task& t = paper_task();
  EXPECT_EQ(fs::path(t.model).filename(), "arm4.xml");
  EXPECT_TRUE(fs::exists(t.model)) << t.model;
  EXPECT_EQ(t.q0_rule, "swingup");
  EXPECT_EQ(t.N, 25);
  EXPECT_EQ(t.kmax, 10);
  const ResolvedTask r = resolve(t, 4);
  EXPECT_EQ(r.q0, (VecX<double>(4) << -M_PI, 0, 0, 0).finished());
  EXPECT_TRUE(r.controller.q_ref.isZero(0.0));
  EXPECT_EQ(r.controller.weights.R, VecX<double>::Constant(4, 1e-4));
  EXPECT_DOUBLE_EQ(r.controller.cgmres.dt, 1e-3);
  EXPECT_DOUBLE_EQ(t.Qa_fallback, 1e-4);
}

// a divergence's hint names what applies to the solver that diverged
TEST(PaperTask, DivergenceHintsNameTheSolversOwnSettings) {
  Task t = paper_task();
  const std::string cgmres = divergence_hint(t);
  EXPECT_NE(cgmres.find("--zeta"), std::string::npos) << cgmres;
  EXPECT_EQ(cgmres.find("--iterations"), std::string::npos) << cgmres;
  EXPECT_NE(cgmres.find("--solver riccati"), std::string::npos) << cgmres;
  t.solver = "riccati";
  const std::string riccati = divergence_hint(t);
  EXPECT_NE(riccati.find("--iterations 3"), std::string::npos) << riccati;
  EXPECT_NE(riccati.find("line_search"), std::string::npos) << riccati;
  EXPECT_EQ(riccati.find("--zeta"), std::string::npos) << riccati;
  EXPECT_EQ(riccati.find("--alpha"), std::string::npos) << riccati;
  EXPECT_EQ(riccati.find("--solver"), std::string::npos) << riccati;
}

// Where FD's single-shooting rollout is ill-conditioned (λT_f above kIllConditionedGrowth), the
// hint names only what applies there, with the numbers of this model: ID, the Riccati solver, a
// horizon of 4/λ at the same step (N = 4/(λΔτ) rounded), multiple shooting; not ζ, N or R, which
// did not help. Below the threshold, or for ID or the Riccati solver, the usual hint.
TEST(PaperTask, AnIllConditionedFdRolloutsHintNamesWhatAppliesThere) {
  Task t = arm_defaults();  // FD below: T_f = 0.5 s, N = 25, Δτ = 20 ms
  t.formulation = "fd";
  const double lambda = 20;  // e^{λT_f} = e^10 ≈ 2.2e4
  const std::string fd = divergence_hint(t, 0, lambda);
  EXPECT_EQ(fd.rfind("try --formulation id", 0), 0u) << fd;
  EXPECT_NE(fd.find("diverges at 20 1/s"), std::string::npos) << fd;
  EXPECT_NE(fd.find("amplifies by 2.2e+04"), std::string::npos) << fd;
  EXPECT_NE(fd.find("--solver riccati"), std::string::npos) << fd;
  EXPECT_NE(fd.find("--Tf 0.2 --N 10 "), std::string::npos) << fd;  // 4/λ = 0.2 s at 20 ms
  EXPECT_NE(fd.find("--shooting multiple"), std::string::npos) << fd;
  for (const char* unhelpful : {"--zeta", "--N 25", "larger --N", "--R"}) {
    EXPECT_EQ(fd.find(unhelpful), std::string::npos) << unhelpful << " in " << fd;
  }
  // just below e^4.5 over the horizon: the usual hint, ID among its tries
  const std::string below = divergence_hint(t, 0, 0.99 * kIllConditionedGrowth / t.Tf);
  EXPECT_EQ(below.rfind("try --solver riccati", 0), 0u) << below;
  EXPECT_NE(below.find("--formulation id"), std::string::npos) << below;
  EXPECT_EQ(below.find("diverges at"), std::string::npos) << below;
  EXPECT_NE(below.find("--zeta"), std::string::npos) << below;
  const std::string above = divergence_hint(t, 0, 1.01 * kIllConditionedGrowth / t.Tf);
  EXPECT_EQ(above.rfind("try --formulation id", 0), 0u) << above;
  t.formulation = "id";
  EXPECT_EQ(divergence_hint(t, 0, lambda).find("--formulation id"), std::string::npos);
  t.formulation = "fd";
  t.solver = "riccati";
  EXPECT_EQ(divergence_hint(t, 0, lambda).find("--formulation id"), std::string::npos);
}

TEST(TaskFile, FieldsOverrideTheBaseAndPathsAreRelativeToTheFile) {
  TempDir dir;
  const std::string path = dir.write("mine.json", R"({
    "model": "robots/my_arm.xml", "q0": [0.1, 0.2], "qref": [1, 2], "formulation": "fd",
    "weights": {"R": [0.01, 0.02]}, "cgmres": {"N": 10, "alpha": 0, "init_full_horizon": true}})");
  const Task t = load_task(path);
  EXPECT_TRUE(t.init_full_horizon);
  EXPECT_FALSE(paper_task().init_full_horizon);  // the paper grows its horizon from zero
  EXPECT_EQ(fs::path(t.model), fs::path(path).parent_path() / "robots/my_arm.xml");
  EXPECT_EQ(t.formulation, "fd");
  EXPECT_EQ(t.N, 10);
  EXPECT_EQ(t.kmax, arm_defaults().kmax);       // from the base: the defaults for real arms
  EXPECT_TRUE(t.Qq.empty());                   // "auto", resolved with the model
  EXPECT_TRUE(t.offset_free);
  EXPECT_EQ(t.implicit_damping, "auto");
  const ResolvedTask r = resolve(t, 2);
  EXPECT_EQ(r.controller.weights.Qq.size(), 0);
  EXPECT_EQ(r.q0, (VecX<double>(2) << 0.1, 0.2).finished());
  EXPECT_EQ(r.controller.weights.R, (VecX<double>(2) << 0.01, 0.02).finished());
  EXPECT_EQ(r.controller.formulation, Formulation::kForwardDynamics);
  EXPECT_TRUE(r.controller.cgmres.init_full_horizon);
  EXPECT_EQ(r.controller.cgmres.alpha, 0.0);
  // and it survives the round trip through a summary's task
  const Task back = task_from_json(to_json(t), "round trip", Task{});
  EXPECT_TRUE(back.init_full_horizon);
  EXPECT_TRUE(back.Qq.empty());
  EXPECT_EQ(back.R, t.R);
  EXPECT_EQ(back.implicit_damping, "auto");
  EXPECT_EQ(back.offset_free, t.offset_free);
  EXPECT_EQ(back.reach_tolerance, t.reach_tolerance);
}

// a user's file that names only the model, q0 and q_ref takes everything else from the defaults
// for real arms; the paper's task names every field itself and runs without offset-free tracking
TEST(TaskFile, AMinimalFileTakesTheDefaultsForRealArmsAndThePaperStatesItsOwn) {
  TempDir dir;
  const Task t = load_task(dir.write("min.json", R"({"model": "arm.xml", "q0": "home", "qref": [0.1, 0.2]})"));
  const Task& d = arm_defaults();
  EXPECT_EQ(t.q0_rule, "home");
  EXPECT_EQ(t.N, d.N);
  EXPECT_EQ(t.duration, d.duration);
  EXPECT_TRUE(t.init_full_horizon);
  EXPECT_EQ(t.alpha, 0.0);
  EXPECT_TRUE(t.offset_free);
  EXPECT_GT(t.observer_time_constant, 0.0);
  EXPECT_EQ(t.implicit_damping, "auto");
  EXPECT_TRUE(t.friction_velocity.empty());
  EXPECT_EQ(t.reach_tolerance, 5e-3);
  const Task& p = paper_task();
  EXPECT_FALSE(p.offset_free);
  EXPECT_EQ(p.implicit_damping, "off");
  EXPECT_FALSE(p.Qq.empty());
  EXPECT_FALSE(p.R.empty());
  EXPECT_EQ(p.alpha, 1.0);
  // weights may be "auto" by name, and anything else that is a string is refused
  const Task a = load_task(dir.write("auto.json", R"({"weights": {"R": "auto", "Qq": 5}})"));
  EXPECT_TRUE(a.R.empty());
  EXPECT_EQ(a.Qq, std::vector<double>{5});
  EXPECT_NE(message_of([&] { load_task(dir.write("bad.json", R"({"weights": {"R": "big"}})")); }).find("'R'"),
            std::string::npos);
  EXPECT_NE(message_of([&] { load_task(dir.write("bad2.json", R"({"implicit_damping": "yes"})")); })
                .find("'implicit_damping'"),
            std::string::npos);
}

TEST(TaskFile, BadFilesNameFileAndField) {
  TempDir dir;
  const std::string typo = dir.write("typo.json", R"({"weigths": {}})");
  EXPECT_NE(message_of([&] { load_task(typo); }).find("unknown field 'weigths'"), std::string::npos);
  const std::string inner = dir.write("inner.json", R"({"cgmres": {"kmx": 3}})");
  EXPECT_NE(message_of([&] { load_task(inner); }).find("'kmx'"), std::string::npos);
  const std::string type = dir.write("type.json", R"({"cgmres": {"N": "many"}})");
  const std::string m = message_of([&] { load_task(type); });
  EXPECT_NE(m.find("type.json"), std::string::npos) << m;
  EXPECT_NE(m.find("'N'"), std::string::npos) << m;
  const std::string broken = dir.write("broken.json", "{");
  EXPECT_NE(message_of([&] { load_task(broken); }).find("broken.json"), std::string::npos);
  EXPECT_NE(message_of([&] { load_task(dir.write("q0.json", R"({"q0": "upright"})")); }).find("q0"),
            std::string::npos);
  // resolution names the option and the field
  Task t = paper_task();
  t.Qq = {1, 2, 3};
  EXPECT_NE(message_of([&] { resolve(t, 4); }).find("--Qq (weights.Qq) has 3 values"), std::string::npos);
  t = paper_task();
  t.R = {-1};
  EXPECT_NE(message_of([&] { resolve(t, 4); }).find("non-negative"), std::string::npos);
}

TEST(PaperTables, HoldTables1To3) {
  const PaperTables t = load_paper_tables();
  EXPECT_EQ(t.cells.size(), 32u);  // 2 × 3 × 4 for Tables 1–2, 2 × 4 for Table 3
  const PaperCell* fd = t.find("12", "fd", 4, 25, 10);
  const PaperCell* id = t.find("12", "id", 4, 25, 10);
  ASSERT_TRUE(fd && id);
  EXPECT_DOUBLE_EQ(fd->ms, 2.0);
  EXPECT_DOUBLE_EQ(id->ms, 1.3);
  EXPECT_EQ(t.find("12", "fd", 4, 10, 3)->mark, "*");
  EXPECT_EQ(t.find("12", "id", 4, 50, 5)->mark, "†");
  EXPECT_DOUBLE_EQ(t.find("3", "id", 32, 25, 10)->ms, 16);
  EXPECT_EQ(t.task, paper_task_path());
  for (const PaperCell& c : t.cells) {
    EXPECT_TRUE(fs::exists(fs::path(t.task).parent_path() / c.model)) << c.model;
  }
}

TEST(RunRecord, SummaryRoundTripsAndRefusesOtherSchemas) {
  RunSummary s;
  s.task = paper_task();
  s.task.formulation = "fd";
  s.task.q0 = {0.5, 0, 0, 0};
  s.task.q0_rule.clear();
  s.n = 4;
  s.steps = 123;
  s.diverged = true;
  s.diverged_at = 0.122;
  s.divergence_reason = "why";
  s.mean_update_ms = 1.5;
  s.p50_update_ms = std::nan("");
  s.unmodeled = {"contacts"};
  s.torque_lower = {-87, -std::numeric_limits<double>::infinity(), -1, -1};
  s.torque_upper = {87, std::numeric_limits<double>::infinity(), 1, 1};
  s.saturated_steps = {3, 0, 1, 0};
  s.saturated_any = 4;
  s.max_constraint_violation = 0.25;
  s.open_loop_rate = 12.5;
  s.model_hash = "fnv1a64:0123456789abcdef";
  s.log_hash = "fnv1a64:fedcba9876543210";
  const RunSummary back = summary_from_json(nlohmann::json::parse(to_json(s).dump()), "x.json");
  EXPECT_EQ(to_json(back).dump(), to_json(s).dump());
  EXPECT_EQ(back.label(), "C/GMRES (FD, adjoint) N=25 kmax=10");
  // a task as run names its solver; a record whose task leaves it unnamed is read as C/GMRES
  nlohmann::json unnamed = to_json(s);
  ASSERT_EQ(unnamed.at("task").at("solver"), "cgmres");
  unnamed.at("task").erase("solver");
  EXPECT_EQ(summary_from_json(unnamed, "x.json").task.solver, "cgmres");
  RunSummary multiple = back;
  multiple.task.shooting = "multiple";
  EXPECT_EQ(multiple.label(), "C/GMRES (FD, adjoint, multiple shooting) N=25 kmax=10");
  EXPECT_TRUE(std::isnan(back.p50_update_ms));
  EXPECT_EQ(back.torque_upper, s.torque_upper);  // unbounded joints survive as null
  EXPECT_EQ(back.max_constraint_violation, 0.25);
  EXPECT_EQ(back.model_hash, s.model_hash);
  EXPECT_EQ(back.log_hash, s.log_hash);
  s.max_constraint_violation = std::nan("");  // non-finite OCP torques stay visible
  EXPECT_TRUE(std::isnan(summary_from_json(to_json(s), "x.json").max_constraint_violation));

  nlohmann::json other = to_json(s);
  other["schema"] = 99;
  EXPECT_NE(message_of([&] { summary_from_json(other, "old.json"); }).find("old.json"), std::string::npos);
  nlohmann::json missing = to_json(s);
  missing.erase("steps");
  EXPECT_NE(message_of([&] { summary_from_json(missing, "m.json"); }).find("m.json"), std::string::npos);
}

TEST(RunRecord, LogWrittenIsLogRead) {
  TempDir dir;
  for (bool commanded : {false, true}) {
    SCOPED_TRACE(commanded ? "with commanded torques" : "without");
    std::ostringstream text;
    {
      RunLogWriter w(text, 2, commanded);
      const VecX<double> q = (VecX<double>(2) << -3.1, 0.25).finished(), v = VecX<double>::Constant(2, 0.5),
                         u = (VecX<double>(2) << 12.5, -1e-7).finished(), uc = (VecX<double>(2) << 99, -1e-7).finished();
      w.row(0.0, q, v, u, uc, 1e-3, 0.2);
      w.row(0.001, q, v, u, uc, std::nan(""), 0.3);
    }
    EXPECT_EQ(text.str().substr(0, text.str().find('\n')),
              commanded ? "t,q0,q1,v0,v1,u0,u1,uc0,uc1,residual,update_ms" : "t,q0,q1,v0,v1,u0,u1,residual,update_ms");
    const std::string path = dir.write("run.csv", text.str());
    const RunLog log = read_run_log(path);
    EXPECT_EQ(log.n, 2);
    ASSERT_EQ(log.rows(), 2u);
    EXPECT_DOUBLE_EQ(log.q_row(0)[0], -3.1);
    EXPECT_DOUBLE_EQ(log.u_row(1)[0], 12.5);
    EXPECT_DOUBLE_EQ(log.u_row(1)[1], -1e-7);
    EXPECT_EQ(log.u_commanded.size(), commanded ? 4u : 0u);
    if (commanded) {
      EXPECT_DOUBLE_EQ(log.u_commanded[2], 99);
    }
    EXPECT_TRUE(std::isnan(log.residual[1]));
    EXPECT_DOUBLE_EQ(log.update_ms[1], 0.3);
    EXPECT_EQ(log.label, "run");
  }
}

TEST(RunRecord, FrameColumnsAreRead) {
  TempDir dir;
  std::ostringstream text;
  {
    RunLogWriter w(text, 2, false, true);
    const VecX<double> q = VecX<double>::Constant(2, 0.1), v = q, u = q, uc = q;
    const Vec3<double> p0(0.5, 0.1, 0.4), r0(0.5, 0.1, 0.45), p1(0.6, -0.2, 0.3), r1(0.61, -0.2, 0.3);
    w.row(0.0, q, v, u, uc, 1e-3, 0.2, &p0, &r0);
    w.row(0.001, q, v, u, uc, 1e-3, 0.2, &p1, &r1);
    w.row(0.002, q, v, u, uc, 1e-3, 0.2);  // no measurement: NaN
  }
  EXPECT_EQ(text.str().substr(0, text.str().find('\n')),
            "t,q0,q1,v0,v1,u0,u1,residual,update_ms,x,y,z,x_ref,y_ref,z_ref");
  const RunLog log = read_run_log(dir.write("frame.csv", text.str()));
  ASSERT_EQ(log.rows(), 3u);
  ASSERT_EQ(log.frame.size(), 9u);
  ASSERT_EQ(log.frame_ref.size(), 9u);
  EXPECT_DOUBLE_EQ(log.frame[2], 0.4);
  EXPECT_DOUBLE_EQ(log.frame_ref[2], 0.45);
  EXPECT_DOUBLE_EQ(log.frame[4], -0.2);
  EXPECT_DOUBLE_EQ(log.frame_ref[3], 0.61);
  EXPECT_TRUE(std::isnan(log.frame[6]) && std::isnan(log.frame_ref[8]));
  // the columns before them are read as without them
  EXPECT_DOUBLE_EQ(log.residual[1], 1e-3);
  EXPECT_DOUBLE_EQ(log.update_ms[1], 0.2);

  // a log without them has none
  const RunLog plain = read_run_log(dir.write("plain.csv", "t,q0,v0,u0,residual,update_ms\n0,0,0,0,0,0\n"));
  EXPECT_EQ(plain.rows(), 1u);
  EXPECT_TRUE(plain.frame.empty());
  EXPECT_TRUE(plain.frame_ref.empty());

  // some of them, or them out of order, is a bad header
  for (const std::string extra : {",x,y,z", ",x,y,z,x_ref,y_ref", ",x_ref,y_ref,z_ref,x,y,z", ",x,y,z,x_ref,y_ref,z_ref,w"}) {
    const int cells = 6 + static_cast<int>(std::count(extra.begin(), extra.end(), ','));
    std::string row = "0";
    for (int c = 1; c < cells; ++c) row += ",0";
    const std::string path = dir.write("partial.csv", "t,q0,v0,u0,residual,update_ms" + extra + "\n" + row + "\n");
    const std::string msg = message_of([&] { read_run_log(path); });
    EXPECT_NE(msg.find("line 1: bad header"), std::string::npos) << extra << ": " << msg;
    EXPECT_NE(msg.find("x_ref"), std::string::npos) << msg;  // the expected shape names them
  }
}

TEST(RunRecord, SummariesWithoutHashesAreStillRead) {
  RunSummary s;
  s.task = paper_task();
  s.n = 4;
  nlohmann::json old = to_json(s);
  EXPECT_FALSE(old.contains("model_hash"));  // not written when unknown
  EXPECT_FALSE(old.contains("log_hash"));
  const RunSummary back = summary_from_json(old, "old.json");
  EXPECT_EQ(back.model_hash, "");
  EXPECT_EQ(back.log_hash, "");
}

TEST(RunRecord, FileHashIsFnv1aOfTheBytes) {
  TempDir dir;
  // FNV-1a 64 test vectors
  EXPECT_EQ(file_hash(dir.write("empty", "")), "fnv1a64:cbf29ce484222325");
  EXPECT_EQ(file_hash(dir.write("a", "a")), "fnv1a64:af63dc4c8601ec8c");
  const std::string big(200000, 'x');
  EXPECT_EQ(file_hash(dir.write("big1", big)), file_hash(dir.write("big2", big)));
  EXPECT_NE(file_hash(dir.write("big1", big)), file_hash(dir.write("big3", big + "y")));
  EXPECT_EQ(file_hash(""), "");
  EXPECT_EQ(file_hash(fs::temp_directory_path().string()), "");  // a directory
  EXPECT_EQ(file_hash("/dev/null"), "");                          // a device is never read
}

// a 4-joint log of `rows` rows and, beside it, a summary of `n` joints and `steps` steps
class SiblingSummary : public ::testing::Test {
 protected:
  std::string log(int rows) {
    std::ostringstream text;
    {
      RunLogWriter w(text, 4, false);
      const VecX<double> q = VecX<double>::Zero(4), v = q, u = q, uc = q;
      for (int k = 0; k < rows; ++k) w.row(1e-3 * k, q, v, u, uc, 0.1, 0.2);
    }
    return dir_.write("run.csv", text.str());
  }
  void summary(int n, int steps, const std::string& log_hash = "") {
    RunSummary s;
    s.task = paper_task();
    s.task.formulation = "fd";
    s.task.derivatives = "matrix";
    s.n = n;
    s.steps = steps;
    s.model_hash = "fnv1a64:0000000000000001";
    s.log_hash = log_hash;
    dir_.write("run.json", to_json(s).dump());
  }
  TempDir dir_;
};

TEST_F(SiblingSummary, OfThisRunLabelsTheLogAndNamesItsModel) {
  const std::string csv = log(5);
  summary(4, 5, file_hash(csv));
  const RunLog l = read_run_log(csv);
  EXPECT_EQ(l.label, "C/GMRES (FD, matrix) N=25 kmax=10");
  EXPECT_EQ(l.formulation, "fd");
  EXPECT_EQ(l.model_hash, "fnv1a64:0000000000000001");
  EXPECT_EQ(l.summary_model, paper_task().model);
  EXPECT_EQ(fs::path(l.summary_path).filename(), "run.json");
  EXPECT_EQ(l.summary_warning, "");
}

TEST_F(SiblingSummary, OfAnotherRunIsNotUsed) {
  const std::string csv = log(5);
  struct Case {
    int n, steps;
    std::string log_hash, needle;
  };
  for (const Case& c : {Case{3, 5, "", "3 joints"}, Case{4, 7, "", "7 control steps"},
                        Case{4, 5, "fnv1a64:0000000000000002", "fnv1a64:0000000000000002"}}) {
    summary(c.n, c.steps, c.log_hash);
    const RunLog l = read_run_log(csv);
    EXPECT_EQ(l.label, "run") << c.needle;
    EXPECT_EQ(l.formulation, "");
    EXPECT_EQ(l.model_hash, "");
    EXPECT_NE(l.summary_warning.find("run.json"), std::string::npos) << l.summary_warning;
    EXPECT_NE(l.summary_warning.find(c.needle), std::string::npos) << l.summary_warning;
  }
}

TEST_F(SiblingSummary, ThatIsBrokenDoesNotBlockTheLog) {
  const std::string csv = log(5);
  for (const std::string text : {"{", "{\"schema\": 1}", "[]", "{\"schema\": 7}"}) {
    dir_.write("run.json", text);
    RunLog l;
    EXPECT_NO_THROW(l = read_run_log(csv)) << text;
    EXPECT_EQ(l.rows(), 5u);
    EXPECT_EQ(l.label, "run");
    EXPECT_NE(l.summary_warning.find("run.json"), std::string::npos) << l.summary_warning;
    EXPECT_NE(l.summary_warning.find("file name"), std::string::npos) << l.summary_warning;
  }
}

}  // namespace
}  // namespace idmpc
