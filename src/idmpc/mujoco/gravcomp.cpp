#include "idmpc/mujoco/gravcomp.hpp"

#include <mutex>

namespace idmpc::mj {
namespace {

// qfrc_passive += Σ_b J_b(xipos_b)ᵀ (−c_b m_b g): MuJoCo >= 2.3's mj_gravcomp
void add_gravcomp(const mjModel* m, mjData* d) {
  if (m->opt.disableflags & (mjDSBL_GRAVITY | mjDSBL_PASSIVE)) return;
  const int id = mj_name2id(m, mjOBJ_NUMERIC, kGravcompField);
  if (id < 0) return;
  const int adr = m->numeric_adr[id], size = m->numeric_size[id];
  for (int b = 1; b < m->nbody && b < size; ++b) {
    const mjtNum c = m->numeric_data[adr + b];
    if (c == 0 || m->body_mass[b] == 0) continue;
    mjtNum force[3], torque[3] = {0, 0, 0};
    for (int k = 0; k < 3; ++k) force[k] = -c * m->body_mass[b] * m->opt.gravity[k];
    mj_applyFT(m, d, force, torque, d->xipos + 3 * b, b, d->qfrc_passive);
  }
}

}  // namespace

std::vector<double> body_gravcomp(const mjModel* m) {
  std::vector<double> out(static_cast<std::size_t>(m->nbody), 0.0);
  const int id = mj_name2id(m, mjOBJ_NUMERIC, kGravcompField);
  if (id < 0) return out;
  const int adr = m->numeric_adr[id], size = m->numeric_size[id];
  for (int b = 0; b < m->nbody && b < size; ++b) out[static_cast<std::size_t>(b)] = m->numeric_data[adr + b];
  return out;
}

void install_gravcomp_callback() {
  static std::once_flag once;
  std::call_once(once, [] { mjcb_passive = add_gravcomp; });
}

}  // namespace idmpc::mj
