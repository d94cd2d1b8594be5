// idmpc dynamics MODEL --in STATES.csv --out OUT.csv: ID and FD of our model, row by row.
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <stdexcept>

#include "app/atomic_file.hpp"
#include "app/commands.hpp"
#include "app/output_paths.hpp"
#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/mujoco/import.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::app {
namespace {

// bounds on the input, so that an endless or binary stream ends with an error, not with
// memory or disk exhausted
constexpr long kMaxRows = 10'000'000;       // ≈ 2 GB of output at n = 4
constexpr std::size_t kMaxLineBytes = 1 << 20;

struct DynamicsOptions {
  std::string model, in, out;
  bool direct_torque = false;
  bool actuate_every_joint = false;
};

std::string quoted_field(const std::string& field) {
  constexpr std::size_t kShown = 40;
  return "'" + (field.size() > kShown ? field.substr(0, kShown) + "…" : field) + "'";
}

// reads one line of at most kMaxLineBytes; false at the end of the input
bool read_line(std::istream& in, std::string& line, const std::string& where) {
  line.clear();
  for (int c = in.get(); c != std::char_traits<char>::eof(); c = in.get()) {
    if (c == '\n') return true;
    if (line.size() == kMaxLineBytes) {
      throw std::invalid_argument(where + " is longer than " + std::to_string(kMaxLineBytes) +
                                  " bytes: expected rows of 3n numbers");
    }
    line.push_back(static_cast<char>(c));
  }
  return !line.empty();
}

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  std::size_t begin = 0;
  for (std::size_t end = line.find(','); end != std::string::npos; end = line.find(',', begin)) {
    fields.push_back(line.substr(begin, end - begin));
    begin = end + 1;
  }
  fields.push_back(line.substr(begin));
  return fields;
}

// a whole field (surrounding blanks allowed) as a number; false if it is anything else
bool parse_number(const std::string& field, double& x) {
  const std::size_t first = field.find_first_not_of(" \t\r");
  if (first == std::string::npos) return false;
  const std::size_t last = field.find_last_not_of(" \t\r");
  const std::string text = field.substr(first, last - first + 1);
  if (text.find('\0') != std::string::npos) return false;
  char* end = nullptr;
  x = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

void run(const DynamicsOptions& opt) {
  std::vector<NamedPath> inputs = model_inputs(opt.model);
  inputs.push_back({"--in", opt.in});
  check_output_paths(inputs, {{"--out", opt.out}});
  const mj::LoadedModel loaded = mj::load_model_translated(opt.model);
  if (!loaded.translations.empty()) std::cerr << "idmpc: note: " << loaded.notice() << "\n";
  mj::ImportOptions options;
  options.direct_torque = opt.direct_torque;
  options.actuate_every_joint = opt.actuate_every_joint;
  const mj::ImportedModel imported = mj::import_model(loaded.model.get(), opt.model, options);
  for (const auto& n : imported.notices) std::cerr << "idmpc: note: " << n << "\n";
  const Model& model = imported.model;
  const int n = model.n;
  const std::size_t columns = 3 * static_cast<std::size_t>(n);
  std::ifstream in(opt.in, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read states file '" + opt.in + "'");
  AtomicFile out(opt.out);
  auto& os = out.stream();
  for (int i = 0; i < n; ++i) os << (i ? "," : "") << "tau" << i;
  for (int i = 0; i < n; ++i) os << ",qacc" << i;
  os << '\n' << std::setprecision(17);

  Data data(model);
  VecX<double> q(n), v(n), x(n);
  std::string line;
  long line_no = 0, rows = 0;
  bool first = true;
  for (;;) {
    const std::string where = "'" + opt.in + "' line " + std::to_string(line_no + 1);
    if (!read_line(in, line, where)) break;
    ++line_no;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    auto bad = [&](const std::string& what) { return std::invalid_argument(where + ": " + what); };
    if (line.find('\0') != std::string::npos) throw bad("contains a NUL byte: expected text");
    const std::vector<std::string> fields = split_fields(line);
    if (fields.size() != columns) {
      std::string hint;
      if (fields.size() == 1 && (line.find(';') != std::string::npos || line.find('\t') != std::string::npos)) {
        hint = "; fields must be separated by ',' (this line uses ';' or tabs)";
      }
      throw bad(std::to_string(fields.size()) + " field" + (fields.size() == 1 ? "" : "s") +
                ", expected 3n = " + std::to_string(columns) + " (q, v, then acceleration or torque)" + hint);
    }
    // the first non-blank line may be a header: names only, not a single number
    std::size_t numeric = 0;
    std::vector<double> row(columns);
    for (std::size_t k = 0; k < columns; ++k) numeric += parse_number(fields[k], row[k]);
    if (first && numeric == 0) {
      first = false;
      continue;
    }
    first = false;
    for (std::size_t k = 0; k < columns; ++k) {
      if (!parse_number(fields[k], row[k])) {
        throw bad("field " + std::to_string(k + 1) + " " + quoted_field(fields[k]) + " is not a number");
      }
      if (!std::isfinite(row[k])) {
        throw bad("field " + std::to_string(k + 1) + " " + quoted_field(fields[k]) +
                  " is not a finite number");
      }
    }
    if (++rows > kMaxRows) {
      throw bad("more than " + std::to_string(kMaxRows) + " rows: split the input into smaller files");
    }
    for (int i = 0; i < n; ++i) {
      q[i] = row[i];
      v[i] = row[n + i];
      x[i] = row[2 * n + i];
    }
    const VecX<double> tau = rnea(model, data, q, v, x);
    const VecX<double>& qacc = aba(model, data, q, v, x);
    if (!tau.allFinite() || !qacc.allFinite()) {
      throw bad("the dynamics are not finite at this state (tau or qacc overflows): expected "
                "q, v and x of physical size");
    }
    for (int i = 0; i < n; ++i) os << (i ? "," : "") << tau[i];
    for (int i = 0; i < n; ++i) os << ',' << qacc[i];
    os << '\n';
  }
  if (in.bad()) throw std::runtime_error("cannot read states file '" + opt.in + "': read error");
  if (rows == 0) {
    throw std::invalid_argument("'" + opt.in + "' has no data rows: expected rows of 3n = " +
                                std::to_string(columns) + " comma-separated numbers");
  }
  out.commit();
}

}  // namespace

void register_dynamics(CLI::App& app) {
  auto opt = std::make_shared<DynamicsOptions>();
  CLI::App* sub = app.add_subcommand(
      "dynamics", "Row by row: tau = ID(q, v, x) and qacc = FD(q, v, x) from rows q, v, x");
  sub->add_option("model", opt->model, "MJCF/URDF model file")->required();
  sub->add_option("--in", opt->in,
                  "CSV of rows q, v, x (3n comma-separated numbers; the first line may be a header "
                  "of names; at most 10^7 rows of 1 MiB)")
      ->required();
  sub->add_option("--out", opt->out, "CSV output: tau0..tau{n-1},qacc0..qacc{n-1}")
      ->required()
      ->check(non_empty_path());
  sub->add_flag("--direct-torque", opt->direct_torque,
                "ignore the model's actuators (only their validation)");
  sub->add_flag("--actuate-every-joint", opt->actuate_every_joint,
                "accept direct torques on the joints the model has no actuator for (under-actuated models)");
  sub->callback([opt] { run(*opt); });
}

}  // namespace idmpc::app
