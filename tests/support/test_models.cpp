#include "support/test_models.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#ifndef IDMPC_SOURCE_DIR
#error "IDMPC_SOURCE_DIR must be defined (the project's source directory)"
#endif

namespace idmpc::test {

std::vector<std::string> shipped_model_paths() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(IDMPC_SOURCE_DIR) / "mjcf";
  if (!fs::is_directory(dir)) {
    throw std::runtime_error("model directory '" + dir.string() + "' does not exist");
  }
  std::vector<std::string> paths;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    // hidden files are a generator's temporaries
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && entry.path().extension() == ".xml" && name[0] != '.') {
      paths.push_back(entry.path().string());
    }
  }
  if (paths.empty()) {
    throw std::runtime_error("model directory '" + dir.string() + "' holds no *.xml file");
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

}  // namespace idmpc::test
