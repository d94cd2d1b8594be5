#include "idmpc/experiment/task.hpp"

#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/experiment/input_file.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

namespace idmpc {
namespace {

using nlohmann::json;

// a number as a user would type it
std::string text(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

// a measured quantity, to three digits
std::string text3(double x) {
  std::ostringstream o;
  o.precision(3);
  o << x;
  return o.str();
}

// typed access naming file and field
struct Reader {
  const json& j;
  std::string where;

  void known(const std::set<std::string>& keys) const {
    for (const auto& item : j.items()) {
      if (!keys.count(item.key())) throw std::invalid_argument(where + ": unknown field '" + abbreviate(item.key()) + "'");
    }
  }
  bool has(const char* key) const { return j.contains(key); }
  [[noreturn]] void bad(const char* key, const char* expected) const {
    throw std::invalid_argument(where + ": field '" + key + "': expected " + expected + ", got " +
                                abbreviate(j.at(key).dump()));
  }
  void get(const char* key, double& x) const {
    if (!has(key)) return;
    if (!j.at(key).is_number()) bad(key, "a number");
    x = j.at(key).get<double>();
  }
  // the JSON integer itself, never wrapped to int (4294967321 is not 25)
  void get(const char* key, int& x) const {
    if (!has(key)) return;
    const json& v = j.at(key);
    constexpr auto lowest = std::numeric_limits<int>::min(), highest = std::numeric_limits<int>::max();
    const char* expected = "an integer from -2147483648 to 2147483647";
    if (!v.is_number_integer()) bad(key, "an integer");
    if (v.is_number_unsigned() ? v.get<std::uint64_t>() > static_cast<std::uint64_t>(highest)
                               : v.get<std::int64_t>() < lowest || v.get<std::int64_t>() > highest) {
      bad(key, expected);
    }
    x = static_cast<int>(v.get<std::int64_t>());
  }
  void get(const char* key, bool& x) const {
    if (!has(key)) return;
    if (!j.at(key).is_boolean()) bad(key, "true or false");
    x = j.at(key).get<bool>();
  }
  void get(const char* key, std::string& x) const {
    if (!has(key)) return;
    if (!j.at(key).is_string()) bad(key, "a string");
    x = j.at(key).get<std::string>();
  }
  // a scalar or a list of numbers
  void get(const char* key, std::vector<double>& x) const {
    if (!has(key)) return;
    const json& v = j.at(key);
    if (v.is_number()) {
      x = {v.get<double>()};
      return;
    }
    if (!v.is_array() || v.empty()) bad(key, "a number or a list of numbers");
    std::vector<double> out;
    for (const json& e : v) {
      if (!e.is_number()) bad(key, "a number or a list of numbers");
      out.push_back(e.get<double>());
    }
    x = out;
  }
  // a scalar, a list of numbers, or "auto" (then empty)
  void get_or_auto(const char* key, std::vector<double>& x) const {
    if (!has(key)) return;
    if (j.at(key).is_string()) {
      if (j.at(key) != "auto") bad(key, "a number, a list of numbers or \"auto\"");
      x.clear();
      return;
    }
    get(key, x);
  }
  Reader sub(const char* key) const {
    if (!j.at(key).is_object()) bad(key, "an object");
    return Reader{j.at(key), where + ", '" + key + "'"};
  }
};

// a scalar broadcast to every joint, or exactly one value per joint
VecX<double> per_joint(const std::vector<double>& values, int n, const std::string& name) {
  if (values.size() == 1) return VecX<double>::Constant(n, values[0]);
  if (static_cast<int>(values.size()) == n) return Eigen::Map<const VecX<double>>(values.data(), n);
  throw std::invalid_argument(name + " has " + std::to_string(values.size()) + " values, expected 1 or " +
                              std::to_string(n) + " (one per joint)");
}

VecX<double> finite(VecX<double> x, const std::string& name) {
  for (int i = 0; i < x.size(); ++i) {
    if (!std::isfinite(x[i])) throw std::invalid_argument(name + " must be finite, got " + std::to_string(x[i]));
  }
  return x;
}

VecX<double> non_negative(VecX<double> x, const std::string& name) {
  for (int i = 0; i < x.size(); ++i) {
    if (!(x[i] >= 0) || !std::isfinite(x[i])) {
      throw std::invalid_argument(name + " must be finite and non-negative, got " + std::to_string(x[i]));
    }
  }
  return x;
}

std::string resolve_path(const std::string& file, const std::string& relative_to) {
  namespace fs = std::filesystem;
  const fs::path p(file);
  if (p.is_absolute()) return file;
  return (fs::path(relative_to).parent_path() / p).lexically_normal().string();
}

}  // namespace

std::string paper_task_path() { return shipped_mjcf_path("paper_swingup.json"); }
std::string paper_tables_path() { return shipped_mjcf_path("paper_tables.json"); }

Task load_task(const std::string& path, const Task* base) {
  Task t = task_from_json(read_json_file(path, "task file"), "task file '" + path + "'", base ? *base : arm_defaults());
  t.source = path;
  if (!t.model.empty()) t.model = resolve_path(t.model, path);
  return t;
}

Task task_from_json(const nlohmann::json& j, const std::string& where, const Task& base) {
  Task t = base;
  const Reader r{j, where};
  if (!j.is_object()) throw std::invalid_argument(r.where + ": expected a JSON object");
  r.known({"schema", "description", "model", "q0", "qref", "duration", "formulation", "derivatives",
           "simd_stages", "direct_torque", "actuate_every_joint", "implicit_damping", "friction_velocity",
           "offset_free", "observer_time_constant", "reach_tolerance", "torque_limit", "weights", "cgmres",
           "target", "reference", "tracking_tolerance", "latency", "solver", "riccati"});
  if (r.has("schema") && j.at("schema") != kTaskSchema) r.bad("schema", (std::string("\"") + kTaskSchema + "\"").c_str());
  r.get("description", t.description);
  r.get("model", t.model);
  if (t.model.size() > kMaxPathChars) r.bad("model", "a file name of at most 4096 characters");
  if (r.has("q0")) {
    if (j.at("q0").is_string()) {
      r.get("q0", t.q0_rule);
      if (t.q0_rule != "swingup" && t.q0_rule != "home") {
        r.bad("q0", "a list of joint positions, \"swingup\" or \"home\"");
      }
      t.q0.clear();
    } else {
      r.get("q0", t.q0);
      t.q0_rule.clear();
    }
  }
  if (r.has("qref") && j.at("qref").is_string()) {
    if (j.at("qref") != "q0") r.bad("qref", "a number, a list of joint positions or \"q0\"");
    t.qref_start = true;
    t.qref.clear();
  } else if (r.has("qref")) {
    r.get("qref", t.qref);
    t.qref_start = false;
  }
  if (r.has("target")) {
    const Reader g = r.sub("target");
    g.known({"frame", "position", "orientation", "weights"});
    FrameTask f;
    if (!g.has("frame")) throw std::invalid_argument(g.where + ": field 'frame' (a site or body name) is missing");
    g.get("frame", f.frame);
    auto start_or = [&](const char* key, std::vector<double>& x, size_t size, const char* expected) {
      if (!g.has(key) || g.j.at(key) == "start") return;
      g.get(key, x);
      if (x.size() != size) g.bad(key, expected);
    };
    start_or("position", f.position, 3, "[x, y, z] or \"start\"");
    start_or("orientation", f.orientation, 4, "a quaternion [w, x, y, z] or \"start\"");
    if (g.has("weights")) {
      const Reader w = g.sub("weights");
      w.known({"position", "orientation"});
      w.get("position", f.position_weight);
      if (w.has("orientation") && !(w.j.at("orientation") == "auto")) {
        if (!w.j.at("orientation").is_number()) w.bad("orientation", "a number or \"auto\"");
        double orientation = 0;
        w.get("orientation", orientation);
        f.orientation_weight = orientation;
      }
      if (f.position_weight.size() != 1 && f.position_weight.size() != 3) w.bad("position", "1 or 3 values");
    }
    t.target = f;
  }
  if (r.has("reference")) {
    if (!j.at("reference").is_object()) r.bad("reference", "an object with a \"shape\"");
    t.reference = j.at("reference");
  }
  r.get("tracking_tolerance", t.tracking_tolerance);
  r.get("duration", t.duration);
  r.get("formulation", t.formulation);
  r.get("derivatives", t.derivatives);
  r.get("simd_stages", t.simd_stages);
  r.get("direct_torque", t.direct_torque);
  r.get("actuate_every_joint", t.actuate_every_joint);
  if (r.has("implicit_damping")) {
    const json& v = j.at("implicit_damping");
    if (v.is_boolean()) {
      t.implicit_damping = v.get<bool>() ? "on" : "off";
    } else if (v == "auto") {
      t.implicit_damping = "auto";
    } else {
      r.bad("implicit_damping", "true, false or \"auto\"");
    }
  }
  r.get_or_auto("friction_velocity", t.friction_velocity);
  r.get("offset_free", t.offset_free);
  r.get("observer_time_constant", t.observer_time_constant);
  r.get("reach_tolerance", t.reach_tolerance);
  if (r.has("latency")) {
    // "none", "measured" or a compute time in ms (a number, or its text)
    const json& v = j.at("latency");
    const char* expected = "\"none\", \"measured\" or a compute time in ms (a finite number >= 0)";
    if (v.is_number()) {
      const double ms = v.get<double>();
      if (!(ms >= 0) || !std::isfinite(ms)) r.bad("latency", expected);
      t.latency = to_string(Latency{Latency::Kind::kFixed, ms});
    } else if (v.is_string()) {
      try {
        t.latency = to_string(parse_latency(v.get<std::string>()));
      } catch (const std::invalid_argument&) {
        r.bad("latency", expected);
      }
    } else {
      r.bad("latency", expected);
    }
  }
  if (r.has("torque_limit")) r.get("torque_limit", t.torque_limit);
  if (r.has("weights")) {
    const Reader w = r.sub("weights");
    w.known({"Qq", "Qv", "Qa", "R", "Qa_fallback"});
    w.get_or_auto("Qq", t.Qq);
    w.get_or_auto("Qv", t.Qv);
    w.get("Qa", t.Qa);
    w.get_or_auto("R", t.R);
    w.get("Qa_fallback", t.Qa_fallback);
  }
  if (r.has("cgmres")) {
    const Reader c = r.sub("cgmres");
    c.known({"N", "kmax", "Tf", "alpha", "dt", "zeta", "h", "init_full_horizon", "shooting", "products"});
    c.get("N", t.N);
    if (c.has("kmax") && c.j.at("kmax") == "auto") {
      t.kmax = 0;
    } else {
      c.get("kmax", t.kmax);
      if (c.has("kmax") && t.kmax < 1) c.bad("kmax", "a positive integer or \"auto\"");
    }
    c.get("Tf", t.Tf);
    c.get("alpha", t.alpha);
    c.get("dt", t.dt);
    c.get("zeta", t.zeta);
    c.get("h", t.h);
    c.get("init_full_horizon", t.init_full_horizon);
    c.get("shooting", t.shooting);
    c.get("products", t.products);
  }
  r.get("solver", t.solver);
  if (r.has("riccati")) {
    const Reader c = r.sub("riccati");
    c.known({"iterations", "tolerance", "init_iterations", "init_tolerance", "barrier", "line_search"});
    c.get("iterations", t.riccati.iterations);
    c.get("tolerance", t.riccati.tolerance);
    c.get("init_iterations", t.riccati.init_iterations);
    c.get("init_tolerance", t.riccati.init_tolerance);
    c.get("barrier", t.riccati.barrier);
    c.get("line_search", t.riccati.line_search);
  }
  return t;
}

const Task& paper_task() {
  // the paper's task names every field itself
  static const Task task = [] {
    Task empty;
    return load_task(paper_task_path(), &empty);
  }();
  return task;
}

const Task& arm_defaults() {
  // docs/tasks.md gives the reason for each value
  static const Task task = [] {
    Task t;
    t.description = "defaults for real arms";
    t.q0_rule = "home";
    t.duration = 6;
    t.formulation = "id";
    t.derivatives = "adjoint";
    t.simd_stages = true;
    t.implicit_damping = "auto";
    t.offset_free = true;
    t.observer_time_constant = 0.02;
    t.reach_tolerance = 5e-3;
    t.Qa = {0};
    t.Qa_fallback = 1e-4;
    t.N = 25;
    t.kmax = 0;  // "auto": kDefaultKmax, more on an under-actuated model (TaskRun)
    t.Tf = 0.5;
    t.alpha = 0;
    t.dt = 1e-3;
    t.zeta = 0;
    t.h = 1e-8;
    t.init_full_horizon = true;
    t.shooting = "single";
    t.products = "difference";
    return t;
  }();
  return task;
}

nlohmann::json to_json(const Task& t) {
  json j;
  j["schema"] = kTaskSchema;
  if (!t.description.empty()) j["description"] = t.description;
  j["model"] = t.model;
  j["q0"] = t.q0_rule.empty() ? json(t.q0) : json(t.q0_rule);
  j["qref"] = t.qref_start ? json("q0") : json(t.qref);
  if (t.target) {
    const FrameTask& f = *t.target;
    j["target"] = {{"frame", f.frame},
                   {"position", f.position.empty() ? json("start") : json(f.position)},
                   {"orientation", f.orientation.empty() ? json("start") : json(f.orientation)},
                   {"weights",
                    {{"position", f.position_weight},
                     {"orientation", f.orientation_weight ? json(*f.orientation_weight) : json("auto")}}}};
  }
  if (!t.reference.is_null()) j["reference"] = t.reference;
  j["tracking_tolerance"] = t.tracking_tolerance;
  j["duration"] = t.duration;
  j["formulation"] = t.formulation;
  j["derivatives"] = t.derivatives;
  j["simd_stages"] = t.simd_stages;
  j["direct_torque"] = t.direct_torque;
  j["actuate_every_joint"] = t.actuate_every_joint;
  j["implicit_damping"] = t.implicit_damping == "auto" ? json("auto") : json(t.implicit_damping == "on");
  auto or_auto = [](const std::vector<double>& x) { return x.empty() ? json("auto") : json(x); };
  j["friction_velocity"] = or_auto(t.friction_velocity);
  j["offset_free"] = t.offset_free;
  j["observer_time_constant"] = t.observer_time_constant;
  j["reach_tolerance"] = t.reach_tolerance;
  // written only when on: a task without latency reads and hashes as it always has
  if (t.latency != "none") {
    const Latency latency = parse_latency(t.latency);
    j["latency"] = latency.kind == Latency::Kind::kFixed ? json(latency.ms) : json(t.latency);
  }
  if (!t.torque_limit.empty()) j["torque_limit"] = t.torque_limit;
  j["weights"] = {{"Qq", or_auto(t.Qq)}, {"Qv", or_auto(t.Qv)}, {"Qa", t.Qa}, {"R", or_auto(t.R)},
                  {"Qa_fallback", t.Qa_fallback}};
  j["cgmres"] = {{"N", t.N},   {"kmax", t.kmax > 0 ? json(t.kmax) : json("auto")}, {"Tf", t.Tf}, {"alpha", t.alpha},
                 {"dt", t.dt}, {"zeta", t.zeta}, {"h", t.h}, {"init_full_horizon", t.init_full_horizon},
                 {"shooting", t.shooting}, {"products", t.products}};
  // the solver always named (a task's default is "auto", a task as run names the one that ran, so
  // that running it again runs that one); the Riccati settings where it may run
  j["solver"] = t.solver;
  if (t.solver != "cgmres") {
    const RiccatiSettings& rs = t.riccati;
    j["riccati"] = {{"iterations", rs.iterations},         {"tolerance", rs.tolerance},
                    {"init_iterations", rs.init_iterations}, {"init_tolerance", rs.init_tolerance},
                    {"barrier", rs.barrier},               {"line_search", rs.line_search}};
  }
  return j;
}

ResolvedTask resolve(const Task& t, int n) {
  // the parsers of these words echo an unknown one in full: a long one is refused here, shortened
  const std::pair<const std::string&, const char*> words[] = {{t.formulation, "--formulation (formulation)"},
                                                              {t.derivatives, "--derivatives (derivatives)"},
                                                              {t.shooting, "--shooting (cgmres.shooting)"},
                                                              {t.products, "--products (cgmres.products)"},
                                                              {t.solver, "--solver (solver)"},
                                                              {t.implicit_damping, "--implicit-damping (implicit_damping)"}};
  for (const auto& [word, name] : words) {
    if (word.size() > kMaxShownChars) throw std::invalid_argument(std::string(name) + ": unknown value '" + abbreviate(word) + "'");
  }
  ResolvedTask r;
  ControllerSettings& c = r.controller;
  c.formulation = parse_formulation(t.formulation);
  c.derivatives = parse_derivative_mode(t.derivatives);
  // bounded before anything is sized from it
  if (t.N < 1 || t.N > kMaxHorizonSteps) {
    throw std::invalid_argument("--N (cgmres.N) must be from 1 to " + std::to_string(kMaxHorizonSteps) +
                                " horizon steps, got " + std::to_string(t.N));
  }
  if (!(t.duration > 0) || !std::isfinite(t.duration)) {
    throw std::invalid_argument("duration must be positive, got " + std::to_string(t.duration));
  }
  if (t.dt > 0 && !(t.duration / t.dt >= 0.5)) {
    throw std::invalid_argument("--duration (duration) " + text(t.duration) + " s is shorter than one control step (dt = " +
                                text(t.dt) + " s)");
  }
  if (t.dt > 0 && !(t.duration / t.dt <= 1e9)) {
    throw std::invalid_argument("--duration (duration) " + text(t.duration) + " s is more than 1e9 control steps of " +
                                text(t.dt) + " s");
  }
  // named as the option and as the task field
  auto weight = [&](const std::vector<double>& x, const char* name) {
    const std::string both = std::string("--") + name + " (weights." + name + ")";
    if (x.empty()) return VecX<double>();  // "auto": arm_weights fills it in with the model
    return non_negative(per_joint(x, n, both), both);
  };
  c.weights = OcpWeights{weight(t.Qq, "Qq"), weight(t.Qv, "Qv"), weight(t.Qa.empty() ? std::vector<double>{0} : t.Qa, "Qa"),
                         weight(t.R, "R")};
  // the problem must be strictly convex in its decision variable (formulations.md §Costs); "auto" R is positive
  const VecX<double>& R = c.weights.R;
  const VecX<double>& Qa = c.weights.Qa;
  for (int j = 0; j < n && R.size() == n; ++j) {
    if (c.formulation == Formulation::kForwardDynamics && !(R[j] > 0)) {
      throw std::invalid_argument("--R (weights.R) must be positive with FD: the torque is the decision "
                                  "variable and R its only weight; got " + text(R[j]) + " on joint " +
                                  std::to_string(j));
    }
    if (c.formulation == Formulation::kInverseDynamics && !(R[j] + Qa[j] > 0)) {
      throw std::invalid_argument("--R and --Qa (weights.R, weights.Qa) are both 0 on joint " + std::to_string(j) +
                                  ": ID needs one of them positive to weight the acceleration");
    }
  }
  if (c.formulation == Formulation::kForwardDynamics && (Qa.array() != 0).any()) {
    r.warnings.push_back("--Qa (weights.Qa) has no effect with FD: the acceleration is not a decision variable there");
  }
  c.q_ref = finite(t.qref.empty() ? VecX<double>::Zero(n) : per_joint(t.qref, n, "--qref (qref)"), "--qref (qref)");
  if (t.target) {
    // the frame target's own values (its frame and "start" pose need the model: mj::TaskRun)
    const FrameTask& f = *t.target;
    if (f.frame.empty()) throw std::invalid_argument("target.frame: expected a site or body name, got an empty name");
    if (f.frame.find('\0') != std::string::npos) {
      throw std::invalid_argument("target.frame: expected a site or body name, got one with a NUL byte: '" +
                                  abbreviate(f.frame.substr(0, f.frame.find('\0'))) + "\\0…'");
    }
    auto sized = [](const std::vector<double>& x, std::initializer_list<std::size_t> sizes, const char* name,
                    const char* expected) {
      if (std::find(sizes.begin(), sizes.end(), x.size()) != sizes.end()) return;
      throw std::invalid_argument(std::string(name) + " has " + std::to_string(x.size()) + " values, expected " +
                                  expected);
    };
    sized(f.position, {0, 3}, "target.position", "3 ([x, y, z]) or none (the frame's position at q0)");
    sized(f.orientation, {0, 4}, "target.orientation", "4 ([w, x, y, z]) or none (the frame's orientation at q0)");
    sized(f.position_weight, {1, 3}, "target.weights.position", "1 or 3");
    finite(Eigen::Map<const VecX<double>>(f.position.data(), static_cast<Eigen::Index>(f.position.size())),
           "target.position");
    finite(Eigen::Map<const VecX<double>>(f.orientation.data(), static_cast<Eigen::Index>(f.orientation.size())),
           "target.orientation");
    std::vector<double> w = f.position_weight;
    if (f.orientation_weight) w.push_back(*f.orientation_weight);
    non_negative(Eigen::Map<const VecX<double>>(w.data(), static_cast<Eigen::Index>(w.size())),
                 "target.weights (position, orientation)");
    if (!f.orientation.empty()) {
      const double norm = Eigen::Map<const Eigen::Vector4d>(f.orientation.data()).norm();
      if (!(std::abs(norm - 1.0) < 1e-6)) {
        throw std::invalid_argument("target.orientation [w, x, y, z] must be a unit quaternion, its norm is " +
                                    text(norm));
      }
    }
  }
  r.torque_limit = VecX<double>::Constant(n, std::numeric_limits<double>::infinity());
  if (!t.torque_limit.empty()) {
    r.torque_limit = per_joint(t.torque_limit, n, "--torque-limit (torque_limit)");
    if (!(r.torque_limit.array() > 0).all() || r.torque_limit.hasNaN()) {
      throw std::invalid_argument("--torque-limit (torque_limit) must be positive");
    }
  }
  if (t.q0_rule == "swingup") {
    r.q0 = VecX<double>::Zero(n);
    r.q0[0] = -M_PI;
  } else if (t.q0_rule == "home") {
    r.q0.resize(0);  // the model's keyframe: the caller with the model fills it in
  } else {
    if (static_cast<int>(t.q0.size()) != n) {
      throw std::invalid_argument("--q0 (q0) has " + std::to_string(t.q0.size()) + " values, expected " +
                                  std::to_string(n) + " (one per joint)");
    }
    r.q0 = finite(Eigen::Map<const VecX<double>>(t.q0.data(), n), "--q0 (q0)");
  }
  c.cgmres.kmax = t.kmax > 0 ? t.kmax : kDefaultKmax;
  c.cgmres.Tf = t.Tf;
  c.cgmres.alpha = t.alpha;
  c.cgmres.dt = t.dt;
  c.cgmres.zeta = t.zeta;
  c.cgmres.h = t.h;
  c.cgmres.init_full_horizon = t.init_full_horizon;
  c.cgmres.shooting = parse_shooting(t.shooting);
  try {
    c.cgmres.products = parse_products(t.products);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--products (cgmres.products): ") + e.what());
  }
  c.cgmres.validate();
  try {
    c.solver = parse_solver(t.solver);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--solver (solver): ") + e.what());
  }
  c.riccati = t.riccati;
  c.riccati.validate();  // its message names the setting
  if (t.implicit_damping != "on" && t.implicit_damping != "off" && t.implicit_damping != "auto") {
    throw std::invalid_argument("--implicit-damping (implicit_damping): expected on, off or auto, got '" +
                                t.implicit_damping + "'");
  }
  c.implicit_damping = parse_implicit_damping(t.implicit_damping);
  // (under "auto" the controller's setup checks it on the solver it resolves)
  if (c.implicit_damping == ImplicitDamping::kOn && t.alpha != 0 && c.solver == SolverKind::kCgmres) {
    throw std::invalid_argument("--implicit-damping (implicit_damping) needs a fixed horizon, alpha = 0 (its step is "
                                "T_f/N), got alpha = " + text(t.alpha));
  }
  if (!t.friction_velocity.empty()) {
    c.friction_velocity = per_joint(t.friction_velocity, n, "--friction-velocity (friction_velocity)");
    if (!(c.friction_velocity.array() > 0).all() || !c.friction_velocity.allFinite()) {
      throw std::invalid_argument("--friction-velocity (friction_velocity) must be positive and finite");
    }
  }
  if (t.offset_free && !(t.observer_time_constant > 0 && std::isfinite(t.observer_time_constant))) {
    throw std::invalid_argument("--observer-time-constant (observer_time_constant) must be positive with offset-free "
                                "tracking, got " + text(t.observer_time_constant));
  }
  if (!(t.tracking_tolerance > 0) || !std::isfinite(t.tracking_tolerance)) {
    throw std::invalid_argument("tracking_tolerance must be positive and finite [m], got " + text(t.tracking_tolerance));
  }
  try {
    r.latency = parse_latency(t.latency);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--latency (latency): ") + e.what());
  }
  c.N = t.N;
  c.observer_time_constant = t.offset_free ? t.observer_time_constant : 0.0;
  c.simd_stages = t.simd_stages;
  if (!(t.reach_tolerance >= 0) || !std::isfinite(t.reach_tolerance)) {
    throw std::invalid_argument("--reach-tolerance (reach_tolerance) must be non-negative and finite, got " +
                                text(t.reach_tolerance));
  }
  return r;
}

bool without_Qa(const Task& t) {
  return std::all_of(t.Qa.begin(), t.Qa.end(), [](double x) { return x == 0; });
}

std::string divergence_hint(const Task& t, double damping_step_ratio, double open_loop_rate) {
  std::vector<std::string> tries;
  const bool riccati = t.solver == "riccati";
  if (!riccati && t.formulation == "fd" && open_loop_rate * t.Tf > kIllConditionedGrowth) {
    // FD's rollout across a fast unstable open loop: what helped on such arms (docs/results.md);
    // kmax, zeta, N and exact products did not
    const double dtau = t.Tf / t.N;
    const int N = std::max(1, static_cast<int>(std::lround(4.0 / open_loop_rate / dtau)));
    tries.push_back("--formulation id (the open loop diverges at " + text3(open_loop_rate) +
                    " 1/s: FD's rollout amplifies by " + text3(std::exp(open_loop_rate * t.Tf)) +
                    " over the horizon, ID's integrates accelerations)");
    tries.push_back("--solver riccati (no single-shooting rollout to condition)");
    tries.push_back("--Tf " + text(N * dtau) + " --N " + std::to_string(N) + " (a horizon of 4/lambda at the same step)");
    if (t.shooting != "multiple") tries.push_back("--shooting multiple");
  } else {
    if (damping_step_ratio > 1 && t.implicit_damping == "off") {
      tries.push_back("--implicit-damping on (or auto; the joint damping makes the explicit horizon step unstable: "
                      "dtau*max eig(M^-1 D) = " + text(damping_step_ratio) + " > 1)");
    }
    if (t.formulation == "id" && without_Qa(t)) {
      const double Qa = t.Qa_fallback > 0 ? t.Qa_fallback : 1e-4;
      tries.push_back("--Qa " + text(Qa) + " (a small weight on the accelerations, the paper's fallback" +
                      std::string(t.Qa_fallback > 0 ? "; `swingup --fallback` reruns with it" : "") + ")");
    }
    if (riccati) {
      tries.push_back("--iterations " + std::to_string(std::max(3, 2 * t.riccati.iterations)) +
                      " (more SQP iterations per update" +
                      std::string(t.riccati.line_search ? ")" : ", with \"riccati\": {\"line_search\": true} in the task)"));
    } else {
      if (t.alpha > 0 && !t.init_full_horizon) {
        tries.push_back("--alpha 0 --init-full-horizon true (start from the solved full-horizon problem instead of "
                        "growing the horizon from zero)");
      }
      tries.push_back("--solver riccati (Gauss-Newton SQP steps with a line search, no continuation to lose)");
      if (t.formulation == "fd") tries.push_back("--formulation id (its C/GMRES diverged on fewer of the generated arms)");
    }
    tries.push_back("a larger --R (now " + (t.R.empty() ? std::string("auto") : text(t.R.front())) +
                    ") for smaller, smoother torques");
    if (!riccati) {
      const double zeta = t.zeta > 0 ? t.zeta : 1.0 / t.dt;
      tries.push_back("a smaller --zeta (now " + text(zeta) + ")");
    }
    tries.push_back("a larger --N (now " + std::to_string(t.N) + ") for finer horizon steps");
  }
  std::string s = "try ";
  for (size_t k = 0; k < tries.size(); ++k) s += (k ? "; or " : "") + tries[k];
  return s;
}

const PaperCell* PaperTables::find(const std::string& table, const std::string& formulation, int n, int N,
                                   int kmax) const {
  for (const PaperCell& c : cells) {
    if (c.table == table && c.formulation == formulation && c.n == n && c.N == N && c.kmax == kmax) return &c;
  }
  return nullptr;
}

PaperTables load_paper_tables(const std::string& path) {
  const json j = read_json_file(path, "tables file");
  const Reader r{j, "tables file '" + path + "'"};
  r.known({"schema", "source", "machine", "task", "marks", "cells"});
  PaperTables t;
  r.get("source", t.source);
  r.get("machine", t.machine);
  r.get("task", t.task);
  t.task = resolve_path(t.task, path);
  if (!j.contains("cells") || !j.at("cells").is_array()) r.bad("cells", "a list of cells");
  for (const json& c : j.at("cells")) {
    const Reader cr{c, r.where + ", a cell"};
    cr.known({"table", "model", "n", "formulation", "N", "kmax", "ms", "mark"});
    PaperCell cell;
    cr.get("table", cell.table);
    cr.get("model", cell.model);
    cr.get("n", cell.n);
    cr.get("formulation", cell.formulation);
    cr.get("N", cell.N);
    cr.get("kmax", cell.kmax);
    cr.get("ms", cell.ms);
    cr.get("mark", cell.mark);
    t.cells.push_back(cell);
  }
  return t;
}

}  // namespace idmpc
