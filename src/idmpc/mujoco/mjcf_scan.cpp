#include "idmpc/mujoco/mjcf_scan.hpp"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "idmpc/experiment/input_file.hpp"

namespace idmpc::mj {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxIncludeDepth = 16;

bool name_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == ':' || c == '.';
}

// an MJCF file's text; a file that cannot be an input file (a directory, a FIFO or a device, too
// large, missing or unreadable) is refused before it is read, naming `what`
std::string read_text(const std::string& path, const std::string& what) {
  const std::string problem = input_file_problem(path, "an MJCF file");
  if (!problem.empty()) throw std::runtime_error(what + ": " + problem);
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// the file identity of a path, so that two spellings of one file are one file
std::string identity(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  return ec ? fs::path(path).lexically_normal().string() : p.string();
}

// the files on the way from the model to the one being scanned, and every file scanned so far:
// MuJoCo includes each file once, and a cycle would otherwise be followed 16 levels deep
struct IncludeScan {
  std::string model;
  std::vector<std::string> chain;  // identities, the model first
  std::vector<std::string> names;  // as written, for messages
  std::set<std::string> seen;
};

void scan_into(const std::string& path, const std::string& what, const fs::path& base, IncludeScan& scan,
               std::vector<MjcfElement>& out) {
  if (scan.chain.size() > static_cast<std::size_t>(kMaxIncludeDepth)) return;
  const std::string text = read_text(path, what);
  for (MjcfElement& e : scan_elements(text, path)) {
    if (e.name == "include" && !e.get("file").empty()) {
      const fs::path file(e.get("file"));
      const std::string included = (file.is_absolute() ? file : base / file).string();
      const std::string at = "<include> '" + abbreviate(e.get("file")) + "' (" + e.file + " line " +
                             std::to_string(e.line) + ")";
      const std::string id = identity(included);
      const auto cycle = std::find(scan.chain.begin(), scan.chain.end(), id);
      if (cycle != scan.chain.end()) {
        std::string loop;
        for (auto k = cycle; k != scan.chain.end(); ++k) loop += scan.names[k - scan.chain.begin()] + " -> ";
        throw std::runtime_error("model '" + scan.model + "': " + at + " is an include cycle (" + loop + included +
                                 ")");
      }
      if (!scan.seen.insert(id).second) {
        throw std::runtime_error("model '" + scan.model + "': " + at + " includes '" + included +
                                 "' a second time: MuJoCo includes each file once");
      }
      scan.chain.push_back(id);
      scan.names.push_back(included);
      scan_into(included, "model '" + scan.model + "': " + at, base, scan, out);
      scan.chain.pop_back();
      scan.names.pop_back();
    } else {
      out.push_back(std::move(e));
    }
  }
}

// MuJoCo 2.2's mjuu_makefullname: an absolute file or directory wins, else all are joined
std::string full_name(const fs::path& model_dir, const std::string& dir, const std::string& file) {
  const fs::path f(file);
  if (f.is_absolute()) return f.string();
  const fs::path d(dir);
  if (d.is_absolute()) return (d / f).string();
  return (model_dir / d / f).lexically_normal().string();
}

}  // namespace

std::string MjcfElement::get(const std::string& key, const std::string& fallback) const {
  const auto it = attributes.find(key);
  return it == attributes.end() ? fallback : it->second;
}

std::vector<MjcfElement> scan_elements(const std::string& text, const std::string& file) {
  std::vector<MjcfElement> out;
  const std::size_t size = text.size();
  std::size_t i = 0;
  int line = 1;
  auto advance_to = [&](std::size_t target) {
    for (; i < target && i < size; ++i) line += text[i] == '\n';
  };
  auto skip_past = [&](const char* end) {
    const std::size_t pos = text.find(end, i);
    advance_to(pos == std::string::npos ? size : pos + std::char_traits<char>::length(end));
  };
  while (i < size) {
    const std::size_t lt = text.find('<', i);
    if (lt == std::string::npos) break;
    advance_to(lt);
    if (text.compare(i, 4, "<!--") == 0) {
      skip_past("-->");
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      skip_past("]]>");
    } else if (text.compare(i, 2, "<?") == 0) {
      skip_past("?>");
    } else if (text.compare(i, 2, "<!") == 0 || text.compare(i, 2, "</") == 0) {
      skip_past(">");
    } else {
      MjcfElement e;
      e.file = file;
      e.line = line;
      advance_to(i + 1);
      const std::size_t name_begin = i;
      while (i < size && name_char(text[i])) ++i;
      e.name = text.substr(name_begin, i - name_begin);
      // attributes: name = "value" or name = 'value', until > or />
      while (i < size && text[i] != '>') {
        if (std::isspace(static_cast<unsigned char>(text[i])) || text[i] == '/') {
          advance_to(i + 1);
          continue;
        }
        const std::size_t key_begin = i;
        while (i < size && name_char(text[i])) ++i;
        if (i == key_begin) {  // not XML we understand: leave this tag
          advance_to(i + 1);
          continue;
        }
        const std::string key = text.substr(key_begin, i - key_begin);
        while (i < size && std::isspace(static_cast<unsigned char>(text[i]))) advance_to(i + 1);
        if (i >= size || text[i] != '=') continue;
        advance_to(i + 1);
        while (i < size && std::isspace(static_cast<unsigned char>(text[i]))) advance_to(i + 1);
        if (i >= size || (text[i] != '"' && text[i] != '\'')) continue;
        const char quote = text[i];
        const std::size_t value_end = text.find(quote, i + 1);
        if (value_end == std::string::npos) {
          advance_to(size);
          break;
        }
        e.attributes[key] = text.substr(i + 1, value_end - i - 1);
        advance_to(value_end + 1);
      }
      advance_to(i + 1);
      if (!e.name.empty()) out.push_back(std::move(e));
    }
  }
  return out;
}

std::vector<MjcfElement> scan_mjcf(const std::string& path) {
  std::vector<MjcfElement> out;
  IncludeScan scan{path, {identity(path)}, {path}, {identity(path)}};
  scan_into(path, "model '" + path + "'", fs::path(path).parent_path(), scan, out);
  return out;
}

std::vector<AssetFile> asset_files(const std::vector<MjcfElement>& elements, const std::string& model_path) {
  const fs::path model_dir = fs::path(model_path).parent_path();
  std::string meshdir, texturedir;
  for (const MjcfElement& e : elements) {
    if (e.name != "compiler") continue;
    // MuJoCo >= 2.3's assetdir: both directories, unless meshdir or texturedir is given
    if (!e.get("assetdir").empty()) meshdir = texturedir = e.get("assetdir");
    meshdir = e.get("meshdir", meshdir);
    texturedir = e.get("texturedir", texturedir);
  }
  std::vector<AssetFile> out;
  for (const MjcfElement& e : elements) {
    if (e.name == "mesh" || e.name == "skin" || e.name == "hfield") {
      if (!e.get("file").empty()) out.push_back({e.name, full_name(model_dir, meshdir, e.get("file")), &e});
    } else if (e.name == "texture") {
      for (const char* key : {"file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback"}) {
        if (!e.get(key).empty()) out.push_back({"texture", full_name(model_dir, texturedir, e.get(key)), &e});
      }
    }
  }
  return out;
}

bool png_size(const std::string& path, long& width, long& height) {
  std::ifstream in(path, std::ios::binary);
  unsigned char header[24] = {};
  if (!in.read(reinterpret_cast<char*>(header), sizeof(header))) return false;
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (int k = 0; k < 8; ++k) {
    if (header[k] != kSignature[k]) return false;
  }
  // the IHDR chunk comes first: big-endian width at byte 16, height at byte 20
  auto be32 = [&](int at) {
    return static_cast<long>((std::uint32_t{header[at]} << 24) | (std::uint32_t{header[at + 1]} << 16) |
                             (std::uint32_t{header[at + 2]} << 8) | std::uint32_t{header[at + 3]});
  };
  width = be32(16);
  height = be32(20);
  return true;
}

}  // namespace idmpc::mj
