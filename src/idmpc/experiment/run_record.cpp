#include "idmpc/experiment/run_record.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc {
namespace {

constexpr const char* kHeaderShape =
    "t,q0..q{n-1},v0..v{n-1},u0..u{n-1}[,uc0..uc{n-1}],residual,update_ms[,x,y,z,x_ref,y_ref,z_ref]";
const std::vector<std::string> kFrameColumns = {"x", "y", "z", "x_ref", "y_ref", "z_ref"};

std::string trim(const std::string& s) {
  std::size_t b = 0;
  std::size_t e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

// counts consecutive columns prefix0, prefix1, ... starting at `at`
int count_indexed(const std::vector<std::string>& cols, std::size_t at, const std::string& prefix) {
  int k = 0;
  while (at + static_cast<std::size_t>(k) < cols.size() &&
         cols[at + static_cast<std::size_t>(k)] == prefix + std::to_string(k)) {
    ++k;
  }
  return k;
}

// the column layout of a header: n joint columns per q and v, nu torque columns
struct Layout {
  int n = 0;
  int nu = 0;
  bool commanded = false;  ///< uc* columns after u*
  bool frame = false;      ///< a frame's position and its target after update_ms
};

bool parse_header(const std::vector<std::string>& cols, Layout& layout) {
  if (cols.empty() || cols[0] != "t") return false;
  std::size_t at = 1;
  layout.n = count_indexed(cols, at, "q");
  if (layout.n < 1) return false;
  at += static_cast<std::size_t>(layout.n);
  if (count_indexed(cols, at, "v") != layout.n) return false;
  at += static_cast<std::size_t>(layout.n);
  layout.nu = count_indexed(cols, at, "u");
  if (layout.nu < 1) return false;
  at += static_cast<std::size_t>(layout.nu);
  layout.commanded = count_indexed(cols, at, "uc") == layout.nu;
  if (layout.commanded) at += static_cast<std::size_t>(layout.nu);
  if (cols.size() < at + 2 || cols[at] != "residual" || cols[at + 1] != "update_ms") return false;
  at += 2;
  layout.frame = cols.size() == at + kFrameColumns.size() && std::equal(kFrameColumns.begin(), kFrameColumns.end(),
                                                                         cols.begin() + static_cast<long>(at));
  return cols.size() == at || layout.frame;
}

bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  const char* begin = text.c_str();
  char* end = nullptr;
  value = std::strtod(begin, &end);
  // nan, inf and overflow to +-inf are kept: a diverged run logs them
  return end == begin + text.size();
}

// fills label, formulation, derivatives and the model from `<log>.json` when it exists and
// belongs to this log; otherwise says in summary_warning why it was not used
void read_sibling_summary(RunLog& log) {
  namespace fs = std::filesystem;
  const fs::path json_path = fs::path(log.path).replace_extension(".json");
  log.label = fs::path(log.path).stem().string();
  std::error_code ec;
  if (!fs::is_regular_file(json_path, ec)) return;
  const std::string fallback = ": not used, run log '" + log.path + "' is labelled by its file name";
  RunSummary s;
  try {
    s = read_summary(json_path.string());
  } catch (const std::exception& e) {
    log.summary_warning = e.what() + fallback;
    return;
  }
  const auto rows = static_cast<long>(log.rows());
  std::string other;  // how the summary shows that it belongs to another run
  if (s.n != log.n) {
    other = "is for " + std::to_string(s.n) + " joints, the log has " + std::to_string(log.n);
  } else if (s.steps != rows) {
    other = "is for " + std::to_string(s.steps) + " control steps, the log has " + std::to_string(rows) + " rows";
  } else if (!s.log_hash.empty() && s.log_hash != file_hash(log.path)) {
    other = "is for a log with hash " + s.log_hash + ", this log's is " + file_hash(log.path);
  }
  if (!other.empty()) {
    log.summary_warning = "run summary '" + json_path.string() + "' " + other + " (a stale summary?)" + fallback;
    return;
  }
  log.summary_path = json_path.string();
  log.summary_model = s.task.model;
  log.model_hash = s.model_hash;
  log.formulation = s.task.formulation;
  log.derivatives = s.task.derivatives;
  log.held_joints = s.held_joints;
  log.held_q = s.held_q;
  log.label = s.label();
}

}  // namespace

double RunLog::u_norm(std::size_t i) const {
  const double* row = u_row(i);
  double s = 0;
  for (int k = 0; k < nu; ++k) s += row[k] * row[k];
  return std::sqrt(s);
}

std::size_t RunLog::nearest_row(double time) const {
  const auto it = std::lower_bound(t.begin(), t.end(), time);
  if (it == t.begin()) return 0;
  if (it == t.end()) return t.size() - 1;
  const auto i = static_cast<std::size_t>(it - t.begin());
  return (time - t[i - 1] <= t[i] - time) ? i - 1 : i;
}

bool RunLog::finite_pose(std::size_t i) const {
  const double* row = q_row(i);
  return std::all_of(row, row + n, [](double x) { return std::isfinite(x); });
}

RunLog read_run_log(const std::string& csv_path) {
  // a regular file (a run log is as long as its run: its size is not bounded)
  const std::string problem = input_file_problem(csv_path, "a CSV file", std::numeric_limits<std::uintmax_t>::max());
  if (!problem.empty()) throw std::runtime_error("run log '" + csv_path + "': " + problem);
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error("cannot open run log '" + csv_path + "'");

  RunLog log;
  log.path = csv_path;
  const std::string where = "run log '" + csv_path + "'";

  // header
  std::string line;
  if (!std::getline(in, line)) {
    throw std::runtime_error(where + " is empty: expected a header " + kHeaderShape);
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line);
  Layout layout;
  if (!parse_header(header, layout)) {
    throw std::runtime_error(where + " line 1: bad header: expected " + kHeaderShape +
                             ", got '" + abbreviate(line, 200) + "'");
  }
  log.n = layout.n;
  log.nu = layout.nu;

  // rows: t | q | v | u | residual | update_ms
  const std::size_t columns = header.size();
  const std::size_t q_at = 1;
  const std::size_t u_at = q_at + 2 * static_cast<std::size_t>(log.n);
  std::vector<double> values(columns);
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = split(line);
    if (cells.size() != columns) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) + ": expected " +
                               std::to_string(columns) + " columns, got " +
                               std::to_string(cells.size()));
    }
    for (std::size_t c = 0; c < columns; ++c) {
      if (!parse_number(cells[c], values[c])) {
        throw std::runtime_error(where + " line " + std::to_string(line_no) + ", column '" +
                                 abbreviate(header[c]) + "': expected a number, got '" + abbreviate(cells[c]) + "'");
      }
    }
    const double time = values[0];
    if (!std::isfinite(time)) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) +
                               ": expected a finite time, got '" + abbreviate(cells[0]) + "'");
    }
    if (!log.t.empty() && time < log.t.back()) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) +
                               ": expected non-decreasing times, got " + abbreviate(cells[0]) +
                               " after " + std::to_string(log.t.back()));
    }
    log.t.push_back(time);
    log.q.insert(log.q.end(), values.begin() + q_at, values.begin() + q_at + log.n);
    log.u.insert(log.u.end(), values.begin() + u_at, values.begin() + u_at + log.nu);
    if (layout.commanded) {
      log.u_commanded.insert(log.u_commanded.end(), values.begin() + u_at + log.nu,
                             values.begin() + u_at + 2 * log.nu);
    }
    const std::size_t end = columns - (layout.frame ? kFrameColumns.size() : 0);
    log.residual.push_back(values[end - 2]);
    log.update_ms.push_back(values[end - 1]);
    if (layout.frame) {
      log.frame.insert(log.frame.end(), values.begin() + static_cast<long>(end), values.begin() + static_cast<long>(end) + 3);
      log.frame_ref.insert(log.frame_ref.end(), values.begin() + static_cast<long>(end) + 3, values.end());
    }
  }
  if (log.t.empty()) {
    throw std::runtime_error(where + " has a header but no rows: expected at least one row");
  }
  read_sibling_summary(log);
  return log;
}

RunLogWriter::RunLogWriter(std::ostream& out, int n, bool commanded, bool frame)
    : out_(out), n_(n), commanded_(commanded), frame_(frame) {
  out_ << "t";
  for (const char* p : {"q", "v", "u", "uc"}) {
    if (std::string(p) == "uc" && !commanded_) continue;
    for (int i = 0; i < n_; ++i) out_ << ',' << p << i;
  }
  out_ << ",residual,update_ms";
  if (frame_) {
    for (const std::string& c : kFrameColumns) out_ << ',' << c;
  }
  out_ << '\n' << std::setprecision(10);
}

void RunLogWriter::row(double t, const VecX<double>& q, const VecX<double>& v, const VecX<double>& u,
                       const VecX<double>& u_commanded, double residual, double update_ms,
                       const Vec3<double>* frame_position, const Vec3<double>* frame_target) {
  out_ << t;
  for (const VecX<double>* x : {&q, &v, &u, &u_commanded}) {
    if (x == &u_commanded && !commanded_) continue;
    for (int i = 0; i < n_; ++i) out_ << ',' << (*x)[i];
  }
  out_ << ',' << residual << ',' << update_ms;
  if (frame_) {
    for (const Vec3<double>* p : {frame_position, frame_target}) {
      for (int k = 0; k < 3; ++k) out_ << ',' << (p ? (*p)[k] : std::numeric_limits<double>::quiet_NaN());
    }
  }
  out_ << '\n';
}

std::string RunSummary::label() const {
  std::string upper = task.formulation;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (task.solver == "riccati") {
    // the stage Jacobians are matrices whatever the derivative mode says
    return "Riccati (" + upper + ") N=" + std::to_string(task.N) + " iterations=" + std::to_string(task.riccati.iterations);
  }
  return "C/GMRES (" + upper + ", " + task.derivatives + (task.shooting == "multiple" ? ", multiple shooting" : "") +
         (task.products == "exact" ? ", exact products" : "") + ") N=" + std::to_string(task.N) + " kmax=" + std::to_string(task.kmax);
}

namespace {

// 64-bit FNV-1a over bytes, written "fnv1a64:<16 hex digits>"
struct Fnv1a {
  std::uint64_t h = 14695981039346656037ull;  // offset basis
  void add(const char* bytes, std::size_t size) {
    for (std::size_t i = 0; i < size; ++i) {
      h ^= static_cast<unsigned char>(bytes[i]);
      h *= 1099511628211ull;  // FNV prime
    }
  }
  std::string hex() const {
    std::ostringstream o;
    o << "fnv1a64:" << std::hex << std::setw(16) << std::setfill('0') << h;
    return o.str();
  }
};

}  // namespace

std::string file_hash(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty() || !fs::is_regular_file(path, ec)) return "";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read '" + path + "' to hash it");
  Fnv1a f;
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    f.add(buffer.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw std::runtime_error("cannot read '" + path + "' to hash it");
  return f.hex();
}

std::string text_hash(const std::string& text) {
  Fnv1a f;
  f.add(text.data(), text.size());
  return f.hex();
}

nlohmann::json to_json(const RunSummary& s) {
  nlohmann::json j;
  j["schema"] = s.schema;
  j["task"] = to_json(s.task);
  j["solver"] = s.task.solver;  // the one that ran (the task's "auto" resolved)
  j["n"] = s.n;
  if (!s.joint_names.empty()) {
    j["joint_names"] = s.joint_names;
    j["joint_types"] = s.joint_types;
  }
  j["simd_stages"] = s.simd_stages;
  j["zeta"] = s.zeta;
  j["steps"] = s.steps;
  j["diverged"] = s.diverged;
  j["diverged_at"] = s.diverged ? nlohmann::json(s.diverged_at) : nlohmann::json(nullptr);
  j["divergence_reason"] = s.divergence_reason;
  j["divergence_hint"] = s.divergence_hint;
  j["mean_update_ms"] = s.mean_update_ms;
  j["p50_update_ms"] = s.p50_update_ms;
  j["p95_update_ms"] = s.p95_update_ms;
  j["max_update_ms"] = s.max_update_ms;
  j["phase_ms"] = {{"rollout", s.rollout_ms}, {"costate", s.costate_ms}, {"gmres", s.gmres_ms}};
  j["latency"] = {{"setting", s.task.latency},
                  {"control_period_ms", s.control_period_ms},
                  {"updates", s.updates},
                  {"deadline_misses", s.deadline_misses}};
  j["joint_error_rms"] = s.joint_error_rms;
  j["evaluations_per_update"] = s.evaluations_per_update;
  j["init_residual"] = s.init_residual;
  j["final_q_error"] = s.final_q_error;
  j["final_v_norm"] = s.final_v_norm;
  j["mean_residual"] = s.mean_residual;
  j["closed_loop_cost"] = s.closed_loop_cost;
  j["reached"] = s.reached;
  if (s.tracking) {
    const TrackingResult& r = *s.tracking;
    j["tracking"] = {{"position_rms", r.position_rms},       {"position_max", r.position_max},
                     {"orientation_rms", r.orientation_rms}, {"orientation_max", r.orientation_max},
                     {"final_position_error", r.final_position_error}, {"samples", r.samples}};
  }
  j["contact_steps"] = s.contact_steps;
  j["max_contact_force"] = s.max_contact_force;
  j["final_disturbance"] = s.final_disturbance;
  j["implicit_damping"] = s.implicit_damping;
  j["open_loop_rate"] = s.open_loop_rate;
  j["friction_velocity"] = s.friction_velocity;
  j["weights"] = {{"Qq", s.Qq}, {"Qv", s.Qv}, {"R", s.R}};
  j["unbounded_joints"] = s.unbounded_joints;
  j["unmodeled"] = s.unmodeled;
  j["notices"] = s.notices;
  j["warnings"] = s.warnings;
  // infinite limits (unbounded joints) are written as null
  auto limits = [](const std::vector<double>& x) {
    nlohmann::json a = nlohmann::json::array();
    for (double v : x) a.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
    return a;
  };
  j["torque_lower"] = limits(s.torque_lower);
  j["torque_upper"] = limits(s.torque_upper);
  j["saturated_steps"] = s.saturated_steps;
  j["saturated_any"] = s.saturated_any;
  j["max_constraint_violation"] = std::isfinite(s.max_constraint_violation)
                                      ? nlohmann::json(s.max_constraint_violation)
                                      : nlohmann::json(nullptr);  // NaN: the OCP's torques were not finite
  if (!s.held_joints.empty()) {
    j["held_joints"] = s.held_joints;
    j["held_q"] = s.held_q;
  }
  if (!s.model_hash.empty()) j["model_hash"] = s.model_hash;
  if (!s.log_hash.empty()) j["log_hash"] = s.log_hash;
  return j;
}

namespace {

// what a field of a run summary holds
enum class Kind { kNumber, kNumberOrNull, kInteger, kBool, kString, kNumbers, kNumbersOrNulls, kIntegers, kStrings };

bool is(const nlohmann::json& v, Kind kind) {
  auto all = [&v](auto&& test) { return v.is_array() && std::all_of(v.begin(), v.end(), test); };
  switch (kind) {
    case Kind::kNumber: return v.is_number();
    case Kind::kNumberOrNull: return v.is_number() || v.is_null();
    case Kind::kInteger: return v.is_number_integer();
    case Kind::kBool: return v.is_boolean();
    case Kind::kString: return v.is_string();
    case Kind::kNumbers: return all([](const nlohmann::json& x) { return x.is_number(); });
    case Kind::kNumbersOrNulls: return all([](const nlohmann::json& x) { return x.is_number() || x.is_null(); });
    case Kind::kIntegers: return all([](const nlohmann::json& x) { return x.is_number_integer(); });
    case Kind::kStrings: return all([](const nlohmann::json& x) { return x.is_string(); });
  }
  return false;
}

const char* expected(Kind kind) {
  switch (kind) {
    case Kind::kNumber: return "a number";
    case Kind::kNumberOrNull: return "a number or null";
    case Kind::kInteger: return "an integer";
    case Kind::kBool: return "true or false";
    case Kind::kString: return "a string";
    case Kind::kNumbers: return "a list of numbers";
    case Kind::kNumbersOrNulls: return "a list of numbers or nulls";
    case Kind::kIntegers: return "a list of integers";
    case Kind::kStrings: return "a list of strings";
  }
  return "";
}

// every field summary_from_json reads, with what it must hold: "a.b" is checked when the object
// "a" is there; a required field must be there (in its object); checked before any is read, so
// that the reader's errors name the field instead of quoting the JSON library
struct SummaryField {
  const char* path;
  Kind kind;
  bool required;
};
constexpr SummaryField kSummaryFields[] = {
    {"n", Kind::kInteger, true}, {"simd_stages", Kind::kBool, true}, {"zeta", Kind::kNumber, true},
    {"steps", Kind::kInteger, true}, {"diverged", Kind::kBool, true}, {"diverged_at", Kind::kNumberOrNull, false},
    {"divergence_reason", Kind::kString, true}, {"divergence_hint", Kind::kString, false},
    {"mean_update_ms", Kind::kNumber, true}, {"p50_update_ms", Kind::kNumberOrNull, true},
    {"p95_update_ms", Kind::kNumberOrNull, true}, {"max_update_ms", Kind::kNumberOrNull, true},
    {"phase_ms.rollout", Kind::kNumber, true}, {"phase_ms.costate", Kind::kNumber, true},
    {"phase_ms.gmres", Kind::kNumber, true}, {"evaluations_per_update", Kind::kInteger, true},
    {"init_residual", Kind::kNumber, true}, {"final_q_error", Kind::kNumber, true},
    {"final_v_norm", Kind::kNumber, true}, {"mean_residual", Kind::kNumber, true},
    {"reached", Kind::kBool, false}, {"tracking.position_rms", Kind::kNumber, true},
    {"tracking.position_max", Kind::kNumber, true}, {"tracking.orientation_rms", Kind::kNumber, true},
    {"tracking.orientation_max", Kind::kNumber, true}, {"tracking.final_position_error", Kind::kNumber, true},
    {"tracking.samples", Kind::kInteger, true}, {"latency.control_period_ms", Kind::kNumber, true},
    {"latency.updates", Kind::kInteger, true}, {"latency.deadline_misses", Kind::kInteger, true},
    {"joint_error_rms", Kind::kNumber, false}, {"contact_steps", Kind::kInteger, false},
    {"max_contact_force", Kind::kNumber, false}, {"final_disturbance", Kind::kNumbers, false},
    {"implicit_damping", Kind::kBool, false}, {"open_loop_rate", Kind::kNumber, false},
    {"friction_velocity", Kind::kNumbers, false},
    {"weights.Qq", Kind::kNumbers, true}, {"weights.Qv", Kind::kNumbers, true}, {"weights.R", Kind::kNumbers, true},
    {"unbounded_joints", Kind::kStrings, false}, {"unmodeled", Kind::kStrings, true},
    {"notices", Kind::kStrings, false}, {"warnings", Kind::kStrings, true},
    {"torque_lower", Kind::kNumbersOrNulls, true}, {"torque_upper", Kind::kNumbersOrNulls, true},
    {"saturated_steps", Kind::kIntegers, true}, {"saturated_any", Kind::kInteger, true},
    {"max_constraint_violation", Kind::kNumberOrNull, false}, {"model_hash", Kind::kString, false},
    {"log_hash", Kind::kString, false}, {"held_joints", Kind::kStrings, false}, {"held_q", Kind::kNumbers, false},
    {"solver", Kind::kString, false}, {"joint_names", Kind::kStrings, false}, {"joint_types", Kind::kStrings, false}};

void check_summary_fields(const nlohmann::json& j, const std::string& where) {
  for (const SummaryField& f : kSummaryFields) {
    const std::string path = f.path;
    const std::size_t dot = path.find('.');
    const nlohmann::json* object = &j;
    if (dot != std::string::npos) {
      const std::string parent = path.substr(0, dot);
      if (!j.contains(parent)) continue;
      if (!j.at(parent).is_object()) {
        throw std::runtime_error(where + ": field '" + parent + "': expected an object, got " + abbreviate(j.at(parent).dump()));
      }
      object = &j.at(parent);
    }
    const std::string key = dot == std::string::npos ? path : path.substr(dot + 1);
    if (!object->contains(key)) {
      if (f.required) throw std::runtime_error(where + ": missing field '" + path + "' (" + expected(f.kind) + ")");
      continue;
    }
    const nlohmann::json& v = object->at(key);
    if (!is(v, f.kind)) {
      throw std::runtime_error(where + ": field '" + path + "': expected " + expected(f.kind) + ", got " +
                               abbreviate(v.dump()));
    }
  }
  if (j.at("diverged").get<bool>() && !(j.contains("diverged_at") && j.at("diverged_at").is_number())) {
    throw std::runtime_error(where + ": field 'diverged_at': expected a number (the run diverged), got " +
                             (j.contains("diverged_at") ? abbreviate(j.at("diverged_at").dump()) : std::string("none")));
  }
}

}  // namespace

RunSummary summary_from_json(const nlohmann::json& j, const std::string& source) {
  const std::string where = "run summary '" + source + "'";
  if (!j.is_object() || !j.contains("schema") || !j.at("schema").is_number_integer()) {
    throw std::runtime_error(where + ": expected an idmpc run summary with a 'schema' field");
  }
  if (j.at("schema").get<int>() != kRunRecordSchema) {
    throw std::runtime_error(where + ": schema " + j.at("schema").dump() + ", this idmpc reads schema " +
                             std::to_string(kRunRecordSchema));
  }
  check_summary_fields(j, where);
  if (!j.contains("task")) throw std::runtime_error(where + ": missing field 'task' (the task as run)");
  RunSummary s;
  try {
    try {
      // a task as run names its solver; one that leaves it unnamed is read as C/GMRES
      Task as_run;
      as_run.solver = "cgmres";
      s.task = task_from_json(j.at("task"), where + ", 'task'", as_run);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(e.what());
    }
    s.n = j.at("n").get<int>();
    s.simd_stages = j.at("simd_stages").get<bool>();
    s.zeta = j.at("zeta").get<double>();
    s.steps = j.at("steps").get<int>();
    s.diverged = j.at("diverged").get<bool>();
    if (s.diverged) s.diverged_at = j.at("diverged_at").get<double>();
    s.divergence_reason = j.at("divergence_reason").get<std::string>();
    s.divergence_hint = j.value("divergence_hint", std::string());
    s.mean_update_ms = j.at("mean_update_ms").get<double>();
    // percentiles of an empty sample are NaN, written as null
    auto number = [&](const char* key) {
      return j.at(key).is_null() ? std::numeric_limits<double>::quiet_NaN() : j.at(key).get<double>();
    };
    s.p50_update_ms = number("p50_update_ms");
    s.p95_update_ms = number("p95_update_ms");
    s.max_update_ms = number("max_update_ms");
    s.rollout_ms = j.at("phase_ms").at("rollout").get<double>();
    s.costate_ms = j.at("phase_ms").at("costate").get<double>();
    s.gmres_ms = j.at("phase_ms").at("gmres").get<double>();
    s.evaluations_per_update = j.at("evaluations_per_update").get<int>();
    s.init_residual = j.at("init_residual").get<double>();
    s.final_q_error = j.at("final_q_error").get<double>();
    s.final_v_norm = j.at("final_v_norm").get<double>();
    s.mean_residual = j.at("mean_residual").get<double>();
    if (j.contains("closed_loop_cost") && j.at("closed_loop_cost").is_number()) {
      s.closed_loop_cost = j.at("closed_loop_cost").get<double>();
    }
    // absent in summaries written before they existed
    s.reached = j.value("reached", false);
    if (j.contains("tracking")) {
      const auto& t = j.at("tracking");
      s.tracking = TrackingResult{t.at("position_rms").get<double>(),    t.at("position_max").get<double>(),
                                  t.at("orientation_rms").get<double>(), t.at("orientation_max").get<double>(),
                                  t.at("final_position_error").get<double>(), t.at("samples").get<long>()};
    }
    if (j.contains("latency")) {
      s.control_period_ms = j.at("latency").at("control_period_ms").get<double>();
      s.updates = j.at("latency").at("updates").get<long>();
      s.deadline_misses = j.at("latency").at("deadline_misses").get<long>();
    }
    s.joint_error_rms = j.value("joint_error_rms", 0.0);
    s.contact_steps = j.value("contact_steps", 0L);
    s.max_contact_force = j.value("max_contact_force", 0.0);
    s.final_disturbance = j.value("final_disturbance", std::vector<double>{});
    s.implicit_damping = j.value("implicit_damping", false);
    s.open_loop_rate = j.value("open_loop_rate", 0.0);
    s.friction_velocity = j.value("friction_velocity", std::vector<double>{});
    if (j.contains("weights")) {
      s.Qq = j.at("weights").at("Qq").get<std::vector<double>>();
      s.Qv = j.at("weights").at("Qv").get<std::vector<double>>();
      s.R = j.at("weights").at("R").get<std::vector<double>>();
    }
    s.unbounded_joints = j.value("unbounded_joints", std::vector<std::string>{});
    s.unmodeled = j.at("unmodeled").get<std::vector<std::string>>();
    s.notices = j.value("notices", std::vector<std::string>{});
    s.warnings = j.at("warnings").get<std::vector<std::string>>();
    auto limits = [&](const char* key, double unbounded) {
      std::vector<double> x;
      for (const auto& v : j.at(key)) x.push_back(v.is_null() ? unbounded : v.get<double>());
      return x;
    };
    s.torque_lower = limits("torque_lower", -std::numeric_limits<double>::infinity());
    s.torque_upper = limits("torque_upper", std::numeric_limits<double>::infinity());
    s.saturated_steps = j.at("saturated_steps").get<std::vector<long>>();
    s.saturated_any = j.at("saturated_any").get<long>();
    // absent in summaries written before it existed; null when the torques were not finite
    if (j.contains("max_constraint_violation")) s.max_constraint_violation = number("max_constraint_violation");
    if (j.contains("model_hash")) s.model_hash = j.at("model_hash").get<std::string>();
    if (j.contains("log_hash")) s.log_hash = j.at("log_hash").get<std::string>();
    s.joint_names = j.value("joint_names", std::vector<std::string>{});
    s.joint_types = j.value("joint_types", std::vector<std::string>{});
    s.held_joints = j.value("held_joints", std::vector<std::string>{});
    s.held_q = j.value("held_q", std::vector<double>{});
    if (s.held_q.size() != s.held_joints.size()) {
      throw std::runtime_error(where + ": 'held_q' has " + std::to_string(s.held_q.size()) + " values for " +
                               std::to_string(s.held_joints.size()) + " 'held_joints'");
    }
  } catch (const nlohmann::json::exception&) {
    // check_summary_fields names every field read above: a field it does not know
    throw std::runtime_error(where + ": a field of an unexpected type (not an idmpc run summary of this version?)");
  }
  return s;
}

RunSummary read_summary(const std::string& path) {
  return summary_from_json(read_json_file(path, "run summary"), path);
}

}  // namespace idmpc
