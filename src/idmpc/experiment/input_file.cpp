#include "idmpc/experiment/input_file.hpp"

#include <algorithm>
#include <set>
#include <vector>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace idmpc {
namespace {

// an open file descriptor, closed on scope exit
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

std::string mebibytes(std::uintmax_t bytes) {
  const std::uintmax_t mib = std::uintmax_t{1} << 20;
  return std::to_string((bytes + mib - 1) / mib) + " MiB";
}

// what kind of file a mode other than a regular file's names
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// opens `path` for reading without blocking and checks it is a regular file of at most
// `max_bytes`; the problem, or "" with `file` open
std::string open_input(const std::string& path, const std::string& expected, std::uintmax_t max_bytes, Fd& file) {
  if (path.empty()) return "expected a file name, got none";
  file.fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (file.fd < 0) {
    const int error = errno;
    if (error == ENOENT) return "does not exist";
    if (error == EACCES || error == EPERM) return "permission denied";
    if (error == ENOTDIR) return "does not exist (a part of the path is not a directory)";
    return std::string("cannot be opened (") + std::strerror(error) + ")";
  }
  struct stat st{};
  if (::fstat(file.fd, &st) != 0) return std::string("cannot be examined (") + std::strerror(errno) + ")";
  if (!S_ISREG(st.st_mode)) return std::string("is ") + kind_of(st.st_mode) + ", expected " + expected;
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    return "is " + mebibytes(static_cast<std::uintmax_t>(st.st_size)) + ", expected at most " + mebibytes(max_bytes);
  }
  return "";
}

}  // namespace

std::string abbreviate(std::string_view text, std::size_t max_chars) {
  if (text.size() <= max_chars) return std::string(text);
  std::size_t cut = max_chars;
  // not inside a UTF-8 sequence: back off its continuation bytes (10xxxxxx)
  while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0) == 0x80) --cut;
  return std::string(text.substr(0, cut)) + "\xE2\x80\xA6 (" + std::to_string(text.size()) + " characters)";
}

std::string input_file_problem(const std::string& path, const std::string& expected, std::uintmax_t max_bytes) {
  Fd file;
  return open_input(path, expected, max_bytes, file);
}

std::string read_input_file(const std::string& path, const std::string& noun, const std::string& expected,
                            std::uintmax_t max_bytes) {
  Fd file;
  const std::string problem = open_input(path, expected, max_bytes, file);
  const std::string where = noun + " '" + path + "'";
  if (!problem.empty()) throw std::invalid_argument(where + ": " + problem);
  std::string text;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t got = ::read(file.fd, buffer, sizeof(buffer));
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) throw std::invalid_argument(where + ": cannot be read (" + std::strerror(errno) + ")");
    if (got == 0) break;
    text.append(buffer, static_cast<std::size_t>(got));
    // it may have grown since it was examined
    if (text.size() > max_bytes) throw std::invalid_argument(where + ": is larger than " + mebibytes(max_bytes));
  }
  return text;
}

nlohmann::json parse_json(const std::string& text, const std::string& where) {
  // the nesting of arrays and objects outside strings, before the parser builds anything
  int depth = 0, deepest = 0, line = 1, first_too_deep = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
      if (depth > kMaxJsonDepth && first_too_deep == 0) first_too_deep = line;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  if (deepest > kMaxJsonDepth) {
    throw std::invalid_argument(where + ": arrays and objects nested " + std::to_string(deepest) +
                                " levels deep (line " + std::to_string(first_too_deep) + "), expected at most " +
                                std::to_string(kMaxJsonDepth));
  }
  // A key given twice in one object is refused (the parser would keep the last silently): the
  // enclosing objects' keys name where, e.g. "weights.Qq"
  using Event = nlohmann::json::parse_event_t;
  struct Level {
    bool object;
    std::string path;  ///< "" at the top, "weights", "reference.points[]", ...
    std::set<std::string> keys;
  };
  std::vector<Level> levels;
  std::string key;
  const auto check_keys = [&](int /*depth*/, Event event, nlohmann::json& parsed) {
    if (event == Event::object_start || event == Event::array_start) {
      std::string path;
      if (!levels.empty()) {
        const Level& parent = levels.back();
        path = !parent.object ? parent.path + "[]" : parent.path.empty() ? key : parent.path + "." + key;
      }
      levels.push_back({event == Event::object_start, std::move(path), {}});
    } else if (event == Event::object_end || event == Event::array_end) {
      levels.pop_back();
    } else if (event == Event::key) {
      key = parsed.get<std::string>();
      Level& level = levels.back();
      if (!level.keys.insert(key).second) {
        const std::string path = level.path.empty() ? key : level.path + "." + key;
        throw std::invalid_argument(where + ": key \"" + abbreviate(path, 100) +
                                    "\" appears twice in one object; give it once");
      }
    }
    return true;
  };
  try {
    return nlohmann::json::parse(text, check_keys);
  } catch (const nlohmann::json::exception& e) {
    // the parser quotes what it last read, which may be a whole long token
    throw std::invalid_argument(where + ": expected JSON, got a parse error: " + abbreviate(e.what(), 200));
  }
}

nlohmann::json read_json_file(const std::string& path, const std::string& noun) {
  return parse_json(read_input_file(path, noun, "a JSON file"), noun + " '" + path + "'");
}

namespace {

// decimal digits from `i`; how many
std::size_t decimal_digits(std::string_view s, std::size_t& i) {
  const std::size_t begin = i;
  while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
  return i - begin;
}

}  // namespace

bool is_decimal_real(std::string_view s, bool sign, bool infinity) {
  std::size_t i = 0;
  if (sign && i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  if (infinity && s.substr(i) == "inf") return true;
  const std::size_t first = i;
  const std::size_t whole = decimal_digits(s, i);
  if (whole > 1 && s[first] == '0') return false;
  std::size_t fraction = 0;
  if (i < s.size() && s[i] == '.') {
    ++i;
    fraction = decimal_digits(s, i);
  }
  if (whole + fraction == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    if (decimal_digits(s, i) == 0) return false;
  }
  return i == s.size();
}

bool is_decimal_integer(std::string_view s, bool sign) {
  std::size_t i = 0;
  if (sign && i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  const std::size_t first = i;
  const std::size_t n = decimal_digits(s, i);
  return n > 0 && i == s.size() && !(n > 1 && s[first] == '0');
}

}  // namespace idmpc
