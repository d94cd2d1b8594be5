#include "idmpc/mujoco/load.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <unistd.h>

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

}  // namespace

void install_error_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_error = throw_error;
    mju_user_warning = collect_warning;
  });
}

std::vector<std::string> take_warnings() {
  std::lock_guard<std::mutex> lock(g_warning_mutex);
  std::vector<std::string> out;
  out.swap(warning_list());
  return out;
}

ModelPtr load_model(const std::string& path) {
  install_error_handlers();
  if (!std::filesystem::exists(path)) {
    throw std::runtime_error("model file '" + path + "' does not exist");
  }
  char error[1024] = "";
  mjModel* m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
  if (!m) {
    throw std::runtime_error("cannot load model '" + path + "': " +
                             (error[0] ? std::string(error) : std::string("unknown MuJoCo error")));
  }
  return ModelPtr(m);
}

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

std::string object_name(const mjModel* m, mjtObj type, int id) {
  const char* name = mj_id2name(m, type, id);
  if (name && name[0]) return name;
  return "#" + std::to_string(id);
}

}  // namespace idmpc::mj
