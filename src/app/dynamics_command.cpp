// idmpc dynamics MODEL --in STATES.csv --out OUT.csv: ID and FD of our model, row by row.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::app {
namespace {

struct DynamicsOptions {
  std::string model, in, out;
  bool direct_torque = false;
};

// splits a CSV line; returns false if any field is not a number
bool parse_numbers(const std::string& line, std::vector<double>& out) {
  out.clear();
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, ',')) {
    const char* begin = field.c_str();
    char* end = nullptr;
    const double x = std::strtod(begin, &end);
    while (end && (*end == ' ' || *end == '\t' || *end == '\r')) ++end;
    if (end == begin || (end && *end != '\0')) return false;
    out.push_back(x);
  }
  return true;
}

void run(const DynamicsOptions& opt) {
  const mj::ModelPtr m = mj::load_model(opt.model);
  const Model model = mj::import_model(m.get(), opt.model, mj::ImportOptions{opt.direct_torque}).model;
  const int n = model.n;
  std::ifstream in(opt.in);
  if (!in) throw std::runtime_error("cannot read states file '" + opt.in + "'");
  AtomicFile out(opt.out);
  auto& os = out.stream();
  for (int i = 0; i < n; ++i) os << (i ? "," : "") << "tau" << i;
  for (int i = 0; i < n; ++i) os << ",qacc" << i;
  os << '\n' << std::setprecision(17);

  Data data(model);
  VecX<double> q(n), v(n), x(n);
  std::vector<double> row;
  std::string line;
  int line_no = 0, rows = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (!parse_numbers(line, row)) {
      if (line_no == 1) continue;  // header
      throw std::invalid_argument("'" + opt.in + "' line " + std::to_string(line_no) +
                                  ": a field is not a number");
    }
    if (static_cast<int>(row.size()) != 3 * n) {
      throw std::invalid_argument("'" + opt.in + "' line " + std::to_string(line_no) + ": " +
                                  std::to_string(row.size()) + " values, expected 3n = " +
                                  std::to_string(3 * n) + " (q, v, then acceleration or torque)");
    }
    for (int i = 0; i < n; ++i) {
      q[i] = row[i];
      v[i] = row[n + i];
      x[i] = row[2 * n + i];
    }
    if (!q.allFinite() || !v.allFinite() || !x.allFinite()) {
      throw std::invalid_argument("'" + opt.in + "' line " + std::to_string(line_no) + ": non-finite value");
    }
    const VecX<double> tau = rnea(model, data, q, v, x);
    const VecX<double>& qacc = aba(model, data, q, v, x);
    for (int i = 0; i < n; ++i) os << (i ? "," : "") << tau[i];
    for (int i = 0; i < n; ++i) os << ',' << qacc[i];
    os << '\n';
    ++rows;
  }
  if (rows == 0) throw std::invalid_argument("'" + opt.in + "' has no data rows");
  out.commit();
}

}  // namespace

void register_dynamics(CLI::App& app) {
  auto opt = std::make_shared<DynamicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "dynamics", "Row by row: tau = ID(q, v, x) and qacc = FD(q, v, x) from rows q, v, x");
  sub->add_option("model", opt->model, "MJCF/URDF model file")->required();
  sub->add_option("--in", opt->in, "CSV of rows q, v, x (3n numbers; a header line is allowed)")->required();
  sub->add_option("--out", opt->out, "CSV output: tau0..tau{n-1},qacc0..qacc{n-1}")->required();
  sub->add_flag("--direct-torque", opt->direct_torque,
                "ignore the model's actuators (only their validation)");
  sub->callback([opt] { run(*opt); });
}

}  // namespace idmpc::app
