#include "idmpc/render/run_log.hpp"

#include <filesystem>
#include <stdexcept>
#include <vector>
#include <algorithm>

namespace idmpc::render {

void check_run_log(const RunLog& log, const mjModel* m, const std::string& model_path) {
  const std::string model_name = std::filesystem::path(model_path).filename().string();
  const std::string log_name = std::filesystem::path(log.path).filename().string();
  const int held = static_cast<int>(log.held_joints.size());
  if (log.n + held != m->nq) {
    throw std::invalid_argument("log '" + log_name + "' has " + std::to_string(log.n) + " joints" +
                                (held ? " and " + std::to_string(held) + " held" : std::string()) + " but model '" +
                                model_name + "' has " + std::to_string(m->nq));
  }
  for (const std::string& joint : log.held_joints) {
    if (mj_name2id(m, mjOBJ_JOINT, joint.c_str()) < 0) {
      throw std::invalid_argument("log '" + log_name + "' held joint '" + joint + "', which model '" + model_name +
                                  "' does not have");
    }
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

void log_pose(const RunLog& log, std::size_t row, const mjModel* m, mjtNum* qpos) {
  if (log.held_joints.empty()) {
    std::copy(log.q_row(row), log.q_row(row) + m->nq, qpos);
    return;
  }
  std::vector<bool> held(static_cast<std::size_t>(m->nq), false);
  for (std::size_t k = 0; k < log.held_joints.size(); ++k) {
    const int a = m->jnt_qposadr[mj_name2id(m, mjOBJ_JOINT, log.held_joints[k].c_str())];
    qpos[a] = log.held_q[k];
    held[static_cast<std::size_t>(a)] = true;
  }
  const double* q = log.q_row(row);
  for (int a = 0; a < m->nq; ++a) {
    if (!held[static_cast<std::size_t>(a)]) qpos[a] = *q++;
  }
}

}  // namespace idmpc::render
