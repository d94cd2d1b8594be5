#include "app/swingup.hpp"

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "app/atomic_file.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::app {
namespace {

// a scalar broadcast to every joint, or exactly one value per joint
VecX<double> per_joint(const std::vector<double>& values, int n, const std::string& option) {
  if (values.size() == 1) return VecX<double>::Constant(n, values[0]);
  if (static_cast<int>(values.size()) == n) {
    return Eigen::Map<const VecX<double>>(values.data(), n);
  }
  throw std::invalid_argument(option + " has " + std::to_string(values.size()) +
                              " values, expected 1 or " + std::to_string(n) + " (one per joint)");
}

VecX<double> non_negative(VecX<double> x, const std::string& option) {
  for (int i = 0; i < x.size(); ++i) {
    if (!(x[i] >= 0) || !std::isfinite(x[i])) {
      throw std::invalid_argument(option + " must be finite and non-negative, got " + std::to_string(x[i]));
    }
  }
  return x;
}

nlohmann::json to_json(const VecX<double>& x) { return std::vector<double>(x.data(), x.data() + x.size()); }

}  // namespace

void add_swingup_options(CLI::App& sub, SwingupOptions& opt) {
  sub.add_option("--formulation", opt.formulation, "fd (torques, ABA) or id (accelerations, RNEA)")
      ->capture_default_str();
  sub.add_option("--derivatives", opt.derivatives, "matrix (the paper's) or adjoint (O(n))")
      ->capture_default_str();
  sub.add_option("--N", opt.N, "horizon steps")->capture_default_str();
  sub.add_option("--kmax", opt.kmax, "GMRES iterations per update")->capture_default_str();
  sub.add_option("--Tf", opt.Tf, "final horizon length [s]")->capture_default_str();
  sub.add_option("--alpha", opt.alpha, "horizon growth rate [1/s]")->capture_default_str();
  sub.add_option("--dt", opt.dt, "sampling period and plant step [s]")->capture_default_str();
  sub.add_option("--zeta", opt.zeta, "C/GMRES stabilization (0: 1/dt)")->capture_default_str();
  sub.add_option("--h", opt.h, "forward-difference increment of the Frechet products")->capture_default_str();
  sub.add_option("--duration", opt.duration, "simulated time [s]")->capture_default_str();
  sub.add_option("--q0", opt.q0, "initial joint positions, one per joint (default -pi, 0, ...)");
  sub.add_option("--qref", opt.qref, "target joint positions: a scalar or one per joint (default 0)");
  sub.add_option("--Qq", opt.Qq, "weight on q - qref: scalar or one per joint")->capture_default_str();
  sub.add_option("--Qv", opt.Qv, "weight on v: scalar or one per joint")->capture_default_str();
  sub.add_option("--Qa", opt.Qa, "weight on a (ID only): scalar or one per joint")->capture_default_str();
  sub.add_option("--R", opt.R, "weight on torque: scalar or one per joint")->capture_default_str();
  sub.add_flag("--direct-torque", opt.direct_torque,
               "ignore the model's actuators and apply joint torques directly");
  sub.add_flag("!--no-simd-stages", opt.simd_stages,
               "ID + adjoint: evaluate the horizon stages one by one instead of in SIMD lanes");
}

SwingupOutcome run_swingup(const SwingupOptions& opt, const std::string& log_path) {
  // validate everything before any output is opened
  const Formulation formulation = parse_formulation(opt.formulation);
  const DerivativeMode mode = parse_derivative_mode(opt.derivatives);
  if (opt.N < 1) throw std::invalid_argument("--N must be at least 1, got " + std::to_string(opt.N));
  CgmresSettings cs;
  cs.kmax = opt.kmax;
  cs.Tf = opt.Tf;
  cs.alpha = opt.alpha;
  cs.dt = opt.dt;
  cs.zeta = opt.zeta;
  cs.h = opt.h;
  cs.validate();
  if (!(opt.duration > 0) || !std::isfinite(opt.duration)) {
    throw std::invalid_argument("--duration must be positive, got " + std::to_string(opt.duration));
  }
  const mj::ModelPtr m = mj::load_model(opt.model);
  const mj::ImportedModel imported =
      mj::import_model(m.get(), opt.model, mj::ImportOptions{opt.direct_torque});
  const Model& model = imported.model;
  const int n = model.n;
  OcpWeights w{non_negative(per_joint(opt.Qq, n, "--Qq"), "--Qq"),
               non_negative(per_joint(opt.Qv, n, "--Qv"), "--Qv"),
               non_negative(per_joint(opt.Qa, n, "--Qa"), "--Qa"),
               non_negative(per_joint(opt.R, n, "--R"), "--R")};
  const VecX<double> q_ref = opt.qref.empty() ? VecX<double>::Zero(n) : per_joint(opt.qref, n, "--qref");
  VecX<double> q0 = VecX<double>::Zero(n);
  q0[0] = -M_PI;
  if (!opt.q0.empty()) {
    if (static_cast<int>(opt.q0.size()) != n) {
      throw std::invalid_argument("--q0 has " + std::to_string(opt.q0.size()) + " values, expected " +
                                  std::to_string(n) + " (one per joint)");
    }
    q0 = Eigen::Map<const VecX<double>>(opt.q0.data(), n);
  }
  if (!q0.allFinite() || !q_ref.allFinite()) throw std::invalid_argument("--q0/--qref must be finite");

  Ocp ocp(model, formulation, mode, w, q_ref, opt.N);
  ocp.set_stage_batching(opt.simd_stages);
  Cgmres solver(ocp, cs);
  mj::Plant plant(m.get(), imported.actuation);
  mj::ClosedLoopSettings ls;
  ls.duration = opt.duration;
  ls.q0 = q0;
  ls.v0 = VecX<double>::Zero(n);

  // the log streams to a temporary file, renamed once the run has ended
  std::optional<AtomicFile> log;
  if (!log_path.empty()) {
    log.emplace(log_path);
    auto& out = log->stream();
    out << "t";
    for (const char* p : {"q", "v", "u"}) {
      for (int i = 0; i < n; ++i) out << ',' << p << i;
    }
    out << ",residual,update_ms\n" << std::setprecision(10);
  }
  auto on_step = [&](const mj::StepRecord& r) {
    if (!log) return;
    auto& out = log->stream();
    out << r.t;
    for (const VecX<double>* x : {&r.q, &r.v, &r.u}) {
      for (int i = 0; i < n; ++i) out << ',' << (*x)[i];
    }
    out << ',' << r.residual << ',' << r.update_ms << '\n';
  };
  mj::RunResult result = mj::run_closed_loop(plant, ocp, solver, q_ref, ls, on_step);
  if (log) log->commit();

  nlohmann::json s;
  s["model"] = opt.model;
  s["n"] = n;
  s["formulation"] = opt.formulation;
  s["derivatives"] = opt.derivatives;
  s["simd_stages"] = ocp.stage_batching();
  s["N"] = opt.N;
  s["kmax"] = opt.kmax;
  s["Tf"] = opt.Tf;
  s["alpha"] = opt.alpha;
  s["dt"] = opt.dt;
  s["zeta"] = solver.settings().zeta;
  s["h"] = opt.h;
  s["Qq"] = to_json(w.Qq);
  s["Qv"] = to_json(w.Qv);
  s["Qa"] = to_json(w.Qa);
  s["R"] = to_json(w.R);
  s["q0"] = to_json(q0);
  s["qref"] = to_json(q_ref);
  s["duration"] = opt.duration;
  s["steps"] = result.steps;
  s["diverged"] = result.diverged;
  s["diverged_at"] = result.diverged ? nlohmann::json(result.diverged_at) : nlohmann::json(nullptr);
  s["divergence_reason"] = result.divergence_reason;
  s["mean_update_ms"] = result.update_ms.empty() ? 0.0 : [&] {
    double sum = 0;
    for (double x : result.update_ms) sum += x;
    return sum / static_cast<double>(result.update_ms.size());
  }();
  s["p50_update_ms"] = mj::percentile(result.update_ms, 50);
  s["p95_update_ms"] = mj::percentile(result.update_ms, 95);
  s["max_update_ms"] = mj::percentile(result.update_ms, 100);
  s["phase_ms"] = {{"rollout", result.mean_phase_ms.rollout},
                   {"costate", result.mean_phase_ms.costate},
                   {"gmres", result.mean_phase_ms.gmres}};
  s["evaluations_per_update"] = result.evaluations_per_update;
  s["init_residual"] = result.init_residual;
  s["final_q_error"] = result.final_q_error;
  s["final_v_norm"] = result.final_v_norm;
  s["mean_residual"] = result.mean_residual;
  s["unmodeled"] = imported.unmodeled;
  return SwingupOutcome{std::move(result), std::move(s)};
}

void write_json(const nlohmann::json& j, const std::string& path) {
  AtomicFile f(path);
  f.stream() << j.dump(2) << '\n';
  f.commit();
}

std::string human_summary(const nlohmann::json& s) {
  std::ostringstream o;
  o << std::setprecision(4);
  o << "C/GMRES (" << (s["formulation"] == "fd" ? "FD" : "ID") << ", " << s["derivatives"].get<std::string>()
    << ") on " << s["model"].get<std::string>() << ": n = " << s["n"] << ", N = " << s["N"]
    << ", kmax = " << s["kmax"] << ", " << s["duration"].get<double>() << " s\n";
  if (s["diverged"].get<bool>()) {
    o << "  DIVERGED at t = " << s["diverged_at"].get<double>() << " s: "
      << s["divergence_reason"].get<std::string>() << "\n";
  } else {
    o << "  completed " << s["steps"] << " control steps without divergence\n";
  }
  o << "  update time [ms]: mean " << s["mean_update_ms"].get<double>() << ", p50 "
    << s["p50_update_ms"].get<double>() << ", p95 " << s["p95_update_ms"].get<double>() << ", max "
    << s["max_update_ms"].get<double>() << "  (" << s["evaluations_per_update"] << " F evaluations)\n";
  o << "  phases [ms]: rollout " << s["phase_ms"]["rollout"].get<double>() << ", costate "
    << s["phase_ms"]["costate"].get<double>() << ", gmres " << s["phase_ms"]["gmres"].get<double>() << "\n";
  o << "  final max|q - qref| = " << s["final_q_error"].get<double>() << " rad, |v| = "
    << s["final_v_norm"].get<double>() << ", mean residual " << s["mean_residual"].get<double>() << "\n";
  return o.str();
}

}  // namespace idmpc::app
