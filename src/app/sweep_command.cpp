// idmpc sweep: the paper's closed-loop grids (Tables 1–3), resumable, with our figures beside
// the paper's.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "app/swingup.hpp"

namespace idmpc::app {
namespace {

struct SweepOptions {
  std::string out_dir = "results/sweep";
  std::string models_dir = IDMPC_SOURCE_DIR "/mjcf";
  std::string tables = "all";        // 12, 3 or all
  std::string derivatives = "matrix";  // matrix, adjoint or both
  std::string shooting = "single";     // single, multiple or both
  double duration = 10.0;
  bool duration_given = false;  // arms: the task files' own durations unless --duration is given
  bool logs = false;
  bool simd_stages = true;  // false: --no-simd-stages, every run stage by stage (the paper's arithmetic)
};

// what the tables' matrix mode is, for the tables' headers
std::string stages_note(const SweepOptions& opt) {
  return opt.simd_stages ? "Matrix mode runs its stage derivatives in SIMD lanes (the default; `sweep --no-simd-stages` "
                           "runs every stage one by one, the paper's arithmetic)."
                         : "Every run evaluates its stages one by one (`--no-simd-stages`): matrix mode is the "
                           "paper's arithmetic.";
}

// the real-arm grid: the reach task of every arm in mjcf/arms.json, both formulations
constexpr const char* kArmsTable = "arms";
// a reach succeeds when it does not diverge and ends within this of its target (issue 9)
constexpr double kReachTolerance = 1e-3;

struct Cell {
  std::string table, model, formulation, derivatives, shooting;  // arms: model is the task file's name
  int n = 0, N = 0, kmax = 0;
  std::string settings;  // hash of everything else the cell runs with (the task as run)
  std::string key() const {
    return table + "|" + model + "|" + formulation + "|" + derivatives + "|" + shooting + "|" + std::to_string(N) +
           "|" + std::to_string(kmax) + "|" + settings;
  }
  // the solver variant, as the tables label it
  std::string variant() const { return derivatives + (shooting == "single" ? "" : ", " + shooting + " shooting"); }
};

// the hash of the task as the cell runs it, so that a resumed sweep never mixes settings
std::string settings_hash(Task task, const std::string& model) {
  task.model = model;  // as named in the grid, not where --models happens to put it
  task.source.clear();
  return text_hash(to_json(task).dump());
}

struct CellResult {
  Cell cell;
  double Qa = 0;
  bool diverged = false;
  double diverged_at = NAN, mean_ms = NAN, p95_ms = NAN, final_q_error = NAN, final_v_norm = NAN;
  long steps = 0, saturated_steps = 0;   // steps run; steps with a clamped torque
  double max_violation = NAN;            // of the OCP's torques over their bounds [N m]
  bool reached() const { return !diverged && final_q_error < kReachTolerance; }
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

// the paper's cells, in the file's order, for the chosen tables and derivative modes
// a file of the models directory (an absolute name stays as it is)
std::string in_models(const SweepOptions& opt, const std::string& file) {
  return (std::filesystem::path(opt.models_dir) / file).string();
}

// the task a cell runs: the paper's on the cell's model, or an arm's own task file
Task cell_task(const Task& base, const Cell& c, const SweepOptions& opt) {
  const bool arm = c.table == kArmsTable;
  Task task = arm ? load_task(in_models(opt, c.model)) : base;
  if (!arm) {
    task.model = in_models(opt, c.model);
    task.Qa = {0.0};  // the paper's rule: Q_a = 0 first, the fallback only after a divergence
  }
  task.formulation = c.formulation;
  task.derivatives = c.derivatives;
  task.shooting = c.shooting;
  task.N = c.N;
  task.kmax = c.kmax;
  if (!arm || opt.duration_given) task.duration = opt.duration;
  if (!opt.simd_stages) task.simd_stages = false;
  return task;
}

// the real arms' reach tasks (mjcf/arms.json), paths relative to the models directory
std::vector<std::string> arm_tasks(const SweepOptions& opt) {
  const std::string path = opt.models_dir + "/arms.json";
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("'" + path + "' cannot be read (the list of real-arm tasks; see --models)");
  try {
    return nlohmann::json::parse(in).at("tasks").get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument("'" + path + "': expected {\"tasks\": [task files]}, " + e.what());
  }
}

std::vector<Cell> grid_of(const SweepOptions& opt, const PaperTables& tables);

// the grid, each cell keyed by the settings it runs with
std::vector<Cell> grid(const SweepOptions& opt, const PaperTables& tables, const Task& base) {
  std::vector<Cell> cells = grid_of(opt, tables);
  for (Cell& c : cells) c.settings = settings_hash(cell_task(base, c, opt), c.model);
  return cells;
}

std::vector<Cell> grid_of(const SweepOptions& opt, const PaperTables& tables) {
  std::vector<std::string> modes, shootings;
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
  if (opt.tables != "12" && opt.tables != "3" && opt.tables != "all" && opt.tables != kArmsTable) {
    throw std::invalid_argument("--tables must be 12, 3, all or arms, got '" + opt.tables + "'");
  }
  std::vector<Cell> cells;
  if (opt.tables == kArmsTable) {
    for (const auto& mode : modes) {
      for (const auto& shooting : shootings) {
        for (const std::string& file : arm_tasks(opt)) {
          const Task t = load_task(in_models(opt, file));
          for (const char* f : {"fd", "id"}) cells.push_back({kArmsTable, file, f, mode, shooting, 0, t.N, t.kmax, ""});
        }
      }
    }
    return cells;
  }
  for (const auto& mode : modes) {
    for (const auto& shooting : shootings) {
      for (const PaperCell& p : tables.cells) {
        if (opt.tables != "all" && p.table != opt.tables) continue;
        cells.push_back({p.table, p.model, p.formulation, mode, shooting, p.n, p.N, p.kmax, ""});
      }
    }
  }
  return cells;
}

const char* kCsvHeader =
    "table,model,n,formulation,derivatives,shooting,N,kmax,Qa,diverged,diverged_at,mean_update_ms,"
    "p95_update_ms,final_q_error,final_v_norm,paper_ms,paper_note,steps,saturated_steps,"
    "max_constraint_violation,settings";

std::string csv_row(const PaperTables& tables, const CellResult& r) {
  const PaperFigure p = paper_figure(tables, r.cell);
  std::ostringstream o;
  o << std::setprecision(8) << r.cell.table << ',' << r.cell.model << ',' << r.cell.n << ','
    << r.cell.formulation << ',' << r.cell.derivatives << ',' << r.cell.shooting << ',' << r.cell.N << ',' << r.cell.kmax << ','
    << r.Qa << ',' << (r.diverged ? 1 : 0) << ',' << r.diverged_at << ',' << r.mean_ms << ','
    << r.p95_ms << ',' << r.final_q_error << ',' << r.final_v_norm << ',' << p.ms << ',' << p.note << ','
    << r.steps << ',' << r.saturated_steps << ',' << r.max_violation << ',' << r.cell.settings;
  return o.str();
}

// finished cells of an earlier, possibly interrupted, sweep of this grid (CRLF line ends
// accepted; a torn last line, as an interrupted append leaves it, is dropped). A file of
// another format or with cells of other settings is refused, never overwritten.
std::map<std::string, CellResult> read_finished(const std::string& path, const std::vector<Cell>& cells) {
  std::map<std::string, CellResult> done;
  std::ifstream in(path);
  std::string line;
  auto next = [&] {
    if (!std::getline(in, line)) return false;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  };
  if (!next()) return done;
  const std::string refuse = "'" + path + "' holds ";
  const std::string what = "; use another --out or move it away";
  if (line != kCsvHeader) throw std::invalid_argument(refuse + "something other than this idmpc's sweep results" + what);
  std::set<std::string> keys;
  for (const Cell& c : cells) keys.insert(c.key());
  while (next()) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) f.push_back(x);
    if (f.size() != 21) continue;
    try {
      CellResult r;
      r.cell = {f[0], f[1], f[3], f[4], f[5], std::stoi(f[2]), std::stoi(f[6]), std::stoi(f[7]), f[20]};
      r.Qa = std::stod(f[8]);
      r.diverged = f[9] == "1";
      r.diverged_at = std::stod(f[10]);
      r.mean_ms = std::stod(f[11]);
      r.p95_ms = std::stod(f[12]);
      r.final_q_error = std::stod(f[13]);
      r.final_v_norm = std::stod(f[14]);
      r.steps = std::stol(f[17]);
      r.saturated_steps = std::stol(f[18]);
      r.max_violation = std::stod(f[19]);
      if (!keys.count(r.cell.key())) {
        throw std::invalid_argument(refuse + "results of a sweep with other settings (" + r.cell.model + " " +
                                    r.cell.formulation + " " + r.cell.variant() + ": other duration, weights or "
                                    "task)" + what);
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

// the real-arm tables: time per update with ID/FD, then each run's outcome
std::string arms_markdown(const SweepOptions& opt, const std::vector<Cell>& cells,
                          const std::map<std::string, CellResult>& done) {
  auto find = [&](const Cell& c) -> const CellResult* {
    const auto it = done.find(c.key());
    return it == done.end() ? nullptr : &it->second;
  };
  const std::vector<std::string> modes = variants(cells);
  std::vector<std::string> tasks;
  for (const Cell& c : cells) {
    if (std::find(tasks.begin(), tasks.end(), c.model) == tasks.end()) tasks.push_back(c.model);
  }
  auto cell_of = [&](const std::string& task, const std::string& f, const std::string& mode) -> const CellResult* {
    for (const Cell& c : cells) {
      if (c.model == task && c.formulation == f && c.variant() == mode) return find(c);
    }
    return nullptr;
  };
  auto ms = [](const CellResult* r) {
    return r ? fmt(r->mean_ms) + (r->diverged ? "*" : (r->reached() ? "" : "°")) : std::string("–");
  };
  std::ostringstream o;
  o << "# idmpc sweep: the real arms\n\n"
    << "Each arm's reach task (`mjcf/arms.json`), torque limits from its actuators active in the OCP "
    << "and at the plant. Mean ms per control update; `*` diverged (time averaged until then), "
    << "`°` did not end within " << kReachTolerance << " rad of the target. The last column compares "
    << "each formulation's fastest variant that reached the target. " << stages_note(opt) << "\n\n| task | n |";
  for (const auto& mode : modes) o << " FD " << mode << " | ID " << mode << " | ID/FD |";
  o << " best ID / best FD |\n|---|---|";
  for (size_t k = 0; k < modes.size(); ++k) o << "---|---|---|";
  o << "---|\n";
  // a formulation's fastest variant that reached the target
  auto best = [&](const std::string& task, const char* f) {
    double ms = NAN;
    for (const auto& mode : modes) {
      const CellResult* r = cell_of(task, f, mode);
      if (r && r->reached() && !(r->mean_ms >= ms)) ms = r->mean_ms;
    }
    return ms;
  };
  for (const auto& task : tasks) {
    int n = 0;
    for (const auto& mode : modes) {
      for (const char* f : {"fd", "id"}) {
        if (const CellResult* r = cell_of(task, f, mode)) n = r->cell.n;
      }
    }
    o << "| " << task << " | " << (n > 0 ? std::to_string(n) : "–") << " |";
    for (const auto& mode : modes) {
      const CellResult *fd = cell_of(task, "fd", mode), *id = cell_of(task, "id", mode);
      o << ' ' << ms(fd) << " | " << ms(id) << " | " << fmt(fd && id ? id->mean_ms / fd->mean_ms : NAN, 2) << " |";
    }
    o << ' ' << fmt(best(task, "id") / best(task, "fd"), 2) << " |\n";
  }
  o << "\n## Outcomes\n\n| task | variant | reached | final max abs(q - qref) [rad] | steps with a clamped "
       "torque | largest excess of the OCP's torques over their bounds [N m] |\n|---|---|---|---|---|---|\n";
  for (const auto& task : tasks) {
    for (const auto& mode : modes) {
      for (const char* f : {"fd", "id"}) {
        const CellResult* r = cell_of(task, f, mode);
        if (!r) continue;
        o << "| " << task << " | " << (std::string(f) == "fd" ? "FD " : "ID ") << mode << " | "
          << (r->diverged ? "diverged at " + fmt(r->diverged_at) + " s" : (r->reached() ? "yes" : "no")) << " | "
          << fmt(r->final_q_error) << " | " << r->saturated_steps << " of " << r->steps << " | "
          << fmt(r->max_violation) << " |\n";
      }
    }
  }
  return o.str();
}

std::string markdown(const PaperTables& tables, const std::vector<Cell>& cells,
                     const std::map<std::string, CellResult>& done, const SweepOptions& opt) {
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
    return Cell{table, paper_cell(tables, table, n, N, kmax).model, f, mode, "", n, N, kmax, ""};
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

CellResult run_cell(const Task& base, const Cell& c, const SweepOptions& opt) {
  const Task task = cell_task(base, c, opt);
  std::string log;
  if (opt.logs) {
    log = opt.out_dir + "/log_" + c.table + "_" + c.model.substr(0, c.model.rfind('.')) + "_" + c.formulation + "_" +
          c.derivatives + (c.shooting == "single" ? "" : "_" + c.shooting) + "_N" + std::to_string(c.N) + "_k" +
          std::to_string(c.kmax) + ".csv";
  }
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
  return r;
}

void run(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  if (!(opt.duration > 0)) throw std::invalid_argument("--duration must be positive");
  const PaperTables tables = load_paper_tables();
  const Task base = load_task(tables.task);
  const std::vector<Cell> cells = grid(opt, tables, base);
  for (const Cell& c : cells) {
    if (!fs::exists(in_models(opt, c.model))) {
      throw std::invalid_argument("'" + in_models(opt, c.model) + "' not found (see --models)");
    }
  }
  fs::create_directories(opt.out_dir);
  const std::string stem = opt.out_dir + (opt.tables == kArmsTable ? "/arms" : "/sweep");
  const std::string csv = stem + ".csv", md = stem + ".md";
  // one sweep at a time in a directory: the lock goes with the process, however it ends
  const int dir_fd = ::open(opt.out_dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0) throw std::runtime_error("cannot open --out '" + opt.out_dir + "': " + std::strerror(errno));
  struct Unlock {
    int fd;
    ~Unlock() { ::close(fd); }
  } unlock{dir_fd};
  if (::flock(dir_fd, LOCK_EX | LOCK_NB) != 0) {
    throw std::runtime_error("another sweep is writing into '" + opt.out_dir + "' (it is locked); wait for it or use another --out");
  }
  std::map<std::string, CellResult> done = read_finished(csv, cells);

  // rewrite the finished cells cleanly, then append each new cell as soon as it ends
  {
    AtomicFile f(csv);
    f.stream() << kCsvHeader << '\n';
    for (const Cell& c : cells) {
      const auto it = done.find(c.key());
      if (it != done.end()) f.stream() << csv_row(tables, it->second) << '\n';
    }
    f.commit();
  }
  std::ofstream append(csv, std::ios::app);
  int index = 0;
  for (const Cell& c : cells) {
    ++index;
    std::fprintf(stderr, "[%d/%zu] %s %s %s N=%d kmax=%d: ", index, cells.size(), c.model.c_str(),
                 c.formulation == "fd" ? "FD" : "ID", c.variant().c_str(), c.N, c.kmax);
    if (done.count(c.key())) {
      std::fprintf(stderr, "done earlier\n");
      continue;
    }
    const CellResult r = run_cell(base, c, opt);
    std::fprintf(stderr, "%.4g ms per update, %s\n", r.mean_ms,
                 r.diverged ? ("diverged at " + fmt(r.diverged_at) + " s").c_str() : "ok");
    append << csv_row(tables, r) << '\n' << std::flush;
    done[c.key()] = r;
    AtomicFile f(md);
    f.stream() << markdown(tables, cells, done, opt);
    f.commit();
  }
  AtomicFile f(md);
  f.stream() << markdown(tables, cells, done, opt);
  f.commit();
  std::cout << markdown(tables, cells, done, opt) << "\nwritten: " << md << ", " << csv << "\n";
}

}  // namespace

void register_sweep(CLI::App& app) {
  auto opt = std::make_shared<SweepOptions>();
  CLI::App* sub = app.add_subcommand("sweep", "The paper's grids closed-loop (Tables 1-3), resumable");
  sub->add_option("--out", opt->out_dir, "output directory (sweep.csv, sweep.md)")->capture_default_str();
  sub->add_option("--models", opt->models_dir, "directory with the models of mjcf/paper_tables.json")
      ->capture_default_str();
  sub->add_option("--tables", opt->tables,
                  "12 (arm4 N x kmax), 3 (n = 8..32), all, or arms (the real arms' reach tasks of "
                  "mjcf/arms.json, written to arms.csv and arms.md)")
      ->capture_default_str();
  sub->add_option("--derivatives", opt->derivatives, "matrix, adjoint or both")->capture_default_str();
  sub->add_option("--shooting", opt->shooting, "single, multiple or both (DESIGN §9)")->capture_default_str();
  CLI::Option* duration =
      sub->add_option("--duration", opt->duration, "simulated seconds per run (arms: default the task's)")
          ->capture_default_str();
  sub->add_flag("--logs", opt->logs, "keep each run's CSV log in the output directory");
  sub->add_flag("!--no-simd-stages", opt->simd_stages,
                "every run evaluates its horizon stages one by one instead of in SIMD lanes: matrix mode is then "
                "the paper's arithmetic");
  sub->callback([opt, duration] {
    opt->duration_given = duration->count() > 0;
    run(*opt);
  });
}

}  // namespace idmpc::app
