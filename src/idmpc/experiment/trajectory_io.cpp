#include "idmpc/experiment/trajectory_io.hpp"

#include "idmpc/experiment/input_file.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <vector>

namespace idmpc {
namespace {

using nlohmann::json;

// a number as a user would type it
std::string text(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

// --- CSV ---

std::string_view trim(std::string_view s) {
  const auto blank = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> fields;
  for (;;) {
    const std::size_t comma = line.find(',');
    fields.push_back(trim(line.substr(0, comma)));
    if (comma == std::string_view::npos) return fields;
    line.remove_prefix(comma + 1);
  }
}

enum class Parsed { kNumber, kNotANumber, kOutOfRange };

// the whole field as one decimal or scientific number (optional sign), nothing else
Parsed parse_number(std::string_view s, double& x) {
  if (s.size() > 1 && s.front() == '+' && s[1] != '-' && s[1] != '+') s.remove_prefix(1);
  if (s.empty()) return Parsed::kNotANumber;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x, std::chars_format::general);
  if (ec == std::errc::result_out_of_range) return Parsed::kOutOfRange;
  if (ec != std::errc() || end != s.data() + s.size()) return Parsed::kNotANumber;
  return Parsed::kNumber;
}

// --- JSON ---

// typed access naming `where` and the field
struct Fields {
  const json& j;
  const std::string& where;

  [[noreturn]] void bad(const char* key, const std::string& expected) const {
    throw std::invalid_argument(where + ": field '" + key + "': expected " + expected + ", got " +
                                abbreviate(j.at(key).dump()));
  }
  [[noreturn]] void missing(const char* key, const std::string& expected) const {
    throw std::invalid_argument(where + ": missing field '" + key + "' (" + expected + ")");
  }
  void known(const std::set<std::string>& keys, const std::string& shape) const {
    for (const auto& item : j.items()) {
      if (keys.count(item.key())) continue;
      std::string list;
      for (const std::string& k : keys) list += (list.empty() ? "" : ", ") + k;
      throw std::invalid_argument(where + ": unknown field '" + abbreviate(item.key()) + "' for shape \"" + shape +
                                  "\" (expected " + list + ")");
    }
  }
  // a number, or `fallback` when absent and optional
  double number(const char* key, const std::string& expected, bool required, double fallback = 0) const {
    if (!j.contains(key)) {
      if (required) missing(key, expected);
      return fallback;
    }
    if (!j.at(key).is_number() || !std::isfinite(j.at(key).get<double>())) bad(key, expected);
    return j.at(key).get<double>();
  }
  // exactly n numbers
  VecX<double> vector(const char* key, int n, const std::string& expected) const {
    if (!j.contains(key)) missing(key, expected);
    const json& v = j.at(key);
    if (!v.is_array() || static_cast<int>(v.size()) != n) bad(key, expected);
    VecX<double> x(n);
    for (int i = 0; i < n; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) bad(key, expected);
      x[i] = v[i].get<double>();
    }
    return x;
  }
};

std::string numbers(int n, const char* what) {
  return n == 1 ? std::string("a list of 1 number (") + what + ")"
                : "a list of " + std::to_string(n) + " numbers (" + what + ")";
}

// below this a direction counts as zero (a normal along z, a start at the centre)
constexpr double kDegenerate = 1e-9;

std::unique_ptr<Trajectory> circle(const Fields& f, const VecX<double>& start,
                                   const std::optional<Vec3<double>>& plane_normal,
                                   const std::optional<Vec3<double>>& outward) {
  f.known({"shape", "radius", "frequency", "normal", "ramp", "center"}, "circle");
  if (start.size() != 3) {
    throw std::invalid_argument(f.where + ": field 'shape': \"circle\" needs a 3-D reference (a position), got dim " +
                                std::to_string(start.size()));
  }
  const double r = f.number("radius", "a positive number [m]", true);
  if (!(r > 0)) f.bad("radius", "a positive number [m]");
  const std::string frequency = "a positive number [Hz] of at most " + text(CircleTrajectory::kMaxFrequency);
  const double freq = f.number("frequency", frequency, true);
  if (!(freq > 0) || freq > CircleTrajectory::kMaxFrequency) f.bad("frequency", frequency);
  const std::string ramp_expected = "a non-negative number [s] of at most " + text(CircleTrajectory::kMaxRamp);
  const double ramp = f.number("ramp", ramp_expected, false, 1.0);
  if (!(ramp >= 0) || ramp > CircleTrajectory::kMaxRamp) f.bad("ramp", ramp_expected);
  if (!std::isfinite(2 * M_PI * freq * r)) f.bad("radius", "a radius whose speed 2 pi frequency radius is finite [m]");
  // the plane a planar arm moves in is also the one plane that faces it
  Vec3<double> n = plane_normal ? plane_normal->normalized() : Vec3<double>::UnitX();
  const bool facing = f.j.contains("normal") && f.j.at("normal") == "facing";
  if (facing && !plane_normal) {
    // a vertical plane facing the base at the world origin: the normal along the start's
    // horizontal direction from it
    n = Vec3<double>(start[0], start[1], 0.0);
    if (!(n.norm() > kDegenerate)) {
      f.bad("normal", "[x, y, z], or \"facing\" with a start off the world's vertical axis");
    }
    n.normalize();
  } else if (f.j.contains("normal") && !facing) {
    n = f.vector("normal", 3, "a non-zero list of 3 numbers (the plane's normal) or \"facing\"");
    if (!(n.norm() > 0)) f.bad("normal", "a non-zero list of 3 numbers (the plane's normal)");
    n.normalize();
  }
  // a direction's part in the plane; projected twice once normalized, so that a short part
  // (a direction nearly along n) is as perpendicular to n as a long one
  const auto in_plane = [&n](const Vec3<double>& d) -> Vec3<double> { return d - n.dot(d) * n; };
  const auto unit_in_plane = [&in_plane](const Vec3<double>& d) -> Vec3<double> {
    return in_plane(in_plane(d).normalized()).normalized();
  };
  // e1 by default: world +z projected onto the plane (+y when the normal is along z); where the
  // start is as far out as the arm reaches (`outward`, mostly in the plane), that direction: the
  // circle then lies on the side the arm can reach
  const bool out_in_plane = outward && in_plane(*outward).norm() > 0.5 * outward->norm();
  const Vec3<double> e1_default =
      out_in_plane ? unit_in_plane(*outward)
                   : unit_in_plane(in_plane(Vec3<double>::UnitZ()).norm() < kDegenerate ? Vec3<double>::UnitY()
                                                                                      : Vec3<double>::UnitZ());
  const Vec3<double> p0 = start;
  if (!f.j.contains("center")) return std::make_unique<CircleTrajectory>(p0 - r * e1_default, n, r, freq, e1_default, ramp);
  // a given centre: e1 towards the start projected onto the plane
  const Vec3<double> c = f.vector("center", 3, numbers(3, "x, y, z [m]"));
  const Vec3<double> e1 = in_plane(p0 - c).norm() < kDegenerate * std::max(1.0, r) ? e1_default : unit_in_plane(p0 - c);
  return std::make_unique<CircleTrajectory>(c, n, r, freq, e1, ramp);
}

std::unique_ptr<Trajectory> line(const Fields& f, const VecX<double>& start) {
  f.known({"shape", "to", "duration", "delay"}, "line");
  const int dim = static_cast<int>(start.size());
  const VecX<double> to = f.vector("to", dim, numbers(dim, "the reference's dim"));
  const double duration = f.number("duration", "a positive number [s]", true);
  if (!(duration > 0)) f.bad("duration", "a positive number [s]");
  const double delay = f.number("delay", "a non-negative number [s]", false, 0.0);
  if (!(delay >= 0)) f.bad("delay", "a non-negative number [s]");
  MatX<double> P(dim, 2);
  P << start, to;
  try {
    return std::make_unique<WaypointTrajectory>(std::vector<double>{delay, delay + duration}, std::move(P));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(f.where + ": field 'duration': " + e.what());
  }
}

std::unique_ptr<Trajectory> waypoints(const Fields& f, const VecX<double>& start) {
  f.known({"shape", "points"}, "waypoints");
  const char* expected = "a non-empty list of {\"t\": seconds, \"value\": [...]}";
  if (!f.j.contains("points")) f.missing("points", expected);
  const json& points = f.j.at("points");
  if (!points.is_array() || points.empty()) f.bad("points", expected);
  const int dim = static_cast<int>(start.size());
  std::vector<double> t;
  std::vector<VecX<double>> values;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::string where = f.where + ", 'points'[" + std::to_string(i) + "]";
    if (!points[i].is_object()) {
      throw std::invalid_argument(where + ": expected {\"t\": seconds, \"value\": [...]}, got " +
                                  abbreviate(points[i].dump()));
    }
    const Fields p{points[i], where};
    p.known({"t", "value"}, "waypoints");
    const double ti = p.number("t", "a non-negative number [s]", true);
    if (!(ti >= 0)) p.bad("t", "a non-negative number [s]");
    if (!t.empty() && !(ti > t.back())) {
      p.bad("t", "a time after the previous point's " + text(t.back()) + " s (strictly increasing)");
    }
    t.push_back(ti);
    values.push_back(p.vector("value", dim, numbers(dim, "the reference's dim")));
  }
  // the reference starts where it is at t = 0
  if (t.front() > 0) {
    t.insert(t.begin(), 0.0);
    values.insert(values.begin(), start);
  }
  MatX<double> P(dim, static_cast<Eigen::Index>(values.size()));
  for (std::size_t k = 0; k < values.size(); ++k) P.col(static_cast<Eigen::Index>(k)) = values[k];
  try {
    return std::make_unique<WaypointTrajectory>(std::move(t), std::move(P));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(f.where + ": field 'points': " + e.what());
  }
}

std::unique_ptr<Trajectory> csv(const Fields& f, const VecX<double>& start, const std::string& base_dir) {
  f.known({"shape", "file"}, "csv");
  const char* expected = "a CSV file name, relative to the task file";
  if (!f.j.contains("file")) f.missing("file", expected);
  if (!f.j.at("file").is_string() || f.j.at("file").get<std::string>().empty() ||
      f.j.at("file").get<std::string>().size() > kMaxPathChars) {
    f.bad("file", expected);
  }
  const std::filesystem::path file(f.j.at("file").get<std::string>());
  const std::string path =
      file.is_absolute() ? file.string() : (std::filesystem::path(base_dir) / file).lexically_normal().string();
  try {
    return std::make_unique<SampledTrajectory>(read_trajectory_csv(path, static_cast<int>(start.size())));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(f.where + ": field 'file': " + e.what());
  }
}

}  // namespace

SampledTrajectory read_trajectory_csv(const std::string& path, int dim) {
  const std::string file = "trajectory file '" + path + "'";
  if (dim < 1) throw std::invalid_argument(file + ": expected a dimension >= 1, got " + std::to_string(dim));
  std::istringstream in(read_input_file(path, "trajectory file", "a CSV file"));
  const std::size_t columns = static_cast<std::size_t>(dim) + 1;
  const std::string expected_columns = std::to_string(columns) + " columns (time and " + std::to_string(dim) +
                                       (dim == 1 ? " value)" : " values)");
  std::vector<double> t;
  std::vector<double> values;  // row after row
  int previous_line = 0;
  bool first = true;
  std::string raw;
  for (int number = 1; std::getline(in, raw); ++number) {
    // comments, line endings and blank lines
    std::string_view line(raw);
    if (number == 1 && line.substr(0, 3) == "\xEF\xBB\xBF") line.remove_prefix(3);  // a UTF-8 byte order mark
    line = line.substr(0, line.find('#'));
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (trim(line).empty()) continue;
    const std::string at = file + " line " + std::to_string(number);
    const std::vector<std::string_view> fields = split(line);
    double x = 0;
    // a header: a first line without a number (one with a mistyped number is data, and an error)
    bool header = first;
    for (std::size_t c = 0; header && c < fields.size(); ++c) header = parse_number(fields[c], x) == Parsed::kNotANumber;
    first = false;
    if (fields.size() != columns) {
      throw std::invalid_argument(at + ": expected " + expected_columns + ", got " + std::to_string(fields.size()) +
                                  (header ? " (header)" : ""));
    }
    if (header) continue;
    for (std::size_t c = 0; c < columns; ++c) {
      const std::string field = at + ", column " + std::to_string(c + 1) + ": expected ";
      const std::string got = ", got '" + abbreviate(fields[c]) + "'";
      switch (parse_number(fields[c], x)) {
        case Parsed::kNotANumber: throw std::invalid_argument(field + "a number" + got);
        case Parsed::kOutOfRange: throw std::invalid_argument(field + "a number in double range" + got);
        case Parsed::kNumber: break;
      }
      if (!std::isfinite(x)) throw std::invalid_argument(field + "a finite number" + got);
      if (c == 0) {
        if (!t.empty() && !(x > t.back())) {
          throw std::invalid_argument(field + "a time after " + text(t.back()) + " s on line " +
                                      std::to_string(previous_line) + " (strictly increasing)" + got);
        }
        t.push_back(x);
      } else {
        values.push_back(x);
      }
    }
    if (t.size() >= 2) {
      // the rate from the previous row: it must not overflow (times 1e-310 s apart)
      const double h = t.back() - t[t.size() - 2];
      const double* now = values.data() + values.size() - static_cast<std::size_t>(dim);
      bool finite_rate = std::isfinite(4 / h);
      for (int i = 0; i < dim && finite_rate; ++i) finite_rate = std::isfinite(4 * ((now[i] - now[i - dim]) / h));
      if (!finite_rate) {
        throw std::invalid_argument(at + ", column 1: expected a time far enough after " + text(t[t.size() - 2]) +
                                    " s on line " + std::to_string(previous_line) +
                                    " for a finite rate between the rows, got '" + abbreviate(fields[0]) + "'");
      }
    }
    previous_line = number;
  }
  if (t.size() < 2) {
    throw std::invalid_argument(file + ": expected at least 2 rows of samples, got " + std::to_string(t.size()));
  }
  MatX<double> P = Eigen::Map<const MatX<double>>(values.data(), dim, static_cast<Eigen::Index>(t.size()));
  return SampledTrajectory(std::move(t), std::move(P));
}

namespace {

std::unique_ptr<Trajectory> shape_of(const json& j, const std::string& where, const VecX<double>& start,
                                     const std::string& base_dir, const std::optional<Vec3<double>>& plane_normal,
                                     const std::optional<Vec3<double>>& outward);

}  // namespace

std::unique_ptr<Trajectory> trajectory_from_json(const json& j, const std::string& where, const VecX<double>& start,
                                                 const std::string& base_dir,
                                                 const std::optional<Vec3<double>>& plane_normal,
                                                 const std::optional<Vec3<double>>& outward) {
  try {
    return shape_of(j, where, start, base_dir, plane_normal, outward);
  } catch (const std::invalid_argument& e) {
    // the trajectories' own checks name neither the file nor the field: prefixed once
    const std::string what = e.what();
    if (what.rfind(where, 0) == 0) throw;
    throw std::invalid_argument(where + ": " + what);
  }
}

namespace {

std::unique_ptr<Trajectory> shape_of(const json& j, const std::string& where, const VecX<double>& start,
                                     const std::string& base_dir, const std::optional<Vec3<double>>& plane_normal,
                                     const std::optional<Vec3<double>>& outward) {
  if (start.size() < 1) throw std::invalid_argument(where + ": the reference's start value is empty (dim 0)");
  if (!start.allFinite()) throw std::invalid_argument(where + ": the reference's start value is not finite");
  if (!j.is_object()) {
    throw std::invalid_argument(where + ": expected an object {\"shape\": \"circle\" | \"line\" | \"waypoints\" | "
                                        "\"csv\", ...}, got " + abbreviate(j.dump()));
  }
  const Fields f{j, where};
  const char* shapes = "\"circle\", \"line\", \"waypoints\" or \"csv\"";
  if (!j.contains("shape")) f.missing("shape", shapes);
  const json& shape = j.at("shape");
  if (shape == "circle") return circle(f, start, plane_normal, outward);
  if (shape == "line") return line(f, start);
  if (shape == "waypoints") return waypoints(f, start);
  if (shape == "csv") return csv(f, start, base_dir);
  f.bad("shape", shapes);
}

}  // namespace

}  // namespace idmpc
