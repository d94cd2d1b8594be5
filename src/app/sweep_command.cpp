// idmpc sweep: the paper's closed-loop grids (Tables 1–3), resumable, with our figures beside
// the paper's.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "app/data_dir_option.hpp"
#include "app/number_options.hpp"
#include "app/output_paths.hpp"
#include "app/sweep_cells.hpp"
#include "app/sweep_grid.hpp"
#include "app/sweep_results.hpp"
#include "app/sweep_tables.hpp"
#include "app/swingup.hpp"
#include "idmpc/experiment/input_file.hpp"
#include "idmpc/mujoco/task_run.hpp"

namespace idmpc::app {
namespace {

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
