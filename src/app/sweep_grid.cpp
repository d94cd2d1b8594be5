#include "app/sweep_grid.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>

#include "app/output_paths.hpp"
#include "idmpc/experiment/data_dir.hpp"
#include "idmpc/experiment/input_file.hpp"
#include "idmpc/experiment/run_record.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc::app {
namespace {

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

// a file of the models directory (an absolute name stays as it is)
std::string in_models(const SweepOptions& opt, const std::string& file) {
  return opt.models_dir.empty() ? shipped_mjcf_path(file) : (std::filesystem::path(opt.models_dir) / file).string();
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
  } else if (opt.solver == "auto") {
    // a sweep's cells compare named solver families; "auto" chooses one per model (swingup)
    throw std::invalid_argument("--solver auto: a sweep names its solvers, cgmres, riccati or both");
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

}  // namespace

bool task_table(const std::string& table) { return table == kArmsTable || table == kTrackingTable; }

bool runs_task_file(const std::string& table, const std::string& model) {
  return task_table(table) ||
         (table == kWorkPrecisionTable && model.size() > 5 && model.compare(model.size() - 5, 5, ".json") == 0);
}

std::string arms_list(const SweepOptions& opt) {
  if (!opt.arms_tasks.empty()) return opt.arms_tasks;
  return in_models(opt, opt.tables == kTrackingTable ? "tracking.json" : "arms.json");
}

std::string cell_file(const SweepOptions& opt, const Cell& c) {
  if (!c.runs_task_file()) return in_models(opt, c.model);
  if (c.table == kWorkPrecisionTable) return in_models(opt, c.model);
  return (std::filesystem::path(arms_list(opt)).parent_path() / c.model).string();
}

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

std::string cell_label(const Cell& c) {
  return c.model + " " + (c.formulation == "fd" ? "FD" : "ID") + " " + c.variant() +
         (task_table(c.table) ? (c.offset_free ? ", offset-free on" : ", offset-free off") : "") +
         (c.latency == "none" ? "" : ", latency " + c.latency) + " N=" + std::to_string(c.N) +
         " kmax=" + std::to_string(c.kmax);
}

}  // namespace idmpc::app
