// idmpc sweep: the paper's closed-loop grids (Tables 1–3), resumable, with our figures beside
// the paper's.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

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
  double duration = 10.0;
  bool logs = false;
};

struct Cell {
  std::string table, model, formulation, derivatives;
  int n = 0, N = 0, kmax = 0;
  std::string key() const {
    return table + "|" + model + "|" + formulation + "|" + derivatives + "|" + std::to_string(N) +
           "|" + std::to_string(kmax);
  }
};

struct CellResult {
  Cell cell;
  double Qa = 0;
  bool diverged = false;
  double diverged_at = NAN, mean_ms = NAN, p95_ms = NAN, final_q_error = NAN, final_v_norm = NAN;
};

// the paper's ms per update (Intel Core i5 2.0 GHz, Pinocchio); * FD diverged, † ID needed Qa
struct PaperFigure {
  double ms;
  const char* note;
};
PaperFigure paper_figure(const Cell& c) {
  static const std::map<std::string, PaperFigure> table = {
      {"fd|3|10", {0.37, "*"}}, {"fd|3|15", {0.55, "*"}}, {"fd|3|25", {0.94, "*"}}, {"fd|3|50", {1.8, "*"}},
      {"fd|5|10", {0.48, "*"}}, {"fd|5|15", {0.75, "*"}}, {"fd|5|25", {1.2, "*"}}, {"fd|5|50", {2.4, "*"}},
      {"fd|10|10", {8.1, ""}}, {"fd|10|15", {1.2, ""}}, {"fd|10|25", {2.0, ""}}, {"fd|10|50", {4.0, ""}},
      {"id|3|10", {0.22, "†"}}, {"id|3|15", {0.33, "†"}}, {"id|3|25", {0.58, "†"}}, {"id|3|50", {1.1, "†"}},
      {"id|5|10", {0.29, ""}}, {"id|5|15", {0.45, ""}}, {"id|5|25", {0.81, ""}}, {"id|5|50", {1.5, "†"}},
      {"id|10|10", {0.47, ""}}, {"id|10|15", {0.73, ""}}, {"id|10|25", {1.3, ""}}, {"id|10|50", {2.5, ""}},
      {"fd|n8", {4.5, ""}}, {"fd|n16", {11, ""}}, {"fd|n24", {20, ""}}, {"fd|n32", {32, ""}},
      {"id|n8", {2.6, ""}}, {"id|n16", {6.0, ""}}, {"id|n24", {10, ""}}, {"id|n32", {16, ""}}};
  const std::string key = c.table == "3" ? c.formulation + "|n" + std::to_string(c.n)
                                         : c.formulation + "|" + std::to_string(c.kmax) + "|" + std::to_string(c.N);
  const auto it = table.find(key);
  return it == table.end() ? PaperFigure{NAN, ""} : it->second;
}

std::vector<Cell> grid(const SweepOptions& opt) {
  std::vector<std::string> modes;
  if (opt.derivatives == "both") {
    modes = {"matrix", "adjoint"};
  } else {
    parse_derivative_mode(opt.derivatives);
    modes = {opt.derivatives};
  }
  if (opt.tables != "12" && opt.tables != "3" && opt.tables != "all") {
    throw std::invalid_argument("--tables must be 12, 3 or all, got '" + opt.tables + "'");
  }
  std::vector<Cell> cells;
  for (const auto& mode : modes) {
    if (opt.tables != "3") {
      for (int kmax : {3, 5, 10}) {
        for (int N : {10, 15, 25, 50}) {
          for (const char* f : {"fd", "id"}) cells.push_back({"12", "arm4.xml", f, mode, 4, N, kmax});
        }
      }
    }
    if (opt.tables != "12") {
      for (int n : {8, 16, 24, 32}) {
        for (const char* f : {"fd", "id"}) {
          cells.push_back({"3", "chain" + std::to_string(n) + ".xml", f, mode, n, 25, 10});
        }
      }
    }
  }
  return cells;
}

const char* kCsvHeader =
    "table,model,n,formulation,derivatives,N,kmax,Qa,diverged,diverged_at,mean_update_ms,"
    "p95_update_ms,final_q_error,final_v_norm,paper_ms,paper_note";

std::string csv_row(const CellResult& r) {
  const PaperFigure p = paper_figure(r.cell);
  std::ostringstream o;
  o << std::setprecision(8) << r.cell.table << ',' << r.cell.model << ',' << r.cell.n << ','
    << r.cell.formulation << ',' << r.cell.derivatives << ',' << r.cell.N << ',' << r.cell.kmax << ','
    << r.Qa << ',' << (r.diverged ? 1 : 0) << ',' << r.diverged_at << ',' << r.mean_ms << ','
    << r.p95_ms << ',' << r.final_q_error << ',' << r.final_v_norm << ',' << p.ms << ',' << p.note;
  return o.str();
}

// finished cells of an earlier, possibly interrupted, sweep; malformed lines are dropped
std::map<std::string, CellResult> read_finished(const std::string& path) {
  std::map<std::string, CellResult> done;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line) || line != kCsvHeader) return done;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string x;
    while (std::getline(ss, x, ',')) f.push_back(x);
    if (f.size() < 14) continue;
    try {
      CellResult r;
      r.cell = {f[0], f[1], f[3], f[4], std::stoi(f[2]), std::stoi(f[5]), std::stoi(f[6])};
      r.Qa = std::stod(f[7]);
      r.diverged = f[8] == "1";
      r.diverged_at = std::stod(f[9]);
      r.mean_ms = std::stod(f[10]);
      r.p95_ms = std::stod(f[11]);
      r.final_q_error = std::stod(f[12]);
      r.final_v_norm = std::stod(f[13]);
      done[r.cell.key()] = r;
    } catch (const std::exception&) {
      continue;
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
std::string md_cell(const CellResult* r) {
  if (!r) return "–";
  const PaperFigure p = paper_figure(r->cell);
  std::string s = fmt(r->mean_ms) + (r->diverged ? "*" : "") + (r->Qa > 0 ? "†" : "");
  return s + " (" + fmt(p.ms) + p.note + ")";
}

std::string markdown(const std::vector<Cell>& cells, const std::map<std::string, CellResult>& done,
                     const SweepOptions& opt) {
  auto find = [&](const Cell& c) -> const CellResult* {
    const auto it = done.find(c.key());
    return it == done.end() ? nullptr : &it->second;
  };
  std::ostringstream o;
  o << "# idmpc sweep: mean ms per control update, ours (paper)\n\n"
    << "Closed-loop swing-up, " << opt.duration << " s simulated, MuJoCo plant. "
    << "`*` diverged (time averaged until divergence), `†` ID needed Q_a = 1e-4 I "
    << "(the paper's fallback). The paper's figures are from an Intel Core i5 2.0 GHz with "
    << "Pinocchio: compare ratios, not absolute times.\n";
  for (const std::string mode : {"matrix", "adjoint"}) {
    const bool any = std::any_of(cells.begin(), cells.end(), [&](const Cell& c) { return c.derivatives == mode; });
    if (!any) continue;
    if (opt.tables != "3") {
      for (const char* f : {"fd", "id"}) {
        o << "\n## Table " << (std::string(f) == "fd" ? "1: C/GMRES (FD)" : "2: C/GMRES (ID)")
          << ", arm4, derivatives: " << mode << "\n\n| | N=10 | N=15 | N=25 | N=50 |\n|---|---|---|---|---|\n";
        for (int kmax : {3, 5, 10}) {
          o << "| kmax=" << kmax;
          for (int N : {10, 15, 25, 50}) o << " | " << md_cell(find({"12", "arm4.xml", f, mode, 4, N, kmax}));
          o << " |\n";
        }
      }
      o << "\n## Ratio ID/FD, arm4, derivatives: " << mode << ", ours (paper)\n\n"
        << "| | N=10 | N=15 | N=25 | N=50 |\n|---|---|---|---|---|\n";
      for (int kmax : {3, 5, 10}) {
        o << "| kmax=" << kmax;
        for (int N : {10, 15, 25, 50}) {
          const Cell cf{"12", "arm4.xml", "fd", mode, 4, N, kmax}, ci{"12", "arm4.xml", "id", mode, 4, N, kmax};
          const CellResult *rf = find(cf), *ri = find(ci);
          const double ours = rf && ri ? ri->mean_ms / rf->mean_ms : NAN;
          o << " | " << fmt(ours, 2) << " (" << fmt(paper_figure(ci).ms / paper_figure(cf).ms, 2) << ")";
        }
        o << " |\n";
      }
    }
    if (opt.tables != "12") {
      o << "\n## Table 3: N = 25, kmax = 10, derivatives: " << mode
        << "\n\n| | n=8 | n=16 | n=24 | n=32 |\n|---|---|---|---|---|\n";
      for (const char* f : {"fd", "id"}) {
        o << "| C/GMRES (" << (std::string(f) == "fd" ? "FD" : "ID") << ")";
        for (int n : {8, 16, 24, 32}) {
          o << " | " << md_cell(find({"3", "chain" + std::to_string(n) + ".xml", f, mode, n, 25, 10}));
        }
        o << " |\n";
      }
      o << "| ratio ID/FD";
      for (int n : {8, 16, 24, 32}) {
        const Cell cf{"3", "chain" + std::to_string(n) + ".xml", "fd", mode, n, 25, 10};
        const Cell ci{"3", "chain" + std::to_string(n) + ".xml", "id", mode, n, 25, 10};
        const CellResult *rf = find(cf), *ri = find(ci);
        o << " | " << fmt(rf && ri ? ri->mean_ms / rf->mean_ms : NAN, 2) << " ("
          << fmt(paper_figure(ci).ms / paper_figure(cf).ms, 2) << ")";
      }
      o << " |\n";
    }
  }
  return o.str();
}

CellResult run_cell(const Cell& c, const SweepOptions& opt, double Qa) {
  SwingupOptions s;
  s.model = opt.models_dir + "/" + c.model;
  s.formulation = c.formulation;
  s.derivatives = c.derivatives;
  s.N = c.N;
  s.kmax = c.kmax;
  s.duration = opt.duration;
  s.Qa = {Qa};
  std::string log;
  if (opt.logs) {
    log = opt.out_dir + "/log_" + c.table + "_" + c.model.substr(0, c.model.size() - 4) + "_" +
          c.formulation + "_" + c.derivatives + "_N" + std::to_string(c.N) + "_k" + std::to_string(c.kmax) + ".csv";
  }
  const SwingupOutcome out = run_swingup(s, log);
  const auto& j = out.summary;
  CellResult r;
  r.cell = c;
  r.Qa = Qa;
  r.diverged = j["diverged"].get<bool>();
  r.diverged_at = r.diverged ? j["diverged_at"].get<double>() : NAN;
  r.mean_ms = j["mean_update_ms"].get<double>();
  r.p95_ms = j["p95_update_ms"].get<double>();
  r.final_q_error = j["final_q_error"].get<double>();
  r.final_v_norm = j["final_v_norm"].get<double>();
  return r;
}

void run(const SweepOptions& opt) {
  namespace fs = std::filesystem;
  if (!(opt.duration > 0)) throw std::invalid_argument("--duration must be positive");
  const std::vector<Cell> cells = grid(opt);
  for (const Cell& c : cells) {
    if (!fs::exists(opt.models_dir + "/" + c.model)) {
      throw std::invalid_argument("model '" + opt.models_dir + "/" + c.model + "' not found (see --models)");
    }
  }
  fs::create_directories(opt.out_dir);
  const std::string csv = opt.out_dir + "/sweep.csv", md = opt.out_dir + "/sweep.md";
  std::map<std::string, CellResult> done = read_finished(csv);

  // rewrite the finished cells cleanly, then append each new cell as soon as it ends
  {
    AtomicFile f(csv);
    f.stream() << kCsvHeader << '\n';
    for (const Cell& c : cells) {
      const auto it = done.find(c.key());
      if (it != done.end()) f.stream() << csv_row(it->second) << '\n';
    }
    f.commit();
  }
  std::ofstream append(csv, std::ios::app);
  int index = 0;
  for (const Cell& c : cells) {
    ++index;
    std::fprintf(stderr, "[%d/%zu] %s %s %s N=%d kmax=%d: ", index, cells.size(), c.model.c_str(),
                 c.formulation == "fd" ? "FD" : "ID", c.derivatives.c_str(), c.N, c.kmax);
    if (done.count(c.key())) {
      std::fprintf(stderr, "done earlier\n");
      continue;
    }
    CellResult r = run_cell(c, opt, 0.0);
    // the paper's rule: ID that fails with Q_a = 0 is rerun with Q_a = 1e-4 I
    if (r.diverged && c.formulation == "id") {
      std::fprintf(stderr, "diverged at %.3f s with Qa = 0, rerun with Qa = 1e-4: ", r.diverged_at);
      r = run_cell(c, opt, 1e-4);
    }
    std::fprintf(stderr, "%.4g ms per update, %s\n", r.mean_ms,
                 r.diverged ? ("diverged at " + fmt(r.diverged_at) + " s").c_str() : "ok");
    append << csv_row(r) << '\n' << std::flush;
    done[c.key()] = r;
    AtomicFile f(md);
    f.stream() << markdown(cells, done, opt);
    f.commit();
  }
  AtomicFile f(md);
  f.stream() << markdown(cells, done, opt);
  f.commit();
  std::cout << markdown(cells, done, opt) << "\nwritten: " << md << ", " << csv << "\n";
}

}  // namespace

void register_sweep(CLI::App& app) {
  auto opt = std::make_shared<SweepOptions>();
  CLI::App* sub = app.add_subcommand("sweep", "The paper's grids closed-loop (Tables 1-3), resumable");
  sub->add_option("--out", opt->out_dir, "output directory (sweep.csv, sweep.md)")->capture_default_str();
  sub->add_option("--models", opt->models_dir, "directory with arm4.xml and chain{8,16,24,32}.xml")
      ->capture_default_str();
  sub->add_option("--tables", opt->tables, "12 (arm4 N x kmax), 3 (n = 8..32) or all")->capture_default_str();
  sub->add_option("--derivatives", opt->derivatives, "matrix, adjoint or both")->capture_default_str();
  sub->add_option("--duration", opt->duration, "simulated seconds per run")->capture_default_str();
  sub->add_flag("--logs", opt->logs, "keep each run's CSV log in the output directory");
  sub->callback([opt] { run(*opt); });
}

}  // namespace idmpc::app
