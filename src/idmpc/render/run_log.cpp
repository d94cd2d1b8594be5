#include "idmpc/render/run_log.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace idmpc::render {
namespace {

constexpr const char* kHeaderShape = "t,q0..q{n-1},v0..v{n-1},u0..u{n-1},residual,update_ms";

std::string trim(const std::string& s) {
  std::size_t b = 0;
  std::size_t e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

// counts consecutive columns prefix0, prefix1, ... starting at `at`
int count_indexed(const std::vector<std::string>& cols, std::size_t at, const std::string& prefix) {
  int k = 0;
  while (at + static_cast<std::size_t>(k) < cols.size() &&
         cols[at + static_cast<std::size_t>(k)] == prefix + std::to_string(k)) {
    ++k;
  }
  return k;
}

// the column layout of a header: n joint columns per q and v, nu torque columns
struct Layout {
  int n = 0;
  int nu = 0;
};

bool parse_header(const std::vector<std::string>& cols, Layout& layout) {
  if (cols.empty() || cols[0] != "t") return false;
  std::size_t at = 1;
  layout.n = count_indexed(cols, at, "q");
  if (layout.n < 1) return false;
  at += static_cast<std::size_t>(layout.n);
  if (count_indexed(cols, at, "v") != layout.n) return false;
  at += static_cast<std::size_t>(layout.n);
  layout.nu = count_indexed(cols, at, "u");
  if (layout.nu < 1) return false;
  at += static_cast<std::size_t>(layout.nu);
  return cols.size() == at + 2 && cols[at] == "residual" && cols[at + 1] == "update_ms";
}

bool parse_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  const char* begin = text.c_str();
  char* end = nullptr;
  value = std::strtod(begin, &end);
  // nan, inf and overflow to +-inf are kept: a diverged run logs them
  return end == begin + text.size();
}

// a field of the summary, at the top level or one object deep (e.g. {"controller": {...}})
const nlohmann::json* find_field(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return nullptr;
  if (auto it = j.find(key); it != j.end()) return &*it;
  for (const auto& item : j.items()) {
    if (item.value().is_object()) {
      if (auto it = item.value().find(key); it != item.value().end()) return &*it;
    }
  }
  return nullptr;
}

std::string number_text(const nlohmann::json& v) {
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  if (v.is_number()) {
    std::ostringstream ss;
    ss << v.get<double>();
    return ss.str();
  }
  if (v.is_string()) return v.get<std::string>();
  return "";
}

// fills formulation, derivatives and label from `<log>.json` when it exists
void read_summary(RunLog& log) {
  namespace fs = std::filesystem;
  const fs::path json_path = fs::path(log.path).replace_extension(".json");
  log.label = fs::path(log.path).stem().string();
  std::error_code ec;
  if (!fs::is_regular_file(json_path, ec)) return;

  std::ifstream in(json_path);
  if (!in) throw std::runtime_error("cannot open run summary '" + json_path.string() + "'");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("run summary '" + json_path.string() +
                             "': expected JSON, got a parse error: " + e.what());
  }
  auto text_field = [&](const char* key) {
    const nlohmann::json* v = find_field(j, key);
    return v && v->is_string() ? v->get<std::string>() : std::string();
  };
  log.formulation = text_field("formulation");
  log.derivatives = text_field("derivatives");
  const nlohmann::json* horizon = find_field(j, "N");
  const nlohmann::json* kmax = find_field(j, "kmax");
  if (log.formulation.empty()) return;

  // "C/GMRES (ID, adjoint) N=25 kmax=10"
  std::string upper = log.formulation;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  std::string label = "C/GMRES (" + upper;
  if (!log.derivatives.empty()) label += ", " + log.derivatives;
  label += ")";
  if (horizon && !number_text(*horizon).empty()) label += " N=" + number_text(*horizon);
  if (kmax && !number_text(*kmax).empty()) label += " kmax=" + number_text(*kmax);
  log.label = label;
}

}  // namespace

double RunLog::u_norm(std::size_t i) const {
  const double* row = u_row(i);
  double s = 0;
  for (int k = 0; k < nu; ++k) s += row[k] * row[k];
  return std::sqrt(s);
}

std::size_t RunLog::nearest_row(double time) const {
  const auto it = std::lower_bound(t.begin(), t.end(), time);
  if (it == t.begin()) return 0;
  if (it == t.end()) return t.size() - 1;
  const auto i = static_cast<std::size_t>(it - t.begin());
  return (time - t[i - 1] <= t[i] - time) ? i - 1 : i;
}

bool RunLog::finite_pose(std::size_t i) const {
  const double* row = q_row(i);
  return std::all_of(row, row + n, [](double x) { return std::isfinite(x); });
}

RunLog read_run_log(const std::string& csv_path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(csv_path, ec)) {
    throw std::runtime_error("run log '" + csv_path + "' does not exist");
  }
  if (fs::is_directory(csv_path, ec)) {
    throw std::runtime_error("run log '" + csv_path + "': expected a CSV file, got a directory");
  }
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error("cannot open run log '" + csv_path + "'");

  RunLog log;
  log.path = csv_path;
  const std::string where = "run log '" + csv_path + "'";

  // header
  std::string line;
  if (!std::getline(in, line)) {
    throw std::runtime_error(where + " is empty: expected a header " + kHeaderShape);
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line);
  Layout layout;
  if (!parse_header(header, layout)) {
    const std::string shown = line.size() > 200 ? line.substr(0, 200) + "..." : line;
    throw std::runtime_error(where + " line 1: bad header: expected " + kHeaderShape +
                             ", got '" + shown + "'");
  }
  log.n = layout.n;
  log.nu = layout.nu;

  // rows: t | q | v | u | residual | update_ms
  const std::size_t columns = header.size();
  const std::size_t q_at = 1;
  const std::size_t u_at = q_at + 2 * static_cast<std::size_t>(log.n);
  std::vector<double> values(columns);
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    const std::vector<std::string> cells = split(line);
    if (cells.size() != columns) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) + ": expected " +
                               std::to_string(columns) + " columns, got " +
                               std::to_string(cells.size()));
    }
    for (std::size_t c = 0; c < columns; ++c) {
      if (!parse_number(cells[c], values[c])) {
        throw std::runtime_error(where + " line " + std::to_string(line_no) + ", column '" +
                                 header[c] + "': expected a number, got '" + cells[c] + "'");
      }
    }
    const double time = values[0];
    if (!std::isfinite(time)) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) +
                               ": expected a finite time, got '" + cells[0] + "'");
    }
    if (!log.t.empty() && time < log.t.back()) {
      throw std::runtime_error(where + " line " + std::to_string(line_no) +
                               ": expected non-decreasing times, got " + cells[0] +
                               " after " + std::to_string(log.t.back()));
    }
    log.t.push_back(time);
    log.q.insert(log.q.end(), values.begin() + q_at, values.begin() + q_at + log.n);
    log.u.insert(log.u.end(), values.begin() + u_at, values.begin() + u_at + log.nu);
    log.residual.push_back(values[columns - 2]);
    log.update_ms.push_back(values[columns - 1]);
  }
  if (log.t.empty()) {
    throw std::runtime_error(where + " has a header but no rows: expected at least one row");
  }
  read_summary(log);
  return log;
}

void check_run_log(const RunLog& log, const mjModel* m, const std::string& model_path) {
  const std::string model_name = std::filesystem::path(model_path).filename().string();
  const std::string log_name = std::filesystem::path(log.path).filename().string();
  if (log.n != m->nq) {
    throw std::invalid_argument("log '" + log_name + "' has " + std::to_string(log.n) +
                                " joints but model '" + model_name + "' has " +
                                std::to_string(m->nq));
  }
}

}  // namespace idmpc::render
