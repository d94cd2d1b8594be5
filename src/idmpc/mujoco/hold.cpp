#include "idmpc/mujoco/hold.hpp"

#include "idmpc/mujoco/import.hpp"

#include <algorithm>
#include <set>
#include <sstream>
#include <stdexcept>

namespace idmpc::mj {
namespace {

bool joint_transmission(const mjModel* m, int u) {
  const int type = m->actuator_trntype[u];
  return type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT;
}

// the joints of body b and its ancestors
std::set<int> joints_above(const mjModel* m, int b) {
  std::set<int> out;
  for (; b > 0; b = m->body_parentid[b]) {
    for (int k = 0; k < m->body_jntnum[b]; ++k) out.insert(m->body_jntadr[b] + k);
  }
  return out;
}

// the joints a fixed tendon sums
std::vector<int> tendon_joints(const mjModel* m, int t) {
  std::vector<int> out;
  for (int w = m->tendon_adr[t]; w < m->tendon_adr[t] + m->tendon_num[t]; ++w) {
    if (m->wrap_type[w] == mjWRAP_JOINT) out.push_back(m->wrap_objid[w]);
  }
  return out;
}

// fixed tendons over held joints only: the weld removes them (mjcf_translate.cpp does the same
// in the text)
bool removed_tendon(const mjModel* m, int t, const std::vector<bool>& held) {
  const std::vector<int> joints = tendon_joints(m, t);
  if (joints.empty() || static_cast<int>(joints.size()) != m->tendon_num[t]) return false;
  return std::all_of(joints.begin(), joints.end(), [&](int j) { return held[static_cast<std::size_t>(j)]; });
}

std::string number(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

}  // namespace

VecX<double> HeldJoints::full_q(const VecX<double>& q_controller) const {
  VecX<double> full(static_cast<Eigen::Index>(dof_of.size() + joints.size()));
  full.setZero();
  for (std::size_t k = 0; k < dof_of.size(); ++k) full[dof_of[k]] = q_controller[static_cast<Eigen::Index>(k)];
  for (std::size_t k = 0; k < qpos_of.size(); ++k) full[qpos_of[k]] = q[static_cast<Eigen::Index>(k)];
  return full;
}

VecX<double> HeldJoints::controlled(const VecX<double>& full) const {
  VecX<double> out(static_cast<Eigen::Index>(dof_of.size()));
  for (std::size_t k = 0; k < dof_of.size(); ++k) out[static_cast<Eigen::Index>(k)] = full[dof_of[k]];
  return out;
}

std::string HeldJoints::notice(const mjModel* full) const {
  std::string joints_text, actuators_text;
  for (std::size_t k = 0; k < names.size(); ++k) {
    joints_text += (k ? ", '" : "'") + names[k] + "' at " + number(q[static_cast<Eigen::Index>(k)]);
  }
  for (std::size_t k = 0; k < actuators.size(); ++k) {
    actuators_text += (k ? ", '" : "'") + object_name(full, mjOBJ_ACTUATOR, actuators[k]) + "' (ctrl " +
                      number(ctrl[static_cast<Eigen::Index>(k)] + 0.0) + ")";
  }
  return "joint(s) " + joints_text + " held by " + (actuators.empty() ? std::string("no actuator") : actuators_text) +
         ": welded in the controller's model, their weight carried by the link that holds them";
}

std::vector<int> joints_to_hold(const mjModel* m, const std::string& source) {
  std::vector<bool> own(m->njnt, false);  // joints with an actuator of their own
  for (int u = 0; u < m->nu; ++u) {
    if (joint_transmission(m, u)) own[static_cast<std::size_t>(m->actuator_trnid[2 * u])] = true;
  }
  // joints the arm carries: some joint above them has an actuator of its own
  std::vector<bool> carried(m->njnt, false);
  for (int j = 0; j < m->njnt; ++j) {
    for (int b = m->body_parentid[m->jnt_bodyid[j]]; b > 0 && !carried[static_cast<std::size_t>(j)]; b = m->body_parentid[b]) {
      for (int k = 0; k < m->body_jntnum[b]; ++k) {
        if (own[static_cast<std::size_t>(m->body_jntadr[b] + k)]) carried[static_cast<std::size_t>(j)] = true;
      }
    }
  }
  std::vector<bool> held(m->njnt, false);
  bool any_other = false;
  for (int u = 0; u < m->nu; ++u) any_other = any_other || !joint_transmission(m, u);
  if (any_other) {
    // the joints each other actuator moves at qpos0
    const DataPtr d = transmission_at(m, m->qpos0);
    for (int u = 0; u < m->nu; ++u) {
      if (joint_transmission(m, u)) continue;
      std::vector<int> moved;
      for (int i = 0; i < m->nv; ++i) {
        if (d->actuator_moment[static_cast<std::size_t>(u) * m->nv + i] != 0) moved.push_back(m->dof_jntid[i]);
      }
      // a gripper's actuator moves joints the arm carries, none with an actuator of its own;
      // import_model says what it cannot drive of any other
      const bool gripper = std::all_of(moved.begin(), moved.end(), [&](int j) {
        return !own[static_cast<std::size_t>(j)] && carried[static_cast<std::size_t>(j)];
      });
      if (!gripper) continue;
      for (int j : moved) held[static_cast<std::size_t>(j)] = true;
    }
  }
  // joints without an actuator that an active equality ties to held ones
  auto tie = [&](const std::set<int>& joints) {
    const bool touches = std::any_of(joints.begin(), joints.end(), [&](int j) { return held[static_cast<std::size_t>(j)]; });
    bool grew = false;
    if (!touches) return grew;
    for (int j : joints) {
      if (!own[static_cast<std::size_t>(j)] && carried[static_cast<std::size_t>(j)] && !held[static_cast<std::size_t>(j)]) {
        held[static_cast<std::size_t>(j)] = true;
        grew = true;
      }
    }
    return grew;
  };
  for (bool grew = true; grew;) {
    grew = false;
    for (int e = 0; e < m->neq; ++e) {
      if (!m->eq_active[e]) continue;
      const int a = m->eq_obj1id[e], b = m->eq_obj2id[e];
      std::set<int> joints;
      if (m->eq_type[e] == mjEQ_JOINT) {
        joints.insert(a);
        if (b >= 0) joints.insert(b);
      } else if (m->eq_type[e] == mjEQ_CONNECT || m->eq_type[e] == mjEQ_WELD) {
        // the joints between the two bodies
        const std::set<int> above_a = joints_above(m, a), above_b = joints_above(m, b >= 0 ? b : 0);
        std::set_symmetric_difference(above_a.begin(), above_a.end(), above_b.begin(), above_b.end(),
                                      std::inserter(joints, joints.end()));
      } else if (m->eq_type[e] == mjEQ_TENDON) {
        for (const int t : {a, b}) {
          if (t < 0) continue;
          for (int j : tendon_joints(m, t)) joints.insert(j);
        }
      }
      grew = tie(joints) || grew;
    }
  }
  std::vector<int> out;
  for (int j = 0; j < m->njnt; ++j) {
    if (held[static_cast<std::size_t>(j)]) out.push_back(j);
  }
  // a held joint carries held joints only: the controller's model welds it
  for (int j = 0; j < m->njnt; ++j) {
    if (held[static_cast<std::size_t>(j)]) continue;
    for (int b = m->body_parentid[m->jnt_bodyid[j]]; b > 0; b = m->body_parentid[b]) {
      for (int k = 0; k < m->body_jntnum[b]; ++k) {
        const int above = m->body_jntadr[b] + k;
        if (held[static_cast<std::size_t>(above)]) {
          throw std::invalid_argument("model '" + source + "': joint '" + object_name(m, mjOBJ_JOINT, above) +
                                      "' is moved through a tendon or an equality constraint, not by an actuator of its "
                                      "own, and carries joint '" + object_name(m, mjOBJ_JOINT, j) +
                                      "': idmpc holds such joints, which must carry held joints only (e.g. a "
                                      "gripper's fingers)");
        }
      }
    }
    // a body's joints are held all or none
    const int b = m->jnt_bodyid[j];
    for (int k = 0; k < m->body_jntnum[b]; ++k) {
      if (held[static_cast<std::size_t>(m->body_jntadr[b] + k)]) {
        throw std::invalid_argument("model '" + source + "': body '" + object_name(m, mjOBJ_BODY, b) +
                                    "' has held and driven joints ('" + object_name(m, mjOBJ_JOINT, j) +
                                    "' has an actuator): expected a body's joints all held or none");
      }
    }
  }
  return out;
}

HeldJoints hold_joints(const mjModel* m, const std::vector<int>& joints, const VecX<double>& qpos) {
  HeldJoints h;
  h.joints = joints;
  std::vector<bool> held(m->njnt, false);
  for (int j : joints) held[static_cast<std::size_t>(j)] = true;
  h.q.resize(static_cast<Eigen::Index>(joints.size()));
  for (std::size_t k = 0; k < joints.size(); ++k) {
    h.names.push_back(object_name(m, mjOBJ_JOINT, joints[k]));
    h.qpos_of.push_back(m->jnt_qposadr[joints[k]]);
    h.q[static_cast<Eigen::Index>(k)] = qpos[h.qpos_of.back()];
  }
  for (int i = 0; i < m->nv; ++i) {
    if (!held[static_cast<std::size_t>(m->dof_jntid[i])]) h.dof_of.push_back(i);
  }
  // the actuator lengths with the arm where qpos has it and the fingers at rest
  const DataPtr d = transmission_at(m, qpos.data());
  std::vector<double> ctrl;
  for (int u = 0; u < m->nu; ++u) {
    const int id = m->actuator_trnid[2 * u];
    const bool on_held = joint_transmission(m, u) ? held[static_cast<std::size_t>(id)]
                                                  : m->actuator_trntype[u] == mjTRN_TENDON && removed_tendon(m, id, held);
    if (!on_held) {
      h.actuator_of.push_back(u);
      continue;
    }
    // the control at which the actuator's force is zero at the held length: a servo's target
    // (gain·ctrl + b0 + b1·length = 0); 0 for an actuator without a position bias
    const mjtNum* g = m->actuator_gainprm + u * mjNGAIN;
    const mjtNum* b = m->actuator_biasprm + u * mjNBIAS;
    double c = 0;
    if (m->actuator_biastype[u] == mjBIAS_AFFINE && g[0] != 0 && b[1] != 0) {
      c = -(b[0] + b[1] * d->actuator_length[u]) / g[0];
    }
    if (m->actuator_ctrllimited[u]) c = std::clamp(c, m->actuator_ctrlrange[2 * u], m->actuator_ctrlrange[2 * u + 1]);
    h.actuators.push_back(u);
    ctrl.push_back(c);
  }
  h.ctrl = Eigen::Map<const VecX<double>>(ctrl.data(), static_cast<Eigen::Index>(ctrl.size()));
  return h;
}

LoadedModel load_held_model(const std::string& path, const mjModel* full, const HeldJoints& held) {
  Weld weld;
  weld.joints = held.joints;
  std::set<int> bodies;
  for (int j : held.joints) bodies.insert(full->jnt_bodyid[j]);
  for (const int b : bodies) {
    // MuJoCo's kinematics (mj_kinematics) of the body's joints at their held values, in the
    // parent's frame
    Weld::Body placed;
    placed.body = b;
    mju_copy3(placed.pos, full->body_pos + 3 * b);
    mju_copy4(placed.quat, full->body_quat + 4 * b);
    for (int j = full->body_jntadr[b]; j < full->body_jntadr[b] + full->body_jntnum[b]; ++j) {
      const int a = full->jnt_qposadr[j];
      const auto k = std::find(held.joints.begin(), held.joints.end(), j) - held.joints.begin();
      const double delta = held.q[k] - full->qpos0[a];
      const mjtNum* axis = full->jnt_axis + 3 * j;
      if (full->jnt_type[j] == mjJNT_SLIDE) {
        mjtNum moved[3];
        mju_rotVecQuat(moved, axis, placed.quat);
        mju_addToScl3(placed.pos, moved, delta);
      } else {
        // about the anchor: pos + R·anchor − R·Rj·anchor
        mjtNum turn[4], quat[4], before[3], after[3];
        mju_axisAngle2Quat(turn, axis, delta);
        mju_mulQuat(quat, placed.quat, turn);
        mju_rotVecQuat(before, full->jnt_pos + 3 * j, placed.quat);
        mju_rotVecQuat(after, full->jnt_pos + 3 * j, quat);
        mju_addTo3(placed.pos, before);
        mju_subFrom3(placed.pos, after);
        mju_copy4(placed.quat, quat);
      }
    }
    weld.bodies.push_back(placed);
  }
  LoadedModel out = load_model_translated(path, &weld);
  const mjModel* m = out.model.get();
  if (m->nv != static_cast<int>(held.dof_of.size()) || m->nu != static_cast<int>(held.actuator_of.size())) {
    throw std::runtime_error("model '" + path + "' with its held joints welded has " + std::to_string(m->nv) +
                             " dofs and " + std::to_string(m->nu) + " actuators, expected " +
                             std::to_string(held.dof_of.size()) + " and " + std::to_string(held.actuator_of.size()));
  }
  return out;
}

ControllerModel load_controller_model(const std::string& path, const std::string& keyframe, bool hold) {
  ControllerModel out;
  out.full = load_model_translated(path);
  const mjModel* m = out.full.model.get();
  if (!hold) return out;
  const std::vector<int> joints = joints_to_hold(m, path);
  if (joints.empty()) return out;
  const VecX<double> qpos = keyframe.empty() ? VecX<double>(Eigen::Map<const VecX<double>>(m->qpos0, m->nq))
                                             : keyframe_qpos(m, keyframe, path);
  out.held = hold_joints(m, joints, qpos);
  out.welded = load_held_model(path, m, out.held);
  return out;
}

}  // namespace idmpc::mj
