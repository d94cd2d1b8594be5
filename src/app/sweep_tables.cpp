#include "app/sweep_tables.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <stdexcept>

namespace idmpc::app {

std::string fmt(double x, int precision) {
  if (std::isnan(x)) return "–";
  std::ostringstream o;
  o << std::setprecision(precision) << x;
  return o.str();
}

std::string stages_note(const SweepOptions& opt) {
  return opt.simd_stages ? "Matrix mode runs its stage derivatives in SIMD lanes (the default; `sweep --no-simd-stages` "
                           "runs every stage one by one, the paper's arithmetic)."
                         : "Every run evaluates its stages one by one (`--no-simd-stages`): matrix mode is the "
                           "paper's arithmetic.";
}

std::vector<std::string> variants(const std::vector<Cell>& cells) {
  std::vector<std::string> out;
  for (const Cell& c : cells) {
    if (std::find(out.begin(), out.end(), c.variant()) == out.end()) out.push_back(c.variant());
  }
  return out;
}

namespace {

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

}  // namespace

std::string markdown_with_latency(const PaperTables& tables, const std::vector<Cell>& cells,
                                  const std::map<std::string, CellResult>& done, const SweepOptions& opt) {
  const std::string tables_md = markdown(tables, cells, done, opt);
  if (opt.latency == std::vector<std::string>{"none"}) return tables_md;
  return tables_md + latency_markdown(opt, cells, done);
}

}  // namespace idmpc::app
