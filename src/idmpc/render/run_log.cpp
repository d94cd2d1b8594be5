#include "idmpc/render/run_log.hpp"

#include <filesystem>
#include <stdexcept>

namespace idmpc::render {

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
