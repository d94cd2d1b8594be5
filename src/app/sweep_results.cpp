#include "app/sweep_results.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

#include "app/swingup.hpp"
#include "idmpc/experiment/input_file.hpp"

namespace idmpc::app {
namespace {

// the columns of sweep.csv and arms.csv
const std::vector<std::string> kCsvColumns = {
    "table", "model", "n", "formulation", "derivatives", "shooting", "offset_free", "N", "kmax", "Qa", "diverged",
    "diverged_at", "mean_update_ms", "p95_update_ms", "final_q_error", "reach_tolerance", "reached",
    "final_v_norm", "paper_ms", "paper_note", "steps", "saturated_steps", "max_constraint_violation",
    "contact_steps", "max_contact_force", "max_final_disturbance", "position_rms", "position_max",
    "orientation_rms", "orientation_max", "tracking_tolerance", "products", "mean_residual", "closed_loop_cost",
    "latency", "updates", "deadline_misses", "max_update_ms", "joint_error_rms", "solver", "settings"};

// the index of a column of kCsvColumns
size_t column(const char* name) {
  const auto it = std::find(kCsvColumns.begin(), kCsvColumns.end(), name);
  if (it == kCsvColumns.end()) throw std::logic_error(std::string("no sweep column ") + name);
  return static_cast<size_t>(it - kCsvColumns.begin());
}

CellResult run_cell(const Task& base, const Cell& c, const SweepOptions& opt) {
  const Task task = cell_task(base, c, opt);
  const std::string log = opt.logs ? opt.out_dir + "/" + log_name(c) : std::string();
  // the paper's rule: ID that fails with Q_a = 0 is rerun with the task's fallback Q_a
  const RunSummary s = run_swingup(task, log, true).summary;
  CellResult r;
  r.cell = c;
  r.cell.n = s.n;
  r.Qa = s.task.Qa.empty() ? 0.0 : s.task.Qa.front();
  r.steps = s.steps;
  r.saturated_steps = s.saturated_any;
  r.max_violation = s.max_constraint_violation;
  r.diverged = s.diverged;
  r.diverged_at = s.diverged ? s.diverged_at : NAN;
  r.mean_ms = s.mean_update_ms;
  r.p95_ms = s.p95_update_ms;
  r.final_q_error = s.final_q_error;
  r.final_v_norm = s.final_v_norm;
  r.reached = s.reached;
  r.reach_tolerance = s.task.reach_tolerance;
  r.contact_steps = s.contact_steps;
  r.max_contact_force = s.max_contact_force;
  r.mean_residual = s.mean_residual;
  r.closed_loop_cost = s.closed_loop_cost;
  r.max_ms = s.max_update_ms;
  r.updates = s.updates;
  r.deadline_misses = s.deadline_misses;
  r.joint_error_rms = s.joint_error_rms;
  r.final_disturbance = 0;
  for (double d : s.final_disturbance) r.final_disturbance = std::max(r.final_disturbance, std::abs(d));
  if (s.tracking) {
    r.position_rms = s.tracking->position_rms;
    r.position_max = s.tracking->position_max;
    r.orientation_rms = s.tracking->orientation_rms;
    r.orientation_max = s.tracking->orientation_max;
    r.tracking_tolerance = s.task.tracking_tolerance;
  }
  return r;
}

}  // namespace

PaperFigure paper_figure(const PaperTables& tables, const Cell& c) {
  const PaperCell* p = tables.find(c.table, c.formulation, c.n, c.N, c.kmax);
  return p ? PaperFigure{p->ms, p->mark} : PaperFigure{NAN, ""};
}

std::string csv_header() {
  std::string h;
  for (const std::string& c : kCsvColumns) h += (h.empty() ? "" : ",") + c;
  return h;
}

std::string csv_row(const PaperTables& tables, const CellResult& r) {
  const PaperFigure p = paper_figure(tables, r.cell);
  std::vector<std::string> f(kCsvColumns.size());
  auto set = [&](const char* name, const auto& value) {
    std::ostringstream o;
    o << std::setprecision(8) << value;
    f[column(name)] = o.str();
  };
  set("table", r.cell.table);
  set("model", r.cell.model);
  set("n", r.cell.n);
  set("formulation", r.cell.formulation);
  set("derivatives", r.cell.derivatives);
  set("shooting", r.cell.shooting);
  set("offset_free", r.cell.offset_free ? 1 : 0);
  set("N", r.cell.N);
  set("kmax", r.cell.kmax);
  set("Qa", r.Qa);
  set("diverged", r.diverged ? 1 : 0);
  set("diverged_at", r.diverged_at);
  set("mean_update_ms", r.mean_ms);
  set("p95_update_ms", r.p95_ms);
  set("final_q_error", r.final_q_error);
  set("reach_tolerance", r.reach_tolerance);
  set("reached", r.reached ? 1 : 0);
  set("final_v_norm", r.final_v_norm);
  set("paper_ms", p.ms);
  set("paper_note", p.note);
  set("steps", r.steps);
  set("saturated_steps", r.saturated_steps);
  set("max_constraint_violation", r.max_violation);
  set("contact_steps", r.contact_steps);
  set("max_contact_force", r.max_contact_force);
  set("position_rms", r.position_rms);
  set("position_max", r.position_max);
  set("orientation_rms", r.orientation_rms);
  set("orientation_max", r.orientation_max);
  set("tracking_tolerance", r.tracking_tolerance);
  set("max_final_disturbance", r.final_disturbance);
  set("products", r.cell.products);
  set("mean_residual", r.mean_residual);
  set("closed_loop_cost", r.closed_loop_cost);
  set("latency", r.cell.latency);
  set("updates", r.updates);
  set("deadline_misses", r.deadline_misses);
  set("max_update_ms", r.max_ms);
  set("joint_error_rms", r.joint_error_rms);
  set("solver", r.cell.solver);
  set("settings", r.cell.settings);
  std::string row;
  for (const std::string& x : f) row += (row.empty() ? "" : ",") + x;
  return row;
}

std::map<std::string, CellResult> read_finished(const std::string& path, const std::vector<Cell>& cells) {
  std::map<std::string, CellResult> done;
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec)) && !std::filesystem::exists(path, ec)) {
    return done;
  }
  // a regular file of bounded size: a FIFO, a device or a directory in its place is refused
  std::istringstream in(read_input_file(path, "sweep results", "a CSV file of sweep results"));
  std::string line;
  auto next = [&] {
    if (!std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next()) return done;
  const std::string refuse = "'" + path + "' holds ";
  const std::string what = "; use another --out or move it away";
  if (line != csv_header()) {
    if (line.rfind("table,model,n,formulation,", 0) == 0) {
      throw std::invalid_argument(refuse + "sweep results in the columns of another idmpc version" + what);
    }
    throw std::invalid_argument(refuse + "something other than this idmpc's sweep results" + what);
  }
  std::set<std::string> keys;
  for (const Cell& c : cells) keys.insert(c.key());
  while (next()) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) f.push_back(x);
    if (f.size() != kCsvColumns.size()) continue;
    auto at = [&](const char* name) -> const std::string& { return f[column(name)]; };
    try {
      CellResult r;
      r.cell = {at("table"), at("model"), at("formulation"), at("derivatives"), at("shooting"), std::stoi(at("n")),
                std::stoi(at("N")), std::stoi(at("kmax")), at("settings"), at("offset_free") == "1", at("products"),
                at("latency"), at("solver")};
      r.Qa = std::stod(at("Qa"));
      r.diverged = at("diverged") == "1";
      r.diverged_at = std::stod(at("diverged_at"));
      r.mean_ms = std::stod(at("mean_update_ms"));
      r.p95_ms = std::stod(at("p95_update_ms"));
      r.final_q_error = std::stod(at("final_q_error"));
      r.reach_tolerance = std::stod(at("reach_tolerance"));
      r.reached = at("reached") == "1";
      r.final_v_norm = std::stod(at("final_v_norm"));
      r.steps = std::stol(at("steps"));
      r.saturated_steps = std::stol(at("saturated_steps"));
      r.max_violation = std::stod(at("max_constraint_violation"));
      r.contact_steps = std::stol(at("contact_steps"));
      r.max_contact_force = std::stod(at("max_contact_force"));
      r.final_disturbance = std::stod(at("max_final_disturbance"));
      r.position_rms = std::stod(at("position_rms"));
      r.position_max = std::stod(at("position_max"));
      r.orientation_rms = std::stod(at("orientation_rms"));
      r.orientation_max = std::stod(at("orientation_max"));
      r.tracking_tolerance = std::stod(at("tracking_tolerance"));
      r.mean_residual = std::stod(at("mean_residual"));
      r.closed_loop_cost = std::stod(at("closed_loop_cost"));
      r.updates = std::stol(at("updates"));
      r.deadline_misses = std::stol(at("deadline_misses"));
      r.max_ms = std::stod(at("max_update_ms"));
      r.joint_error_rms = std::stod(at("joint_error_rms"));
      if (!keys.count(r.cell.key())) {
        throw std::invalid_argument(refuse + "results of a sweep with other settings (" + r.cell.model + " " +
                                    r.cell.formulation + " " + r.cell.variant() +
                                    (task_table(r.cell.table)
                                         ? std::string(r.cell.offset_free ? ", offset-free on" : ", offset-free off") +
                                               ": other duration, weights, task or --offset-free)"
                                         : std::string(": other duration, weights or task)")) +
                                    what);
      }
      done[r.cell.key()] = r;
    } catch (const std::logic_error& e) {
      if (dynamic_cast<const std::invalid_argument*>(&e) && std::string(e.what()).rfind(refuse, 0) == 0) throw;
      continue;  // a malformed number: a torn line
    }
  }
  return done;
}

std::string log_name(const Cell& c) {
  // the model or task file without its extension, a listed task's directories joined by '_'
  std::string name = std::filesystem::path(c.model).replace_extension().string();
  std::replace(name.begin(), name.end(), '/', '_');
  return "log_" + c.table + "_" + name + "_" + c.formulation + "_" + c.derivatives +
         (c.shooting == "single" ? "" : "_" + c.shooting) + (c.products == "difference" ? "" : "_" + c.products) +
         "_N" + std::to_string(c.N) + "_k" + std::to_string(c.kmax) +
         (task_table(c.table) ? (c.offset_free ? "_offset_on" : "_offset_off") : "") +
         (c.latency == "none" ? "" : "_latency_" + c.latency) + ".csv";
}

CellResult run_cell_after_progress(const Task& base, const Cell& c, const SweepOptions& opt) {
  try {
    return run_cell(base, c, opt);
  } catch (...) {
    std::fputc('\n', stderr);
    throw;
  }
}

}  // namespace idmpc::app
