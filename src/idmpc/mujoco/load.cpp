#include "idmpc/mujoco/load.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unistd.h>

#include "idmpc/experiment/input_file.hpp"
#include "idmpc/mujoco/gravcomp.hpp"
#include "idmpc/mujoco/mjcf_scan.hpp"
#include "idmpc/mujoco/mjcf_translate.hpp"

namespace idmpc::mj {
namespace {

std::mutex g_warning_mutex;
std::vector<std::string>& warning_list() {
  static std::vector<std::string> list;
  return list;
}

void throw_error(const char* msg) { throw std::runtime_error(std::string("MuJoCo error: ") + msg); }

void collect_warning(const char* msg) {
  std::lock_guard<std::mutex> lock(g_warning_mutex);
  warning_list().emplace_back(msg);
}

// images MuJoCo loads in full (RGB textures, height fields): at most 8192 x 8192 pixels, about
// 200 MB; larger ones (40000 x 40000 overflows MuJoCo's int sizes) are refused before loading
constexpr long long kMaxImagePixels = 8192LL * 8192LL;

// MJCF names (attributes, values, elements) that MuJoCo 2.2 does not know and later versions
// added; Menagerie models use several of them
const std::set<std::string> kNewerNames = {
    "implicitfast", "kv", "dampratio", "gravcomp", "actuatorgravcomp", "inheritrange", "actearly",
    "actdim", "maxhullvert", "assetdir", "eulerdamp", "nsample", "interp", "delay", "replicate",
    "frame", "flex", "flexcomp", "plugin", "extension", "instance", "attach", "layer"};

long long integer(const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long long x = std::strtoll(text.c_str(), &end, 10);
  if (errno == ERANGE) return std::numeric_limits<long long>::max();
  return x;
}

void check_render_asset_sizes(const std::vector<MjcfElement>& elements, const std::string& path) {
  auto refuse = [&](const MjcfElement& e, const std::string& what, long long w, long long h) {
    throw std::runtime_error("model '" + path + "': <" + e.name + "> '" + e.get("name", "(unnamed)") +
                             "' (" + e.file + " line " + std::to_string(e.line) + ") " + what + " is " +
                             std::to_string(w) + "x" + std::to_string(h) + ": expected at most " +
                             std::to_string(kMaxImagePixels) + " pixels (8192x8192)");
  };
  auto too_big = [](long long w, long long h) {
    // negative sizes are MuJoCo's to report
    return w > 0 && h > 0 && (w > kMaxImagePixels || h > kMaxImagePixels || w * h > kMaxImagePixels);
  };
  for (const MjcfElement& e : elements) {
    if (e.name == "texture" && e.get("builtin", "none") != "none") {
      const long long w = integer(e.get("width", "0")), h = integer(e.get("height", "0"));
      if (too_big(w, h)) refuse(e, "builtin texture", w, h);
    } else if (e.name == "hfield") {
      const long long r = integer(e.get("nrow", "0")), c = integer(e.get("ncol", "0"));
      if (too_big(r, c)) refuse(e, "height field", r, c);
    }
  }
  for (const AssetFile& a : asset_files(elements, path)) {
    long w = 0, h = 0;
    if (a.kind == "texture" && png_size(a.resolved, w, h) && too_big(w, h)) {
      refuse(*a.element, "texture file '" + a.resolved + "'", w, h);
    }
  }
}

// attributes (MJCF and URDF) holding the numbers of the model's physics: MuJoCo 2.2 compiles NaN
// or infinity in them, or quietly drops it (a geom's mass="nan" is taken as unset, and the
// density's mass used instead)
const std::set<std::string> kPhysicalAttributes = {
    "mass", "density", "pos", "quat", "axisangle", "euler", "xyaxes", "zaxis", "fromto", "size", "diaginertia",
    "fullinertia", "axis", "range", "ctrlrange", "forcerange", "actuatorfrcrange", "frictionloss", "damping",
    "armature", "stiffness", "springref", "ref", "gear", "gainprm", "biasprm", "kp", "kv", "timestep", "gravity",
    "settotalmass", "friction", "qpos",
    // URDF
    "xyz", "rpy", "value", "effort", "lower", "upper", "velocity", "ixx", "ixy", "ixz", "iyy", "iyz", "izz"};

void check_finite_numbers(const std::vector<MjcfElement>& elements, const std::string& path) {
  for (const MjcfElement& e : elements) {
    for (const auto& [key, value] : e.attributes) {
      if (!kPhysicalAttributes.count(key)) continue;
      std::istringstream tokens(value);
      for (std::string token; tokens >> token;) {
        char* end = nullptr;
        const double x = std::strtod(token.c_str(), &end);
        // a number MuJoCo reads as NaN or infinity (an overflow such as 1e999 included)
        if (end == token.c_str() + token.size() && !std::isfinite(x)) {
          throw std::runtime_error("model '" + path + "': <" + e.name + "> '" + abbreviate(e.get("name", "(unnamed)")) +
                                   "' (" + e.file + " line " + std::to_string(e.line) + ") has " + key + "=\"" +
                                   abbreviate(value) + "\": expected finite numbers");
        }
      }
    }
  }
}

// MuJoCo's parser message, turned into one line that says what to do
std::string explain_load_error(const std::string& raw, const std::vector<MjcfElement>& elements,
                               const std::string& path) {
  std::smatch match;
  std::string where;
  std::string line;
  if (std::regex_search(raw, match, std::regex("Element '([^']*)', line ([0-9]+)"))) {
    where = " (<" + match[1].str() + ">, line " + match[2].str() + ")";
    line = " (line " + match[2].str() + ")";
  }
  const std::string build = std::string("this build uses MuJoCo ") + mj_versionString();
  const std::regex attribute("unrecognized attribute: '([^']*)'"), keyword("invalid keyword: '([^']*)'");
  if (std::regex_search(raw, match, attribute) || std::regex_search(raw, match, keyword)) {
    const std::string name = match[1].str();
    const bool is_keyword = raw.find("invalid keyword") != std::string::npos;
    const std::string what = (is_keyword ? "value '" : "attribute '") + name + "'" + where;
    if (kNewerNames.count(name)) return what + " needs a newer MuJoCo: " + build;
    return what + " is unknown to MuJoCo " + mj_versionString() +
           " (this build): misspelled, or from a newer MuJoCo";
  }
  if (raw.find("unrecognized element") != std::string::npos &&
      std::regex_search(raw, match, std::regex("Element '([^']*)'"))) {
    const std::string name = match[1].str();
    if (kNewerNames.count(name)) return "element <" + name + ">" + line + " needs a newer MuJoCo: " + build;
    return "element <" + name + ">" + line + " is unknown to MuJoCo " + mj_versionString() +
           " (this build): misspelled, or from a newer MuJoCo";
  }
  // a missing asset: name the file as MuJoCo looked for it
  for (const AssetFile& a : asset_files(elements, path)) {
    std::error_code ec;
    if (!std::filesystem::exists(a.resolved, ec)) {
      return a.kind + " file '" + a.resolved + "' does not exist (<" + a.element->name + "> '" +
             a.element->get("name", "(unnamed)") + "', " + a.element->file + " line " +
             std::to_string(a.element->line) + ")";
    }
  }
  return raw.empty() ? std::string("unknown MuJoCo error") : raw;
}

}  // namespace

void install_error_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = throw_error;
    mju_user_warning = collect_warning;
  });
  install_gravcomp_callback();
}

std::vector<std::string> take_warnings() {
  std::lock_guard<std::mutex> lock(g_warning_mutex);
  std::vector<std::string> out;
  out.swap(warning_list());
  return out;
}

std::string LoadedModel::notice() const {
  if (translations.empty()) return "";
  std::vector<std::pair<std::string, int>> kinds;  // in order of first appearance
  for (const Translation& t : translations) {
    const auto it = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == t.kind; });
    if (it == kinds.end()) {
      kinds.emplace_back(t.kind, 1);
    } else {
      ++it->second;
    }
  }
  std::string list;
  for (const auto& [kind, count] : kinds) {
    list += (list.empty() ? "" : ", ") + kind + (count > 1 ? " ×" + std::to_string(count) : "");
  }
  const std::size_t n = translations.size();
  return "model '" + source + "' is written for a newer MuJoCo; translated in memory for MuJoCo " +
         mj_versionString() + " (the file is unchanged): " + std::to_string(n) + (n == 1 ? " change (" : " changes (") +
         list + "), each listed by 'idmpc check'";
}

LoadedModel load_model_translated(const std::string& path, const Weld* weld) {
  install_error_handlers();
  // a regular file MuJoCo can read whole: a directory, FIFO or device is refused before any read
  const std::string problem = input_file_problem(path, "an MJCF or URDF file");
  if (!problem.empty()) throw std::runtime_error("model '" + path + "': " + problem);
  // render-only assets MuJoCo would allocate in full: bounded before it sees them
  const std::vector<MjcfElement> elements = scan_mjcf(path);
  check_render_asset_sizes(elements, path);
  check_finite_numbers(elements, path);
  const MjcfTranslation translation = translate_mjcf(path, weld);
  std::vector<std::string> untranslatable = translation.untranslatable;
  auto refuse_untranslatable = [&] {
    const std::string version = mj_versionString();
    std::string items;
    for (std::size_t k = 0; k < untranslatable.size(); ++k) items += (k ? "; " : "") + untranslatable[k];
    throw std::runtime_error("cannot load model '" + path + "': it needs a newer MuJoCo (this build uses MuJoCo " +
                             version + "), and " + std::to_string(untranslatable.size()) +
                             (untranslatable.size() == 1 ? " item has" : " items have") +
                             " no MuJoCo " + version + " equivalent: " + items);
  };

  // the translated files, by the names MuJoCo looks them up (without directory)
  const auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  struct VfsGuard {
    mjVFS* vfs;
    ~VfsGuard() { mj_deleteVFS(vfs); }
  } guard{vfs.get()};
  for (const auto& [file, text] : translation.files) {
    const int status = mj_makeEmptyFileVFS(vfs.get(), file.c_str(), static_cast<int>(text.size()));
    if (status != 0) {
      throw std::runtime_error("cannot load model '" + path + "': its translation for MuJoCo " + mj_versionString() +
                               " needs '" + file + "' in memory, and " +
                               (status == 2 ? "another file of the model has the same name" : "MuJoCo has no room"));
    }
    std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), file.c_str())], text.data(), text.size());
  }

  char error[1024] = "";
  mjModel* raw = mj_loadXML(path.c_str(), translation.files.empty() ? nullptr : vfs.get(), error, sizeof(error));
  if (!raw) {
    // without the untranslatable parts the model may not compile: they are the first problem
    if (!untranslatable.empty()) refuse_untranslatable();
    throw std::runtime_error("cannot load model '" + path + "': " + explain_load_error(error, elements, path));
  }
  LoadedModel out;
  out.model = ModelPtr(raw);
  out.source = path;
  out.translations = translation.notices;
  JointForceRanges ranges = apply_translation(raw, translation, out.translations, untranslatable);
  if (!untranslatable.empty()) refuse_untranslatable();
  out.joint_force_lower = std::move(ranges.lower);
  out.joint_force_upper = std::move(ranges.upper);
  return out;
}

ModelPtr load_model(const std::string& path) { return std::move(load_model_translated(path).model); }

ModelPtr load_model_from_string(const std::string& xml) {
  char name[] = "/tmp/idmpc_model_XXXXXX.xml";
  const int fd = mkstemps(name, 4);
  if (fd < 0) throw std::runtime_error("cannot create a temporary model file");
  close(fd);
  {
    std::ofstream out(name);
    out << xml;
  }
  try {
    ModelPtr m = load_model(name);
    std::remove(name);
    return m;
  } catch (...) {
    std::remove(name);
    throw;
  }
}

DataPtr make_data(const mjModel* m) {
  install_error_handlers();
  mjData* d = mj_makeData(m);
  if (!d) throw std::runtime_error("MuJoCo could not allocate mjData");
  return DataPtr(d);
}

DataPtr transmission_at(const mjModel* m, const mjtNum* qpos) {
  DataPtr d = make_data(m);
  mju_copy(d->qpos, qpos, m->nq);
  mj_kinematics(m, d.get());
  mj_comPos(m, d.get());
  mj_tendon(m, d.get());
  mj_transmission(m, d.get());
  return d;
}

std::string object_name(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  if (name && name[0]) return name;
  return "#" + std::to_string(id);
}

int actuator_id(const mjModel* m, const std::string& name) {
  const int id = mj_name2id(m, mjOBJ_ACTUATOR, name.c_str());
  if (id >= 0) return id;
  for (int u = 0; u < m->nu; ++u) {
    if (object_name(m, mjOBJ_ACTUATOR, u) == name) return u;
  }
  return -1;
}

}  // namespace idmpc::mj
