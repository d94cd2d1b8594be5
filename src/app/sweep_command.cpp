// idmpc sweep: the paper's closed-loop grids (Tables 1–3), resumable, with our figures beside
// the paper's.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "app/data_dir_option.hpp"
#include "app/number_options.hpp"
#include "app/output_paths.hpp"
#include "app/sweep_cells.hpp"
#include "app/swingup.hpp"
#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/experiment/input_file.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc::app {
namespace {

struct SweepOptions {
  std::string out_dir = "results/sweep";
  std::string models_dir;             // empty: mjcf/ of the data directory
  std::string tables = "all";        // 12, 3, all or arms
  std::string arms_tasks;            // arms: the list of tasks; empty: arms.json of models_dir
  std::string offset_free = "task";  // arms: task (each task's own setting), on, off or both
  std::string derivatives = "matrix";  // matrix, adjoint or both
  std::string shooting = "single";     // single, multiple or both
  std::string products = "difference"; // difference, exact or both
  std::string solver = "cgmres";       // cgmres, riccati or both
  double duration = 10.0;
  bool duration_given = false;  // arms: the task files' own durations unless --duration is given
  bool logs = false;
  bool simd_stages = true;  // false: --no-simd-stages, every run stage by stage (the paper's arithmetic)
  std::vector<std::string> latency = {"none"};  // the compute latencies each cell runs with (an axis)
};

// what the tables' matrix mode is, for the tables' headers
std::string stages_note(const SweepOptions& opt) {
  return opt.simd_stages ? "Matrix mode runs its stage derivatives in SIMD lanes (the default; `sweep --no-simd-stages` "
                           "runs every stage one by one, the paper's arithmetic)."
                         : "Every run evaluates its stages one by one (`--no-simd-stages`): matrix mode is the "
                           "paper's arithmetic.";
}

// the real-arm grids: each task of a list under both formulations; arms: mjcf/arms.json (reach
// tasks), tracking: mjcf/tracking.json (frame targets that move), unless --arms-tasks
constexpr const char* kArmsTable = "arms";
constexpr const char* kTrackingTable = "tracking";
bool task_table(const std::string& table) { return table == kArmsTable || table == kTrackingTable; }
// the work-precision grid: mjcf/work_precision.json lists the paper's models (the swing-up on
// each), real arms' task files and the kmax values
constexpr const char* kWorkPrecisionTable = "work-precision";
// whether a cell of `table` on `model` runs a task file (a real arm's) rather than the paper's
// task on a model
bool runs_task_file(const std::string& table, const std::string& model) {
  return task_table(table) ||
         (table == kWorkPrecisionTable && model.size() > 5 && model.compare(model.size() - 5, 5, ".json") == 0);
}

struct Cell {
  // arms: model is the task file as the list names it
  std::string table, model, formulation, derivatives, shooting;
  int n = 0, N = 0, kmax = 0;
  std::string settings;      // hash of everything else the cell runs with (the task as run)
  bool offset_free = false;  // offset-free tracking (the disturbance observer) on
  std::string products = "difference";  // how C/GMRES forms its products (formulations.md §Exact products)
  std::string latency = "none";         // compute latency (Task::latency)
  std::string solver = "cgmres";        // the solver family (docs/solvers.md)
  // the resume key: every axis and setting the cell runs with. A cell's ID (--list-cells, --cell)
  // is its hash, so an axis added here reaches the cell runs with no other change.
  std::string key() const {
    return table + "|" + model + "|" + formulation + "|" + derivatives + "|" + shooting + "|" +
           (offset_free ? "offset-free" : "-") + "|" + std::to_string(N) + "|" + std::to_string(kmax) + "|" +
           products + "|" + settings + (latency == "none" ? "" : "|latency " + latency) +
           (solver == "cgmres" ? "" : "|solver " + solver);
  }
  // the solver variant, as the tables label it
  std::string variant() const {
    if (solver == "riccati") return "Riccati SQP-RTI";
    return derivatives + (shooting == "single" ? "" : ", " + shooting + " shooting") +
           (products == "difference" ? "" : ", " + products + " products");
  }
  bool runs_task_file() const { return app::runs_task_file(table, model); }
};

// the hash of the contents of a model file, the files it includes and its asset files (not of
// their paths: the same files in another --models directory are the same cells)
std::string model_files_hash(const std::string& model) {
  std::string hashes;
  for (const NamedPath& file : model_inputs(model)) hashes += file.option + "=" + file_hash(file.path) + "\n";
  return text_hash(hashes);
}

// the hash of the task as the cell runs it and of the model files it runs on (`files`:
// model_files_hash), so that a resumed sweep never mixes settings or models
std::string settings_hash(Task task, const std::string& model, const std::string& files) {
  task.model = model;  // as named in the grid, not where --models happens to put it
  task.source.clear();
  return text_hash(to_json(task).dump() + "\n" + files);
}

struct CellResult {
  Cell cell;
  double Qa = 0;
  bool diverged = false;
  double diverged_at = NAN, mean_ms = NAN, p95_ms = NAN, final_q_error = NAN, final_v_norm = NAN;
  long steps = 0, saturated_steps = 0;   // steps run; steps with a clamped torque
  double max_violation = NAN;            // of the OCP's torques over their bounds [N m]
  // the target reached: not diverged, final max|q − q_ref| below the task's reach_tolerance
  bool reached = false;
  double reach_tolerance = NAN;
  long contact_steps = 0;                // control steps with a contact in the plant
  double max_contact_force = NAN;        // the largest contact normal force [N]
  double final_disturbance = NAN;        // max|d̂| of the observer at the end [N m] (0 when off)
  // a frame target's tracking error: position [m] and orientation [rad], RMS and max (NaN without)
  double position_rms = NAN, position_max = NAN, orientation_rms = NAN, orientation_max = NAN;
  double tracking_tolerance = NAN;
  double mean_residual = NAN;     // mean ‖F‖ over the updates
  double closed_loop_cost = NAN;  // ∫ L dt of the task's stage cost along the run
  // compute latency: updates run, those slower than the control period, the slowest [ms], and the
  // tracking cost (RMS of |q - q_ref| over the run)
  long updates = 0, deadline_misses = 0;
  double max_ms = NAN, joint_error_rms = NAN;
};

// the paper's figure for a cell (mjcf/paper_tables.json)
struct PaperFigure {
  double ms;
  std::string note;
};
PaperFigure paper_figure(const PaperTables& tables, const Cell& c) {
  const PaperCell* p = tables.find(c.table, c.formulation, c.n, c.N, c.kmax);
  return p ? PaperFigure{p->ms, p->mark} : PaperFigure{NAN, ""};
}

// a file of the models directory (an absolute name stays as it is)
std::string in_models(const SweepOptions& opt, const std::string& file) {
  return opt.models_dir.empty() ? shipped_mjcf_path(file) : (std::filesystem::path(opt.models_dir) / file).string();
}

// the list of tasks of the arms table: --arms-tasks, or arms.json of the models directory
std::string arms_list(const SweepOptions& opt) {
  if (!opt.arms_tasks.empty()) return opt.arms_tasks;
  return in_models(opt, opt.tables == kTrackingTable ? "tracking.json" : "arms.json");
}

// the file a cell runs: the paper's model, or an arm's task file (relative to its list's directory)
std::string cell_file(const SweepOptions& opt, const Cell& c) {
  if (!c.runs_task_file()) return in_models(opt, c.model);
  if (c.table == kWorkPrecisionTable) return in_models(opt, c.model);
  return (std::filesystem::path(arms_list(opt)).parent_path() / c.model).string();
}

// the task a cell runs: the paper's on the cell's model, or an arm's own task file
Task cell_task(const Task& base, const Cell& c, const SweepOptions& opt) {
  const bool arm = c.runs_task_file();
  Task task = arm ? load_task(cell_file(opt, c)) : base;
  if (!arm) {
    task.model = cell_file(opt, c);
    task.Qa = {0.0};  // the paper's rule: Q_a = 0 first, the fallback only after a divergence
  }
  task.formulation = c.formulation;
  task.derivatives = c.derivatives;
  task.shooting = c.shooting;
  task.products = c.products;
  task.latency = c.latency;
  task.solver = c.solver;
  task.N = c.N;
  task.kmax = c.kmax;
  task.offset_free = c.offset_free;
  if (!arm || opt.duration_given) task.duration = opt.duration;
  if (!opt.simd_stages) task.simd_stages = false;
  return task;
}

// the list of strings `key` of a JSON object read from `path`, refused in one line naming the
// file and the field (not the JSON library's words)
std::vector<std::string> strings_field(const nlohmann::json& j, const char* key, const std::string& path,
                                       const std::string& items, const std::string& what = "") {
  const std::string expected = "'" + path + "': field '" + key + "': expected a list of " + items;
  if (!j.is_object()) throw std::invalid_argument("'" + path + "': expected a JSON object with the field '" + key + "'" + what);
  if (!j.contains(key)) throw std::invalid_argument("'" + path + "': missing field '" + key + "' (a list of " + items + ")" + what);
  const nlohmann::json& v = j.at(key);
  if (!v.is_array()) throw std::invalid_argument(expected + ", got " + abbreviate(v.dump()) + what);
  std::vector<std::string> out;
  for (const nlohmann::json& x : v) {
    if (!x.is_string()) throw std::invalid_argument(expected + ", got the entry " + abbreviate(x.dump()) + what);
    out.push_back(x.get<std::string>());
  }
  return out;
}

// one key per file however its path is spelled (./a.json, d/../a.json, a link): the canonical
// path of an existing file, else the path made absolute and normal
std::string same_file_key(const std::filesystem::path& p) {
  std::error_code ec;
  const std::filesystem::path canonical = std::filesystem::weakly_canonical(p, ec);
  if (!ec) return canonical.string();
  return std::filesystem::absolute(p, ec).lexically_normal().string();
}

// the task files of the arms table's list ({"tasks": [files relative to the list]}), each once
std::vector<std::string> arm_tasks(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  const std::string path = arms_list(opt);
  const std::string what = opt.arms_tasks.empty() ? " (the list of real-arm tasks; see --models and --arms-tasks)"
                                                  : " (--arms-tasks)";
  nlohmann::json list;
  try {
    list = read_json_file(path, "task list");
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(e.what() + what);
  }
  const std::vector<std::string> tasks = strings_field(list, "tasks", path, "task files, relative to the list", what);
  if (tasks.empty()) throw std::invalid_argument("'" + path + "' lists no task" + what);
  std::vector<std::string> files;  // each task's file, however the list spells it
  for (size_t k = 0; k < tasks.size(); ++k) {
    if (tasks[k].empty() || tasks[k].find_first_of(",\r\n") != std::string::npos) {
      throw std::invalid_argument("'" + path + "' lists the task file name '" + abbreviate(tasks[k]) +
                                  "', empty or with a comma or line break (it names a CSV row)" + what);
    }
    files.push_back(same_file_key(fs::path(path).parent_path() / tasks[k]));
    const auto earlier = std::find(files.begin(), files.end() - 1, files.back());
    if (earlier != files.end() - 1) {
      const std::string first = tasks[static_cast<size_t>(earlier - files.begin())];
      throw std::invalid_argument("'" + path + "' lists '" + abbreviate(tasks[k]) + "' twice" +
                                  (first == tasks[k] ? "" : " (also as '" + abbreviate(first) + "')") + what);
    }
  }
  return tasks;
}

// a listed task that cannot run is refused before any cell runs: the task file reads, its model
// loads, and its settings fit the model (q0, q_ref, limits and weights per joint)
Task checked_arm_task(const SweepOptions& opt, const std::string& file) {
  const std::string path = cell_file(opt, Cell{opt.tables, file, "", "", "", 0, 0, 0, "", false});
  try {
    Task task = load_task(path);
    const mj::TaskRun run(task);
    return task;
  } catch (const std::exception& e) {
    throw std::invalid_argument("'" + arms_list(opt) + "' lists '" + file + "', which cannot run: " + e.what());
  }
}

// the values of the offset-free axis for a task: --offset-free, or the task's own setting
std::vector<bool> offset_free_axis(const SweepOptions& opt, const Task& task) {
  if (opt.offset_free == "both") return {true, false};
  if (opt.offset_free == "on") return {true};
  if (opt.offset_free == "off") return {false};
  return {task.offset_free};
}

std::vector<Cell> grid_of(const SweepOptions& opt, const PaperTables& tables, const Task& base);

// the work-precision grid's list (mjcf/work_precision.json of the models directory): the runs
// (the paper's models, then task files) and the kmax values
// kmax as an int holds it (the GMRES basis bounds it further, for each model)
constexpr std::int64_t kMaxKmax = std::numeric_limits<int>::max();
struct WorkPrecisionGrid {
  std::vector<std::string> runs;
  std::vector<int> kmax;
};
WorkPrecisionGrid work_precision_grid(const SweepOptions& opt) {
  const std::string path = in_models(opt, "work_precision.json");
  const nlohmann::json j = read_json_file(path, "work-precision grid");
  WorkPrecisionGrid g;
  for (const char* key : {"models", "tasks"}) {
    for (const std::string& x : strings_field(j, key, path, std::string(key) + " files")) g.runs.push_back(x);
  }
  if (!j.contains("kmax")) throw std::invalid_argument("'" + path + "': missing field 'kmax' (a list of integers)");
  const nlohmann::json& kmax = j.at("kmax");
  const std::string expected = "'" + path + "': field 'kmax': expected a list of integers from 1 to " +
                               std::to_string(kMaxKmax);
  if (!kmax.is_array()) throw std::invalid_argument(expected + ", got " + abbreviate(kmax.dump()));
  for (const nlohmann::json& k : kmax) {
    // the JSON integer itself, never wrapped to int (4294967306 is not 10)
    const bool in_range = k.is_number_unsigned() ? k.get<std::uint64_t>() >= 1 && k.get<std::uint64_t>() <= static_cast<std::uint64_t>(kMaxKmax)
                          : k.is_number_integer() ? k.get<std::int64_t>() >= 1 && k.get<std::int64_t>() <= kMaxKmax
                                                  : false;
    if (!in_range) throw std::invalid_argument(expected + ", got the entry " + abbreviate(k.dump()));
    const int value = static_cast<int>(k.get<std::int64_t>());
    if (std::find(g.kmax.begin(), g.kmax.end(), value) != g.kmax.end()) {
      throw std::invalid_argument("'" + path + "': field 'kmax' lists " + std::to_string(value) + " twice");
    }
    g.kmax.push_back(value);
  }
  for (size_t k = 0; k < g.runs.size(); ++k) {
    const std::string& x = g.runs[k];
    if (x.empty() || x.find_first_of(",\r\n") != std::string::npos) {
      throw std::invalid_argument("'" + path + "' lists the file name '" + abbreviate(x) +
                                  "', empty or with a comma or line break (it names a CSV row)");
    }
    if (std::find(g.runs.begin(), g.runs.begin() + static_cast<std::ptrdiff_t>(k), x) !=
        g.runs.begin() + static_cast<std::ptrdiff_t>(k)) {
      throw std::invalid_argument("'" + path + "' lists '" + abbreviate(x) + "' twice");
    }
  }
  if (g.runs.empty() || g.kmax.empty()) throw std::invalid_argument("'" + path + "' lists no run or no kmax");
  return g;
}

// the grid, each cell keyed by the settings it runs with
std::vector<Cell> grid(const SweepOptions& opt, const PaperTables& tables, const Task& base) {
  std::vector<Cell> cells = grid_of(opt, tables, base);
  std::map<std::string, std::string> files;  // model_files_hash per model file, read once
  for (Cell& c : cells) {
    const Task task = cell_task(base, c, opt);
    auto it = files.find(task.model);
    if (it == files.end()) it = files.emplace(task.model, model_files_hash(task.model)).first;
    c.settings = settings_hash(task, c.model, it->second);
  }
  return cells;
}

// the cells of the chosen tables (the paper's in the file's order) for the chosen derivative
// modes and shooting schemes
std::vector<Cell> grid_of(const SweepOptions& opt, const PaperTables& tables, const Task& base) {
  std::vector<std::string> modes, shootings, products;
  if (opt.products == "both") {
    products = {"difference", "exact"};
  } else {
    parse_products(opt.products);
    products = {opt.products};
  }
  if (opt.derivatives == "both") {
    modes = {"matrix", "adjoint"};
  } else {
    parse_derivative_mode(opt.derivatives);
    modes = {opt.derivatives};
  }
  if (opt.shooting == "both") {
    shootings = {"single", "multiple"};
  } else {
    parse_shooting(opt.shooting);
    shootings = {opt.shooting};
  }
  if (opt.tables != "12" && opt.tables != "3" && opt.tables != "all" && !task_table(opt.tables) &&
      opt.tables != kWorkPrecisionTable) {
    throw std::invalid_argument("--tables must be 12, 3, all, arms, tracking or work-precision, got '" + opt.tables +
                                "'");
  }
  if (opt.offset_free != "task" && opt.offset_free != "on" && opt.offset_free != "off" && opt.offset_free != "both") {
    throw std::invalid_argument("--offset-free must be task, on, off or both, got '" + opt.offset_free + "'");
  }
  if (!task_table(opt.tables) && opt.offset_free != "task") {
    throw std::invalid_argument("--offset-free is an axis of --tables arms and tracking only, got --tables " +
                                opt.tables);
  }
  if (!task_table(opt.tables) && !opt.arms_tasks.empty()) {
    throw std::invalid_argument("--arms-tasks lists the tasks of --tables arms or tracking, got --tables " +
                                opt.tables);
  }
  std::vector<std::string> solvers;
  if (opt.solver == "both") {
    solvers = {"cgmres", "riccati"};
  } else {
    parse_solver(opt.solver);
    solvers = {opt.solver};
  }
  // the solver variants: C/GMRES's derivative modes × shooting schemes × products, and the
  // Riccati solver's one (its stage Jacobians are matrices, its shooting multiple)
  struct Variant {
    std::string solver, mode, shooting, product;
  };
  std::vector<Variant> variants;
  for (const auto& solver : solvers) {
    if (solver == "riccati") {
      variants.push_back({solver, "matrix", "single", "difference"});
      continue;
    }
    for (const auto& mode : modes) {
      for (const auto& shooting : shootings) {
        for (const auto& product : products) variants.push_back({solver, mode, shooting, product});
      }
    }
  }
  std::vector<Cell> cells;
  if (task_table(opt.tables)) {
    std::vector<std::pair<std::string, Task>> tasks;
    for (const std::string& file : arm_tasks(opt)) tasks.emplace_back(file, checked_arm_task(opt, file));
    for (const Variant& v : variants) {
      for (const auto& [file, t] : tasks) {
        for (const bool offset_free : offset_free_axis(opt, t)) {
          for (const std::string& latency : opt.latency) {
            for (const char* f : {"fd", "id"}) {
              cells.push_back({opt.tables, file, f, v.mode, v.shooting, 0, t.N, t.kmax, "", offset_free, v.product,
                               latency, v.solver});
            }
          }
        }
      }
    }
    return cells;
  }
  if (opt.tables == kWorkPrecisionTable) {
    const WorkPrecisionGrid g = work_precision_grid(opt);
    for (const std::string& model : g.runs) {
      const bool file = runs_task_file(kWorkPrecisionTable, model);
      const Task t = file ? load_task(in_models(opt, model)) : base;
      for (const Variant& v : variants) {
        for (const char* f : {"fd", "id"}) {
          for (const int kmax : g.kmax) {
            for (const std::string& latency : opt.latency) {
              cells.push_back({kWorkPrecisionTable, model, f, v.mode, v.shooting, 0, t.N, kmax, "", t.offset_free,
                               v.product, latency, v.solver});
            }
          }
        }
      }
    }
    return cells;
  }
  for (const Variant& v : variants) {
    for (const PaperCell& p : tables.cells) {
      if (opt.tables != "all" && p.table != opt.tables) continue;
      for (const std::string& latency : opt.latency) {
        cells.push_back({p.table, p.model, p.formulation, v.mode, v.shooting, p.n, p.N, p.kmax, "", base.offset_free,
                         v.product, latency, v.solver});
      }
    }
  }
  return cells;
}

// the columns of sweep.csv and arms.csv
const std::vector<std::string> kCsvColumns = {
    "table", "model", "n", "formulation", "derivatives", "shooting", "offset_free", "N", "kmax", "Qa", "diverged",
    "diverged_at", "mean_update_ms", "p95_update_ms", "final_q_error", "reach_tolerance", "reached",
    "final_v_norm", "paper_ms", "paper_note", "steps", "saturated_steps", "max_constraint_violation",
    "contact_steps", "max_contact_force", "max_final_disturbance", "position_rms", "position_max",
    "orientation_rms", "orientation_max", "tracking_tolerance", "products", "mean_residual", "closed_loop_cost",
    "latency", "updates", "deadline_misses", "max_update_ms", "joint_error_rms", "solver", "settings"};

std::string csv_header() {
  std::string h;
  for (const std::string& c : kCsvColumns) h += (h.empty() ? "" : ",") + c;
  return h;
}

// the index of a column of kCsvColumns
size_t column(const char* name) {
  const auto it = std::find(kCsvColumns.begin(), kCsvColumns.end(), name);
  if (it == kCsvColumns.end()) throw std::logic_error(std::string("no sweep column ") + name);
  return static_cast<size_t>(it - kCsvColumns.begin());
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

// finished cells of an earlier, possibly interrupted, sweep of this grid (CRLF line ends
// accepted; a torn last line, as an interrupted append leaves it, is dropped). A file of
// another format or with cells of other settings is refused, never overwritten.
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

std::string fmt(double x, int precision = 3) {
  if (std::isnan(x)) return "–";
  std::ostringstream o;
  o << std::setprecision(precision) << x;
  return o.str();
}

// one cell of a Markdown table: ours (paper), with the paper's marks
std::string md_cell(const PaperTables& tables, const CellResult* r) {
  if (!r) return "–";
  const PaperFigure p = paper_figure(tables, r->cell);
  std::string s = fmt(r->mean_ms) + (r->diverged ? "*" : "") + (r->Qa > 0 ? "†" : "");
  return s + " (" + fmt(p.ms) + p.note + ")";
}

// the distinct values of a field over a table's paper cells, ascending
template <typename Field>
std::vector<int> axis(const PaperTables& tables, const std::string& table, Field field) {
  std::set<int> values;
  for (const PaperCell& p : tables.cells) {
    if (p.table == table) values.insert(field(p));
  }
  return {values.begin(), values.end()};
}

// the paper's cell of a table at (n, N, kmax), for its model name
const PaperCell& paper_cell(const PaperTables& tables, const std::string& table, int n, int N, int kmax) {
  for (const PaperCell& p : tables.cells) {
    if (p.table == table && p.n == n && p.N == N && p.kmax == kmax) return p;
  }
  throw std::logic_error("no paper cell for table " + table);
}

// the solver variants of a grid (Cell::variant: derivatives, shooting), in the grid's order
std::vector<std::string> variants(const std::vector<Cell>& cells) {
  std::vector<std::string> out;
  for (const Cell& c : cells) {
    if (std::find(out.begin(), out.end(), c.variant()) == out.end()) out.push_back(c.variant());
  }
  return out;
}

// the rows of a task-list table (arms, tracking): each task with each offset-free setting it runs
// with, in the grid's order, and the finished cells of a row
struct TaskRows {
  using Row = std::pair<std::string, bool>;
  const std::vector<Cell>& cells;
  const std::map<std::string, CellResult>& done;
  std::vector<Row> rows;
  std::vector<std::string> modes;  // the solver variants, in the grid's order

  TaskRows(const std::vector<Cell>& c, const std::map<std::string, CellResult>& d) : cells(c), done(d) {
    modes = variants(cells);
    for (const Cell& cell : cells) {
      if (std::find(rows.begin(), rows.end(), Row{cell.model, cell.offset_free}) == rows.end()) {
        rows.emplace_back(cell.model, cell.offset_free);
      }
    }
  }
  const CellResult* find(const Cell& c) const {
    const auto it = done.find(c.key());
    return it == done.end() ? nullptr : &it->second;
  }
  const CellResult* cell_of(const Row& row, const std::string& f, const std::string& mode) const {
    for (const Cell& c : cells) {
      if (c.model == row.first && c.offset_free == row.second && c.formulation == f && c.variant() == mode) {
        return find(c);
      }
    }
    return nullptr;
  }
};

// the real-arm tables: time per update with ID/FD, then each run's outcome
std::string arms_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                          const std::map<std::string, CellResult>& done) {
  const TaskRows table(cells, done);
  const std::vector<std::string>& modes = table.modes;
  const std::vector<TaskRows::Row>& rows = table.rows;
  using Row = TaskRows::Row;
  std::set<double> tolerances;  // of the finished cells
  for (const Cell& c : cells) {
    if (const CellResult* r = table.find(c)) tolerances.insert(r->reach_tolerance);
  }
  auto cell_of = [&](const Row& row, const std::string& f, const std::string& mode) {
    return table.cell_of(row, f, mode);
  };
  auto ms = [](const CellResult* r) {
    return r ? fmt(r->mean_ms) + (r->diverged ? "*" : (r->reached ? "" : "°")) : std::string("–");
  };
  auto on_off = [](bool on) { return std::string(on ? "on" : "off"); };
  // one tolerance for all: said in the headers; else each run's beside its outcome
  const bool one_tolerance = tolerances.size() == 1;
  const std::string tolerance =
      one_tolerance ? fmt(*tolerances.begin()) + " rad" : std::string("the task's reach_tolerance");
  const bool shipped_list = opt.arms_tasks.empty() && opt.models_dir.empty();
  std::ostringstream o;
  o << "# idmpc sweep: the real arms\n\n"
    << "Each task of `" << (shipped_list ? std::string("mjcf/arms.json") : arms_list(opt)) << "` under FD and ID, "
    << "torque limits from the arm's actuators active in the OCP and at the plant. Offset-free tracking (a "
    << "disturbance observer whose estimate enters the horizon model of both formulations): "
    << (opt.offset_free == "task"   ? "as each task sets it"
        : opt.offset_free == "both" ? "on and off for every task, side by side (`--offset-free both`)"
                                    : on_off(opt.offset_free == "on") + " for every task (`--offset-free " +
                                          opt.offset_free + "`)")
    << ". Mean ms per control update; `*` diverged (time averaged until then), `°` did not end within "
    << (one_tolerance ? tolerance + " of the target (max abs(q - qref); the tasks' reach_tolerance)"
                      : std::string("its task's reach_tolerance of the target (max abs(q - qref); see the outcomes)"))
    << ". The last column compares "
    << "each formulation's fastest variant that reached the target. " << stages_note(opt)
    << "\n\n| task | n | offset-free |";
  for (const auto& mode : modes) o << " FD " << mode << " | ID " << mode << " | ID/FD |";
  o << " best ID / best FD |\n|---|---|---|";
  for (size_t k = 0; k < modes.size(); ++k) o << "---|---|---|";
  o << "---|\n";
  // a formulation's fastest variant that reached the target
  auto best = [&](const Row& row, const char* f) {
    double ms = NAN;
    for (const auto& mode : modes) {
      const CellResult* r = cell_of(row, f, mode);
      if (r && r->reached && !(r->mean_ms >= ms)) ms = r->mean_ms;
    }
    return ms;
  };
  for (const Row& row : rows) {
    int n = 0;
    for (const auto& mode : modes) {
      for (const char* f : {"fd", "id"}) {
        if (const CellResult* r = cell_of(row, f, mode)) n = r->cell.n;
      }
    }
    o << "| " << row.first << " | " << (n > 0 ? std::to_string(n) : "–") << " | " << on_off(row.second) << " |";
    for (const auto& mode : modes) {
      const CellResult *fd = cell_of(row, "fd", mode), *id = cell_of(row, "id", mode);
      o << ' ' << ms(fd) << " | " << ms(id) << " | " << fmt(fd && id ? id->mean_ms / fd->mean_ms : NAN, 2) << " |";
    }
    o << ' ' << fmt(best(row, "id") / best(row, "fd"), 2) << " |\n";
  }
  o << "\n## Outcomes\n\n| task | variant | reached (" << (one_tolerance ? "< " : "within ") << tolerance
    << ") | final max abs(q - qref) [rad] | offset-free (final max abs(d̂) [N m]) | steps with a contact "
       "(largest normal force [N]) | steps with a clamped torque | largest excess of the OCP's torques over their "
       "bounds [N m] |\n|---|---|---|---|---|---|---|---|\n";
  for (const Row& row : rows) {
    for (const auto& mode : modes) {
      for (const char* f : {"fd", "id"}) {
        const CellResult* r = cell_of(row, f, mode);
        if (!r) continue;
        std::string reached = r->diverged ? "diverged at " + fmt(r->diverged_at) + " s" : (r->reached ? "yes" : "no");
        if (!one_tolerance) reached += " (< " + fmt(r->reach_tolerance) + ")";
        o << "| " << row.first << " | " << (std::string(f) == "fd" ? "FD " : "ID ") << mode << " | " << reached
          << " | " << fmt(r->final_q_error) << " | "
          << (r->cell.offset_free ? "on (" + fmt(r->final_disturbance) + ")" : std::string("off")) << " | "
          << r->contact_steps << (r->contact_steps > 0 ? " (" + fmt(r->max_contact_force) + ")" : std::string())
          << " | " << r->saturated_steps << " of " << r->steps << " | " << fmt(r->max_violation) << " |\n";
      }
    }
  }
  return o.str();
}

// the tracking table: per task (and offset-free setting) and variant, FD beside ID: ms per update
// and the frame's position error, RMS and max over the run, with the orientation error
std::string tracking_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                              const std::map<std::string, CellResult>& done) {
  const TaskRows table(cells, done);
  auto mm = [](double m) { return fmt(1e3 * m, 3); };
  const bool shipped_list = opt.arms_tasks.empty() && opt.models_dir.empty();
  std::ostringstream o;
  o << "# idmpc sweep: tracking a moving frame target\n\n"
    << "Each task of `" << (shipped_list ? std::string("mjcf/tracking.json") : arms_list(opt))
    << "` under FD and ID: a frame of the arm (its tool point) follows a reference that moves, torque limits from "
       "the arm's actuators active in the OCP and at the plant. Mean ms per control update; the position error "
       "|p - p_ref| of the frame measured on the plant (MuJoCo's kinematics) at every control step against the "
       "reference at that time, RMS and max over the run [mm]; the orientation error (angle of R_ref^T R) RMS "
       "[deg]. `*` diverged, `°` RMS position error not below the task's tracking_tolerance. "
    << stages_note(opt) << "\n\n| task | offset-free | variant | FD ms | ID ms | ID/FD | FD RMS / max [mm] | "
       "ID RMS / max [mm] | FD / ID orientation RMS [deg] |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const TaskRows::Row& row : table.rows) {
    for (const auto& mode : table.modes) {
      const CellResult *fd = table.cell_of(row, "fd", mode), *id = table.cell_of(row, "id", mode);
      auto ms = [](const CellResult* r) {
        return r ? fmt(r->mean_ms) + (r->diverged ? "*" : (r->reached ? "" : "°")) : std::string("–");
      };
      auto err = [&](const CellResult* r) {
        return r && !r->diverged ? mm(r->position_rms) + " / " + mm(r->position_max) : std::string("–");
      };
      auto deg = [](const CellResult* r) {
        return r && !r->diverged ? fmt(r->orientation_rms * 180.0 / M_PI, 3) : std::string("–");
      };
      o << "| " << row.first << " | " << (row.second ? "on" : "off") << " | " << mode << " | " << ms(fd) << " | "
        << ms(id) << " | " << fmt(fd && id ? id->mean_ms / fd->mean_ms : NAN, 2) << " | " << err(fd) << " | "
        << err(id) << " | " << deg(fd) << " / " << deg(id) << " |\n";
    }
  }
  return o.str();
}

// the latency table: each run under every latency of the axis side by side: deadline misses
// (updates slower than the control period) of the updates run, mean and max ms per update, and the
// tracking cost (RMS of |q - q_ref| over the run) against the first latency's
std::string latency_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                             const std::map<std::string, CellResult>& done) {
  // a run without its latency (whose settings differ by it alone)
  auto run_of = [](Cell c) {
    c.latency = "none";
    c.settings.clear();
    return c.key();
  };
  std::vector<std::string> runs;
  std::map<std::string, const Cell*> first_cell;
  for (const Cell& c : cells) {
    if (first_cell.emplace(run_of(c), &c).second) runs.push_back(run_of(c));
  }
  auto result = [&](const std::string& run, const std::string& latency) -> const CellResult* {
    for (const Cell& c : cells) {
      if (c.latency == latency && run_of(c) == run) {
        const auto it = done.find(c.key());
        return it == done.end() ? nullptr : &it->second;
      }
    }
    return nullptr;
  };
  const std::string& base = opt.latency.front();
  std::ostringstream o;
  o << "\n## Compute latency\n\n"
    << "Every run under each `--latency`: `none` applies each torque one control period after its measurement "
       "(the paper's timing, eqs. 27-28); `measured` applies it after the whole plant steps the update's wall "
       "time took, the controller skipping the control steps it is still busy at; a figure in ms does the same "
       "with that compute time. A deadline miss is an update slower than the control period (counted under "
       "every setting: for `none` and `measured` from the wall time on this machine). Meets its rate: no "
       "update of its `none` and `measured` runs missed the deadline. Tracking cost: RMS over the run of "
       "|q - q_ref| [rad]; the last columns divide it by the `"
    << base << "` run's. The tables above are of the first latency, `" << base << "`. `*` diverged.\n\n| run | f |";
  for (const std::string& l : opt.latency) {
    o << " " << l << ": misses / updates | " << l << ": mean / max ms | " << l << ": cost |";
  }
  o << " meets its rate |";
  for (size_t k = 1; k < opt.latency.size(); ++k) o << " cost " << opt.latency[k] << " / " << base << " |";
  o << "\n|---|---|";
  for (size_t k = 0; k < opt.latency.size(); ++k) o << "---|---|---|";
  o << "---|";
  for (size_t k = 1; k < opt.latency.size(); ++k) o << "---|";
  o << "\n";
  for (const std::string& run : runs) {
    const Cell& c = *first_cell.at(run);
    o << "| " << c.model << " " << c.variant()
      << (task_table(c.table) ? std::string(c.offset_free ? ", offset-free" : "")
                              : " N=" + std::to_string(c.N) + " kmax=" + std::to_string(c.kmax))
      << " | " << (c.formulation == "fd" ? "FD" : "ID") << " |";
    bool measured = false, meets = true;
    for (const std::string& l : opt.latency) {
      const CellResult* r = result(run, l);
      if (!r) {
        o << " – | – | – |";
        continue;
      }
      if (l == "none" || l == "measured") {
        measured = true;
        meets = meets && r->deadline_misses == 0 && !r->diverged;
      }
      o << " " << r->deadline_misses << " / " << r->updates << " | " << fmt(r->mean_ms) << " / " << fmt(r->max_ms)
        << " | " << fmt(r->joint_error_rms) << (r->diverged ? "*" : "") << " |";
    }
    o << " " << (measured ? (meets ? "yes" : "no") : "–") << " |";
    const CellResult* first = result(run, base);
    for (size_t k = 1; k < opt.latency.size(); ++k) {
      const CellResult* r = result(run, opt.latency[k]);
      o << " " << fmt(first && r && !first->diverged && !r->diverged ? r->joint_error_rms / first->joint_error_rms : NAN, 3)
        << " |";
    }
    o << "\n";
  }
  return o.str();
}

// the work-precision tables: per run and derivative mode, each formulation's time per update
// against its accuracy over kmax and the products; then the verdict as the time each
// formulation needs to reach a residual or a closed-loop cost
std::string work_precision_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                                    const std::map<std::string, CellResult>& done) {
  auto find = [&](const Cell& c) -> const CellResult* {
    const auto it = done.find(c.key());
    return it == done.end() ? nullptr : &it->second;
  };
  std::vector<std::string> runs, modes, products;
  std::vector<int> kmaxs;
  auto add = [](auto& v, const auto& x) {
    if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
  };
  for (const Cell& c : cells) {
    add(runs, c.model);
    add(modes, c.derivatives + (c.shooting == "single" ? "" : ", " + c.shooting + " shooting"));
    add(products, c.products);
    add(kmaxs, c.kmax);
  }
  auto mode_of = [](const Cell& c) {
    return c.derivatives + (c.shooting == "single" ? "" : ", " + c.shooting + " shooting");
  };
  auto cell_of = [&](const std::string& run, const std::string& mode, const std::string& f,
                     const std::string& product, int kmax) -> const CellResult* {
    for (const Cell& c : cells) {
      if (c.model == run && mode_of(c) == mode && c.formulation == f && c.products == product && c.kmax == kmax) {
        return find(c);
      }
    }
    return nullptr;
  };
  auto upper = [](const std::string& f) { return std::string(f == "fd" ? "FD" : "ID"); };
  std::ostringstream o;
  o << "# idmpc sweep: work–precision\n\n"
    << "Each run of `mjcf/work_precision.json` (the paper's swing-up on its models, the real arms' reach tasks) in "
       "closed loop with the MuJoCo plant, "
    << (opt.duration_given ? fmt(opt.duration) + " s simulated" : "the swing-ups " + fmt(opt.duration) +
                                                                       " s, the tasks their own duration")
    << ", under FD and ID for each kmax and each kind of C/GMRES product (`difference`: the paper's forward "
       "differences, h = 1e-8; `exact`: dual numbers, stage by stage). Each entry: mean ms per update · mean "
       "optimality residual ‖F‖ · closed-loop cost ∫L dt of the task's stage cost; `*` diverged (means until "
       "then). "
    << stages_note(opt) << "\n";
  for (const std::string& run : runs) {
    int n = 0;
    for (const Cell& c : cells) {
      if (c.model != run) continue;
      if (const CellResult* r = find(c)) n = r->cell.n;
    }
    for (const std::string& mode : modes) {
      o << "\n## " << run << " (n = " << (n > 0 ? std::to_string(n) : "–") << "), derivatives: " << mode
        << "\n\n| kmax |";
      for (const char* f : {"fd", "id"}) {
        for (const std::string& p : products) o << ' ' << upper(f) << ' ' << p << " |";
      }
      o << "\n|---|";
      for (size_t k = 0; k < 2 * products.size(); ++k) o << "---|";
      o << '\n';
      for (int kmax : kmaxs) {
        o << "| " << kmax << " |";
        for (const char* f : {"fd", "id"}) {
          for (const std::string& p : products) {
            const CellResult* r = cell_of(run, mode, f, p, kmax);
            o << ' '
              << (r ? fmt(r->mean_ms) + (r->diverged ? "*" : "") + " · " + fmt(r->mean_residual, 2) + " · " +
                          fmt(r->closed_loop_cost, 4)
                    : std::string("–"))
              << " |";
          }
        }
        o << '\n';
      }
    }
  }
  // the verdict: the least time per update with which a formulation reaches a target, over kmax
  // and products (runs that diverged do not count)
  auto fastest = [&](const std::string& run, const std::string& mode, const std::string& f, auto reaches) {
    const CellResult* best = nullptr;
    for (const Cell& c : cells) {
      if (c.model != run || mode_of(c) != mode || c.formulation != f) continue;
      const CellResult* r = find(c);
      if (r && !r->diverged && reaches(*r) && (!best || r->mean_ms < best->mean_ms)) best = r;
    }
    return best;
  };
  auto entry = [&](const CellResult* r) {
    return r ? fmt(r->mean_ms) + " (kmax " + std::to_string(r->cell.kmax) + ", " + r->cell.products + ")"
             : std::string("not reached");
  };
  auto ratio = [&](const CellResult* fd, const CellResult* id) { return fmt(fd && id ? id->mean_ms / fd->mean_ms : NAN, 2); };
  const double residuals[] = {1e-2, 1e-3, 1e-4};
  const double cost_margins[] = {0.01, 0.1};
  o << "\n## Verdict at equal accuracy\n\n"
    << "The least mean ms per update with which each formulation reaches a target, over every kmax and both "
       "kinds of products (runs that diverged do not count); in brackets the variant. Targets: a mean "
       "residual ‖F‖ ≤ R, and a closed-loop cost within 1 % and 10 % of the lowest any run of that model "
       "reached. Beside them, the paper's comparison: equal kmax = 10 with difference products.\n\n"
    << "| run | derivatives | target | FD ms | ID ms | ID/FD |\n|---|---|---|---|---|---|\n";
  for (const std::string& run : runs) {
    double lowest = NAN;
    for (const Cell& c : cells) {
      const CellResult* r = c.model == run ? find(c) : nullptr;
      if (r && !r->diverged && !(r->closed_loop_cost >= lowest)) lowest = r->closed_loop_cost;
    }
    for (const std::string& mode : modes) {
      auto row = [&](const std::string& target, const CellResult* fd, const CellResult* id) {
        o << "| " << run << " | " << mode << " | " << target << " | " << entry(fd) << " | " << entry(id) << " | "
          << ratio(fd, id) << " |\n";
      };
      const CellResult *fd10 = cell_of(run, mode, "fd", "difference", 10), *id10 = cell_of(run, mode, "id", "difference", 10);
      if (fd10 || id10) {
        o << "| " << run << " | " << mode << " | equal kmax = 10, difference | "
          << (fd10 ? fmt(fd10->mean_ms) + (fd10->diverged ? "*" : "") : "–") << " | "
          << (id10 ? fmt(id10->mean_ms) + (id10->diverged ? "*" : "") : "–") << " | " << ratio(fd10, id10) << " |\n";
      }
      for (double R : residuals) {
        auto reaches = [R](const CellResult& r) { return r.mean_residual <= R; };
        row("‖F‖ ≤ " + fmt(R), fastest(run, mode, "fd", reaches), fastest(run, mode, "id", reaches));
      }
      for (double m : cost_margins) {
        const double bound = lowest * (1 + m);
        auto reaches = [bound](const CellResult& r) { return r.closed_loop_cost <= bound; };
        row("cost ≤ " + fmt(bound, 4) + " (+" + fmt(100 * m) + " %)", fastest(run, mode, "fd", reaches),
            fastest(run, mode, "id", reaches));
      }
    }
  }
  return o.str();
}

std::string markdown(const PaperTables& tables, const std::vector<Cell>& cells,
                     const std::map<std::string, CellResult>& done, const SweepOptions& opt) {
  if (opt.tables == kWorkPrecisionTable) return work_precision_markdown(opt, cells, done);
  if (opt.tables == kTrackingTable) return tracking_markdown(opt, cells, done);
  if (opt.tables == kArmsTable) return arms_markdown(opt, cells, done);
  auto find = [&](const Cell& c) -> const CellResult* {
    const auto it = done.find(c.key());
    return it == done.end() ? nullptr : &it->second;
  };
  // mode: a solver variant (derivatives, shooting) as Cell::variant labels it
  auto cell = [&](const std::string& table, const std::string& f, const std::string& mode, int n, int N, int kmax) {
    // the grid's cell (with its settings key), or an unkeyed one that finds nothing
    for (const Cell& c : cells) {
      if (c.table == table && c.formulation == f && c.variant() == mode && c.n == n && c.N == N && c.kmax == kmax) {
        return c;
      }
    }
    return Cell{table, paper_cell(tables, table, n, N, kmax).model, f, mode, "", n, N, kmax, "", false};
  };
  // ours (paper) for the ID/FD ratio of one grid point
  auto ratio = [&](const std::string& table, const std::string& mode, int n, int N, int kmax) {
    const Cell cf = cell(table, "fd", mode, n, N, kmax), ci = cell(table, "id", mode, n, N, kmax);
    const CellResult *rf = find(cf), *ri = find(ci);
    return fmt(rf && ri ? ri->mean_ms / rf->mean_ms : NAN, 2) + " (" +
           fmt(paper_figure(tables, ci).ms / paper_figure(tables, cf).ms, 2) + ")";
  };
  std::ostringstream o;
  o << "# idmpc sweep: mean ms per control update, ours (paper)\n\n"
    << "Closed-loop swing-up, " << opt.duration << " s simulated, MuJoCo plant. "
    << "`*` diverged (time averaged until divergence), `†` ID needed the fallback Q_a "
    << "(the paper's rule). The paper's figures are from " << tables.machine
    << ": compare ratios, not absolute times. " << stages_note(opt) << "\n";
  const std::vector<std::string> modes = variants(cells);
  for (const std::string& mode : modes) {
    if (opt.tables != "3") {
      const std::vector<int> Ns = axis(tables, "12", [](const PaperCell& p) { return p.N; });
      const std::vector<int> kmaxs = axis(tables, "12", [](const PaperCell& p) { return p.kmax; });
      const int n = axis(tables, "12", [](const PaperCell& p) { return p.n; }).front();
      std::string head = "\n\n|";
      for (int N : Ns) head += " | N=" + std::to_string(N);
      head += " |\n|---";
      for (size_t k = 0; k < Ns.size(); ++k) head += "|---";
      head += "|\n";
      const std::string model = paper_cell(tables, "12", n, Ns.front(), kmaxs.front()).model;
      for (const char* f : {"fd", "id"}) {
        o << "\n## Table " << (std::string(f) == "fd" ? "1: C/GMRES (FD)" : "2: C/GMRES (ID)") << ", "
          << model << ", derivatives: " << mode << head;
        for (int kmax : kmaxs) {
          o << "| kmax=" << kmax;
          for (int N : Ns) o << " | " << md_cell(tables, find(cell("12", f, mode, n, N, kmax)));
          o << " |\n";
        }
      }
      o << "\n## Ratio ID/FD, " << model << ", derivatives: " << mode << ", ours (paper)" << head;
      for (int kmax : kmaxs) {
        o << "| kmax=" << kmax;
        for (int N : Ns) o << " | " << ratio("12", mode, n, N, kmax);
        o << " |\n";
      }
    }
    if (opt.tables != "12") {
      const std::vector<int> ns = axis(tables, "3", [](const PaperCell& p) { return p.n; });
      const int N = axis(tables, "3", [](const PaperCell& p) { return p.N; }).front();
      const int kmax = axis(tables, "3", [](const PaperCell& p) { return p.kmax; }).front();
      o << "\n## Table 3: N = " << N << ", kmax = " << kmax << ", derivatives: " << mode << "\n\n|";
      for (int n : ns) o << " | n=" << n;
      o << " |\n|---";
      for (size_t k = 0; k < ns.size(); ++k) o << "|---";
      o << "|\n";
      for (const char* f : {"fd", "id"}) {
        o << "| C/GMRES (" << (std::string(f) == "fd" ? "FD" : "ID") << ")";
        for (int n : ns) o << " | " << md_cell(tables, find(cell("3", f, mode, n, N, kmax)));
        o << " |\n";
      }
      o << "| ratio ID/FD";
      for (int n : ns) o << " | " << ratio("3", mode, n, N, kmax);
      o << " |\n";
    }
  }
  if (modes.size() > 1) {
    // best with best: each formulation's fastest variant that did not diverge (the ID fallback
    // Q_a counts as the paper's rule allows it)
    auto best = [&](const std::string& table, const char* f, int n, int N, int kmax) {
      const CellResult* found = nullptr;
      for (const std::string& mode : modes) {
        const CellResult* r = find(cell(table, f, mode, n, N, kmax));
        if (r && !r->diverged && (!found || r->mean_ms < found->mean_ms)) found = r;
      }
      return found;
    };
    auto best_cell = [&](const std::string& table, int n, int N, int kmax) {
      const CellResult *fd = best(table, "fd", n, N, kmax), *id = best(table, "id", n, N, kmax);
      if (!fd && !id) return std::string("both diverged in every variant");
      if (!fd || !id) return std::string(fd ? "ID diverged in every variant" : "FD diverged in every variant");
      return fmt(id->mean_ms / fd->mean_ms, 2) + " (" + id->cell.variant() + " / " + fd->cell.variant() + ")";
    };
    o << "\n## Best with best: ID/FD of each formulation's fastest variant that did not diverge\n\n"
      << "Over the variants above; in brackets the ID and the FD variant. The paper's arithmetic is "
      << (opt.simd_stages ? "matrix mode, single shooting, stage by stage: `sweep --no-simd-stages`.\n"
                          : "the matrix-mode, single-shooting ratio above.\n");
    if (opt.tables != "3") {
      const std::vector<int> Ns = axis(tables, "12", [](const PaperCell& p) { return p.N; });
      const std::vector<int> kmaxs = axis(tables, "12", [](const PaperCell& p) { return p.kmax; });
      const int n = axis(tables, "12", [](const PaperCell& p) { return p.n; }).front();
      o << "\n| " << paper_cell(tables, "12", n, Ns.front(), kmaxs.front()).model;
      for (int N : Ns) o << " | N=" << N;
      o << " |\n|---";
      for (size_t k = 0; k < Ns.size(); ++k) o << "|---";
      o << "|\n";
      for (int kmax : kmaxs) {
        o << "| kmax=" << kmax;
        for (int N : Ns) o << " | " << best_cell("12", n, N, kmax);
        o << " |\n";
      }
    }
    if (opt.tables != "12") {
      const std::vector<int> ns = axis(tables, "3", [](const PaperCell& p) { return p.n; });
      const int N = axis(tables, "3", [](const PaperCell& p) { return p.N; }).front();
      const int kmax = axis(tables, "3", [](const PaperCell& p) { return p.kmax; }).front();
      o << "\n| Table 3";
      for (int n : ns) o << " | n=" << n;
      o << " |\n|---";
      for (size_t k = 0; k < ns.size(); ++k) o << "|---";
      o << "|\n| best ID / best FD";
      for (int n : ns) o << " | " << best_cell("3", n, N, kmax);
      o << " |\n";
    }
  }
  return o.str();
}

// the tables of the grid, with the latency table when the latency axis has more than none
std::string markdown_with_latency(const PaperTables& tables, const std::vector<Cell>& cells,
                                  const std::map<std::string, CellResult>& done, const SweepOptions& opt) {
  const std::string tables_md = markdown(tables, cells, done, opt);
  if (opt.latency == std::vector<std::string>{"none"}) return tables_md;
  return tables_md + latency_markdown(opt, cells, done);
}

// the file name of a cell's --logs log in the output directory
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

// run_cell after a progress line's start: an error goes on a line of its own
CellResult run_cell_after_progress(const Task& base, const Cell& c, const SweepOptions& opt) {
  try {
    return run_cell(base, c, opt);
  } catch (...) {
    std::fputc('\n', stderr);
    throw;
  }
}

// the cell as the progress lines and errors name it
std::string cell_label(const Cell& c) {
  return c.model + " " + (c.formulation == "fd" ? "FD" : "ID") + " " + c.variant() +
         (task_table(c.table) ? (c.offset_free ? ", offset-free on" : ", offset-free off") : "") +
         (c.latency == "none" ? "" : ", latency " + c.latency) + " N=" + std::to_string(c.N) +
         " kmax=" + std::to_string(c.kmax);
}

// the --latency axis: each value once, as parse_latency reads it back ("1.0" is "1")
std::vector<std::string> latency_axis(const std::vector<std::string>& values) {
  std::vector<std::string> axis;
  for (const std::string& l : values) {
    const std::string value = to_string(parse_latency(l));
    if (std::find(axis.begin(), axis.end(), value) != axis.end()) {
      throw std::invalid_argument("--latency lists '" + value + "' twice");
    }
    axis.push_back(value);
  }
  return axis;
}

// a sweep of the chosen options: the grid, each cell keyed, and what its cells run on
struct Sweep {
  SweepOptions opt;
  PaperTables tables;
  Task base;
  std::vector<Cell> cells;
  std::string csv, md;  // the tables' files
};

Sweep sweep_of(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  if (!(opt.duration > 0)) throw std::invalid_argument("--duration must be positive");
  Sweep s{opt, load_paper_tables(), {}, {}, "", ""};
  s.base = load_task(s.tables.task);
  s.cells = grid(opt, s.tables, s.base);
  std::set<std::string> ids;
  for (const Cell& c : s.cells) {
    if (!fs::exists(cell_file(opt, c))) {
      throw std::invalid_argument("'" + cell_file(opt, c) + "' not found (see --models)");
    }
    if (!ids.insert(cell_id(c.key())).second) {
      throw std::logic_error("two cells of the sweep have the ID " + cell_id(c.key()));
    }
  }
  const std::string stem = opt.out_dir + (task_table(opt.tables)                ? "/" + opt.tables
                                          : opt.tables == kWorkPrecisionTable ? std::string("/work_precision")
                                                                               : std::string("/sweep"));
  s.csv = stem + ".csv";
  s.md = stem + ".md";
  return s;
}

// a cell's settings are checked before any file is made (e.g. a --duration of no step)
void check_cell(const Sweep& s, const Cell& c) {
  try {
    const mj::TaskRun check(cell_task(s.base, c, s.opt));
  } catch (const std::exception& e) {
    throw std::invalid_argument("cell " + cell_label(c) + " cannot run: " + e.what());
  }
}

void write_csv(const Sweep& s, const std::map<std::string, CellResult>& done) {
  AtomicFile f(s.csv);
  f.stream() << csv_header() << '\n';
  for (const Cell& c : s.cells) {
    const auto it = done.find(c.key());
    if (it != done.end()) f.stream() << csv_row(s.tables, it->second) << '\n';
  }
  f.commit();
}

void write_markdown(const Sweep& s, const std::map<std::string, CellResult>& done) {
  AtomicFile f(s.md);
  f.stream() << markdown_with_latency(s.tables, s.cells, done, s.opt);
  f.commit();
}

// the outcome of a cell as its progress line says it
std::string outcome(const CellResult& r) {
  std::string what = "ok";
  if (r.diverged) {
    what = "diverged at " + fmt(r.diverged_at) + " s";
  } else if (task_table(r.cell.table)) {
    what = r.reached ? "reached the target" : "did not reach the target";
  }
  char ms[32];
  std::snprintf(ms, sizeof ms, "%.4g", r.mean_ms);
  return std::string(ms) + " ms per update, " + what;
}

// the sweep, one cell after the other, into sweep.csv and sweep.md
void run_serial(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  const Sweep s = sweep_of(opt);
  for (const Cell& c : s.cells) check_cell(s, c);
  fs::create_directories(opt.out_dir);
  // one sweep at a time in a directory: the lock goes with the process, however it ends
  const OutputDirectoryLock lock(opt.out_dir, OutputDirectoryLock::Mode::exclusive);
  // the temporaries of a sweep killed before it could remove them (of the tables and the logs);
  // the directory is locked, so no other sweep is writing there
  static const std::regex temporaries(R"(\.?(?:(?:sweep|arms|tracking|work_precision)\.(?:csv|md)|log_.*)\.tmp\.([0-9]+)\.[0-9]+)");
  remove_stale_temporaries(opt.out_dir, temporaries);
  std::map<std::string, CellResult> done = read_finished(s.csv, s.cells);

  // rewrite the finished cells cleanly, then append each new cell as soon as it ends
  write_csv(s, done);
  // each finished cell is one whole row, synced before the next cell starts; a row that cannot
  // be written (a full disk, a file size limit) ends the sweep with the rows before it kept
  AppendFile append(s.csv);
  int index = 0;
  for (const Cell& c : s.cells) {
    ++index;
    std::fprintf(stderr, "[%d/%zu] %s: ", index, s.cells.size(), cell_label(c).c_str());
    if (done.count(c.key())) {
      std::fprintf(stderr, "done earlier\n");
      continue;
    }
    const CellResult r = run_cell_after_progress(s.base, c, opt);
    std::fprintf(stderr, "%s\n", outcome(r).c_str());
    append.append(csv_row(s.tables, r) + "\n");
    done[c.key()] = r;
    write_markdown(s, done);
  }
  write_markdown(s, done);
  std::cout << markdown_with_latency(s.tables, s.cells, done, opt) << "\nwritten: " << s.md << ", " << s.csv << "\n";
}

// `text` matched literally in a std::regex
std::string regex_escaped(const std::string& text) {
  static const std::regex special(R"([.^$|()\[\]{}*+?\\])");
  return std::regex_replace(text, special, R"(\$&)");
}

// the cell a run names by its ID
const Cell& cell_named(const Sweep& s, const std::string& id) {
  for (const Cell& c : s.cells) {
    if (cell_id(c.key()) == id) return c;
  }
  throw std::invalid_argument("--cell '" + abbreviate(id) + "': no cell of this sweep has that ID (the IDs depend on "
                              "every option; list them with the same options and --list-cells)");
}

// --list-cells: each cell's ID and what it runs, one line each, tab-separated
void list_cells(const SweepOptions& opt) {
  const Sweep s = sweep_of(opt);
  for (const Cell& c : s.cells) check_cell(s, c);
  for (const Cell& c : s.cells) std::cout << cell_id(c.key()) << "\ttable " << c.table << ": " << cell_label(c) << '\n';
}

// the record of a cell, if a run wrote it
std::optional<CellResult> read_record(const Sweep& s, const Cell& c) {
  const std::string path = cell_record_path(s.opt.out_dir, cell_id(c.key()));
  if (!std::filesystem::exists(path)) return std::nullopt;
  const std::map<std::string, CellResult> records = read_finished(path, s.cells);
  const auto it = records.find(c.key());
  if (it == records.end()) return std::nullopt;
  return it->second;
}

// --cell ID: that cell alone, into its own record; cells of one sweep run side by side
void run_one_cell(const SweepOptions& opt, const std::string& id) {
  namespace fs = std::filesystem;
  const Sweep s = sweep_of(opt);
  const Cell& c = cell_named(s, id);
  check_cell(s, c);
  const std::string record = cell_record_path(opt.out_dir, id);
  // the lock first: a cell refused beside a serial sweep or a merge makes nothing
  fs::create_directories(opt.out_dir);
  const OutputDirectoryLock lock(opt.out_dir, OutputDirectoryLock::Mode::shared);
  const std::string progress = "[cell " + id + "] " + cell_label(c) + ": ";
  if (read_record(s, c)) {
    std::fprintf(stderr, "%sdone earlier\n", progress.c_str());
    return;
  }
  fs::create_directories(fs::path(record).parent_path());
  // the temporaries of this cell's record and log that a killed run of it left (other cells may
  // be writing theirs beside them)
  remove_stale_temporaries(fs::path(record).parent_path().string(),
                           std::regex("\\." + id + "\\.csv\\.tmp\\.([0-9]+)\\.[0-9]+"));
  if (opt.logs) remove_stale_temporaries(opt.out_dir, std::regex(regex_escaped("." + log_name(c)) + R"(\.tmp\.([0-9]+)\.[0-9]+)"));
  AtomicFile f(record);  // an unwritable directory fails before the run
  // the progress line once nothing but the run can fail: an error before it has a line of its own
  std::fprintf(stderr, "%s", progress.c_str());
  const CellResult r = run_cell_after_progress(s.base, c, opt);
  f.stream() << csv_header() << '\n' << csv_row(s.tables, r) << '\n';
  f.commit();
  std::fprintf(stderr, "%s\n", outcome(r).c_str());
}

// --merge: the tables of the serial sweep, from the cells' records; every cell must have one
void merge(const SweepOptions& opt) {
  const Sweep s = sweep_of(opt);
  // a merge does not run beside cells of this host (they would be reported missing) or a sweep
  std::optional<OutputDirectoryLock> lock;
  if (std::filesystem::is_directory(opt.out_dir)) lock.emplace(opt.out_dir, OutputDirectoryLock::Mode::exclusive);
  std::map<std::string, CellResult> done;
  std::vector<std::string> missing;
  for (const Cell& c : s.cells) {
    if (std::optional<CellResult> r = read_record(s, c)) {
      done[c.key()] = *r;
    } else {
      missing.push_back(cell_id(c.key()));
    }
  }
  if (!missing.empty()) {
    std::string ids;
    for (const std::string& id : missing) ids += (ids.empty() ? "" : " ") + id;
    throw std::invalid_argument(std::to_string(missing.size()) + " of " + std::to_string(s.cells.size()) +
                                " cells have no record in '" + opt.out_dir + "/cells' (run them with --cell ID): " +
                                ids);
  }
  // the temporaries killed runs left: of the tables, and of the records of cells that ran again
  static const std::regex table_temporaries(R"(\.(?:sweep|arms|tracking|work_precision)\.(?:csv|md)\.tmp\.([0-9]+)\.[0-9]+)");
  static const std::regex record_temporaries(R"(\.[0-9a-f]{16}\.csv\.tmp\.([0-9]+)\.[0-9]+)");
  static const std::regex log_temporaries(R"(\.log_.*\.tmp\.([0-9]+)\.[0-9]+)");
  remove_stale_temporaries(opt.out_dir, table_temporaries);
  remove_stale_temporaries(opt.out_dir, log_temporaries);
  remove_stale_temporaries(opt.out_dir + "/cells", record_temporaries);
  read_finished(s.csv, s.cells);  // a table of another sweep is refused, never overwritten
  write_csv(s, done);
  write_markdown(s, done);
  std::cout << markdown_with_latency(s.tables, s.cells, done, opt) << "\nwritten: " << s.md << ", " << s.csv << "\n";
}

}  // namespace

void register_sweep(CLI::App& app) {
  auto opt = std::make_shared<SweepOptions>();
  CLI::App* sub = app.add_subcommand("sweep", "The paper's grids closed-loop (Tables 1-3), resumable");
  sub->add_option("--out", opt->out_dir, "output directory (sweep.csv and sweep.md; arms: arms.csv and arms.md)")
      ->capture_default_str()
      ->check(non_empty_path());
  sub->add_option("--models", opt->models_dir,
                  "directory with the models of mjcf/paper_tables.json (and arms.json, the default --arms-tasks); "
                  "default: mjcf/ of the data directory");
  add_data_dir_option(*sub);
  CLI::Option* tables =
      sub->add_option("--tables", opt->tables,
                      "12 (arm4 N x kmax), 3 (n = 8..32), all, arms (each task of --arms-tasks under FD and ID, "
                      "written to arms.csv and arms.md), tracking (each task of --arms-tasks, by default "
                      "mjcf/tracking.json, with its tracking error, written to tracking.csv and tracking.md) or "
                      "work-precision (mjcf/work_precision.json: time per update against the residual and the "
                      "closed-loop cost over kmax, written to work_precision.csv and work_precision.md)")
          ->capture_default_str();
  CLI::Option* arms_tasks =
      sub->add_option("--arms-tasks", opt->arms_tasks,
                      "the tasks of --tables arms or tracking (arms implied when --tables is not given): a JSON "
                      "file {\"description\": ..., \"tasks\": [task files, relative to it]} like mjcf/arms.json, "
                      "the default (arms.json or tracking.json of --models)")
          ->check(non_empty_path());
  sub->add_option("--offset-free", opt->offset_free,
                  "arms: offset-free tracking (the disturbance observer) as each task sets it (task), on, off, or "
                  "both: every task with it on and off, side by side")
      ->capture_default_str();
  sub->add_option("--derivatives", opt->derivatives, "matrix, adjoint or both")->capture_default_str();
  sub->add_option("--shooting", opt->shooting, "single, multiple or both (docs/multiple_shooting.md)")->capture_default_str();
  sub->add_option("--solver", opt->solver,
                  "cgmres (the paper's), riccati (Gauss-Newton SQP, one real-time iteration per update) or both "
                  "(docs/solvers.md); the Riccati cells have one variant whatever --derivatives, --shooting and "
                  "--products say")
      ->capture_default_str();
  sub->add_option("--products", opt->products,
                  "difference (the paper's forward differences), exact (dual numbers) or both (docs/exact_products.md)")
      ->capture_default_str();
  CLI::Option* duration =
      sub->add_option("--duration", opt->duration, "simulated seconds per run (arms: default the task's)")
          ->capture_default_str();
  sub->add_option("--latency", opt->latency,
                  "compute latency of every run, one value or several (an axis, comma-separated): none (the "
                  "paper's timing), measured (each update's wall time) or a compute time in ms; the tables are "
                  "of the first value, a latency table compares them all")
      ->delimiter(',')
      ->check(latency_check())
      ->capture_default_str();
  sub->add_flag("--logs", opt->logs, "keep each run's CSV log in the output directory");
  sub->add_flag("!--no-simd-stages", opt->simd_stages,
                "every run evaluates its horizon stages one by one instead of in SIMD lanes: matrix mode is then "
                "the paper's arithmetic");
  // the sweep as independent cells, for a scheduler (GNU parallel, a SLURM job array)
  auto cell = std::make_shared<std::string>();
  CLI::Option* list = sub->add_flag("--list-cells",
                                    "print each cell's ID and what it runs, tab-separated, one line per cell, and "
                                    "run nothing");
  CLI::Option* one = sub->add_option("--cell", *cell,
                                     "run only the cell with this ID (see --list-cells) into its record, "
                                     "cells/ID.csv of --out; cells run side by side")
                         ->type_name("ID");
  CLI::Option* merged = sub->add_flag("--merge",
                                      "write the tables (sweep.csv and sweep.md) from the cells' records, as the "
                                      "serial sweep writes them; a cell without a record is an error naming it");
  list->excludes(one)->excludes(merged);
  one->excludes(merged);
  require_decimal_numbers(*sub);
  sub->callback([opt, duration, tables, arms_tasks, list, one, merged, cell] {
    opt->duration_given = duration->count() > 0;
    if (arms_tasks->count() > 0 && tables->count() == 0) opt->tables = kArmsTable;
    opt->latency = latency_axis(opt->latency);
    if (list->count() > 0) {
      list_cells(*opt);
    } else if (one->count() > 0) {
      run_one_cell(*opt, *cell);
    } else if (merged->count() > 0) {
      merge(*opt);
    } else {
      run_serial(*opt);
    }
  });
}

}  // namespace idmpc::app
