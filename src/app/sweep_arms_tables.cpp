#include "app/sweep_tables.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace idmpc::app {
namespace {

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

}  // namespace

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

}  // namespace idmpc::app
