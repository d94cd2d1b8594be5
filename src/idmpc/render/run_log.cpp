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
  // the summary beside the log names the model it ran on (summaries before model_hash do not)
  if (!log.model_hash.empty()) {
    const std::string hash = file_hash(model_path);
    if (hash != log.model_hash) {
      throw std::invalid_argument("log '" + log_name + "' was run on model '" + log.summary_model +
                                  "' (its summary '" + log.summary_path + "' says so), not on model '" +
                                  model_path + "': the model files differ (" + log.model_hash + " vs " +
                                  (hash.empty() ? "no regular file" : hash) + ")");
    }
  }
}

}  // namespace idmpc::render
