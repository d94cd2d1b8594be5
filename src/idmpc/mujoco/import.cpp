#include "idmpc/mujoco/import.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "idmpc/experiment/input_file.hpp"
#include "idmpc/mujoco/gravcomp.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::mj {
namespace {

// smallest |gear| (and |gain·gear|) accepted: below it ctrl = τ/(gain·gear) overflows for any
// torque of interest, and 1e-320 is a denormal
constexpr double kMinGear = 1e-12;

Vec3<double> vec3(const mjtNum* x) { return Vec3<double>(x[0], x[1], x[2]); }

std::string number(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

std::string numbers(const mjtNum* x, int count) {
  std::string out;
  for (int k = 0; k < count; ++k) out += (k ? " " : "") + number(x[k]);
  return out;
}

bool finite(const mjtNum* x, int count) {
  for (int k = 0; k < count; ++k) {
    if (!std::isfinite(x[k])) return false;
  }
  return true;
}

Mat3<double> rotation(const mjtNum* quat) {
  return Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]).normalized().toRotationMatrix();
}

Transform<double> translation(const Vec3<double>& r) {
  Transform<double> X;
  X.r = r;
  return X;
}

// body inertia from mass, centre of mass, principal-axes frame and principal moments
Inertia<double> body_inertia(const mjModel* m, int b) {
  const Mat3<double> R = rotation(m->body_iquat + 4 * b);
  const Mat3<double> I_com = R * vec3(m->body_inertia + 3 * b).asDiagonal() * R.transpose();
  return Inertia<double>::from_com(m->body_mass[b], vec3(m->body_ipos + 3 * b), I_com);
}

std::string joint_label(const mjModel* m, int j) {
  return "joint '" + object_name(m, mjOBJ_JOINT, j) + "' of body '" +
         object_name(m, mjOBJ_BODY, m->jnt_bodyid[j]) + "'";
}

// every number of the model the import, the horizon or the plant's torque limits use must be
// finite: MuJoCo's compiler lets e.g. axis="nan 1 0", mass="nan" or ctrlrange="nan 1" pass (its
// range checks, lower < upper, compare with NaN, which is never true)
void require_finite(const mjModel* m, const std::string& source) {
  auto require = [&](bool ok, const std::string& owner, const char* what, const mjtNum* x, int count) {
    if (!ok) {
      throw std::invalid_argument(owner + " in '" + source + "' has a non-finite " + what + " (" +
                                  numbers(x, count) + "): expected finite numbers");
    }
  };
  for (int j = 0; j < m->njnt; ++j) {
    const std::string owner = joint_label(m, j);
    require(finite(m->jnt_axis + 3 * j, 3), owner, "axis", m->jnt_axis + 3 * j, 3);
    require(finite(m->jnt_pos + 3 * j, 3), owner, "position", m->jnt_pos + 3 * j, 3);
    require(finite(m->jnt_stiffness + j, 1), owner, "stiffness", m->jnt_stiffness + j, 1);
    require(finite(m->jnt_range + 2 * j, 2), owner, "range", m->jnt_range + 2 * j, 2);
    const int a = m->jnt_qposadr[j];
    require(finite(m->qpos0 + a, 1), owner, "reference position", m->qpos0 + a, 1);
    require(finite(m->qpos_spring + a, 1), owner, "spring reference", m->qpos_spring + a, 1);
  }
  for (int i = 0; i < m->nv; ++i) {
    const std::string owner = joint_label(m, m->dof_jntid[i]);
    require(finite(m->dof_armature + i, 1), owner, "armature", m->dof_armature + i, 1);
    require(finite(m->dof_damping + i, 1), owner, "damping", m->dof_damping + i, 1);
    require(finite(m->dof_frictionloss + i, 1), owner, "frictionloss", m->dof_frictionloss + i, 1);
  }
  for (int b = 1; b < m->nbody; ++b) {
    const std::string owner = "body '" + object_name(m, mjOBJ_BODY, b) + "'";
    require(finite(m->body_pos + 3 * b, 3), owner, "position", m->body_pos + 3 * b, 3);
    require(finite(m->body_quat + 4 * b, 4), owner, "orientation", m->body_quat + 4 * b, 4);
    require(finite(m->body_mass + b, 1), owner, "mass (mass, or a geom's density or mass)", m->body_mass + b, 1);
    require(finite(m->body_ipos + 3 * b, 3), owner, "centre of mass", m->body_ipos + 3 * b, 3);
    require(finite(m->body_iquat + 4 * b, 4), owner, "inertia frame", m->body_iquat + 4 * b, 4);
    require(finite(m->body_inertia + 3 * b, 3), owner, "inertia", m->body_inertia + 3 * b, 3);
  }
  for (int u = 0; u < m->nu; ++u) {
    const std::string owner = "actuator '" + object_name(m, mjOBJ_ACTUATOR, u) + "'";
    require(finite(m->actuator_ctrlrange + 2 * u, 2), owner, "ctrlrange", m->actuator_ctrlrange + 2 * u, 2);
    require(finite(m->actuator_forcerange + 2 * u, 2), owner, "forcerange", m->actuator_forcerange + 2 * u, 2);
    require(finite(m->actuator_gear + 6 * u, 6), owner, "gear", m->actuator_gear + 6 * u, 6);
    require(finite(m->actuator_gainprm + mjNGAIN * u, mjNGAIN), owner, "gainprm", m->actuator_gainprm + mjNGAIN * u,
            mjNGAIN);
    require(finite(m->actuator_biasprm + mjNBIAS * u, mjNBIAS), owner, "biasprm", m->actuator_biasprm + mjNBIAS * u,
            mjNBIAS);
  }
  require(finite(m->opt.gravity, 3), "the model", "gravity", m->opt.gravity, 3);
  require(finite(&m->opt.timestep, 1), "the model", "timestep", &m->opt.timestep, 1);
}

// hinge and slide joints only, each one dof
void require_one_dof_joints(const mjModel* m, const std::string& source) {
  for (int j = 0; j < m->njnt; ++j) {
    const int type = m->jnt_type[j];
    if (type == mjJNT_BALL || type == mjJNT_FREE) {
      throw std::invalid_argument(joint_label(m, j) + " in '" + source + "' is a " +
                                  (type == mjJNT_BALL ? "ball" : "free") +
                                  " joint: only hinge and slide joints are supported");
    }
  }
  if (m->nq != m->nv) {
    throw std::invalid_argument("model '" + source + "' has nq = " + std::to_string(m->nq) +
                                " but nv = " + std::to_string(m->nv) + ": expected 1-DoF joints");
  }
}

// the links a model's joints make (one per dof, in MuJoCo's dof order) and where each body sits
// on them; joints of one body compose, jointless bodies are welded to their parent's link
struct LinkTree {
  std::vector<int> parent;                     // per dof: parent link, −1 for the base
  std::vector<Transform<double>> X_tree;       // per dof: parent link frame → link frame at qpos0
  std::vector<int> link_of_body;               // per body: the link it is rigidly attached to
  std::vector<Transform<double>> body_in_link; // per body: that link's frame → body frame
};

LinkTree link_tree(const mjModel* m, const std::string& source) {
  LinkTree tree;
  tree.parent.reserve(m->nv);
  tree.X_tree.reserve(m->nv);
  tree.link_of_body.assign(m->nbody, -1);
  tree.body_in_link.resize(m->nbody);
  for (int b = 1; b < m->nbody; ++b) {
    const int pb = m->body_parentid[b];
    // body placement in its parent's frame: coordinates map by Rᵀ, origin at body_pos
    Transform<double> T_body;
    T_body.E = rotation(m->body_quat + 4 * b).transpose();
    T_body.r = vec3(m->body_pos + 3 * b);
    const Transform<double> pre = T_body * tree.body_in_link[pb];
    int link = tree.link_of_body[pb];
    Vec3<double> prev_anchor = Vec3<double>::Zero();
    for (int k = 0; k < m->body_jntnum[b]; ++k) {
      const int j = m->body_jntadr[b] + k;
      const int i = m->jnt_dofadr[j];
      if (i != static_cast<int>(tree.parent.size())) {
        throw std::invalid_argument("model '" + source + "': dofs are not in body order at " +
                                    joint_label(m, j));
      }
      // link frame: the body frame moved to the joint anchor; joints of one body compose
      const Vec3<double> anchor = vec3(m->jnt_pos + 3 * j);
      tree.X_tree.push_back(k == 0 ? translation(anchor) * pre : translation(anchor - prev_anchor));
      tree.parent.push_back(link);
      link = i;
      prev_anchor = anchor;
    }
    tree.link_of_body[b] = link;
    tree.body_in_link[b] = m->body_jntnum[b] > 0 ? translation(-prev_anchor) : pre;
  }
  return tree;
}

// "'a1', 'a2'" or, for more than three, "'a1'…'a7' (7)"
std::string name_list(const std::vector<std::string>& names) {
  if (names.size() > 3) return "'" + names.front() + "'…'" + names.back() + "' (" + std::to_string(names.size()) + ")";
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out;
}

// mimic joints grouped by the actuated joint each follows: "joint(s) 'a', 'b' follow 'c'; 'd' follows 'e'"
std::string coupled_list(const std::vector<std::pair<std::string, std::string>>& coupled) {
  std::vector<std::pair<std::string, std::vector<std::string>>> by_leader;
  for (const auto& c : coupled) {
    const std::string& leader = c.second;  // (a structured binding cannot be captured in C++17)
    auto it = std::find_if(by_leader.begin(), by_leader.end(), [&leader](const auto& g) { return g.first == leader; });
    if (it == by_leader.end()) it = by_leader.insert(by_leader.end(), {leader, {}});
    it->second.push_back(c.first);
  }
  std::string out = "joint(s) ";
  for (std::size_t k = 0; k < by_leader.size(); ++k) {
    const auto& [leader, joints] = by_leader[k];
    out += (k ? "; " : "") + name_list(joints) + (joints.size() > 1 ? " follow '" : " follows '") + leader + "'";
  }
  return out;
}

// the dofs some actuator drives: joint transmissions directly, the others (tendons, sites, …)
// through their moment arms at qpos0
std::vector<bool> actuated_dofs(const mjModel* m) {
  std::vector<bool> out(m->nv, false);
  bool other = false;
  for (int u = 0; u < m->nu; ++u) {
    const int type = m->actuator_trntype[u];
    if (type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT) {
      out[m->jnt_dofadr[m->actuator_trnid[2 * u]]] = true;
    } else {
      other = true;
    }
  }
  if (other) {
    const DataPtr d = transmission_at(m, m->qpos0);
    for (int u = 0; u < m->nu; ++u) {
      const int type = m->actuator_trntype[u];
      if (type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT) continue;
      for (int i = 0; i < m->nv; ++i) {
        if (d->actuator_moment[static_cast<std::size_t>(u) * m->nv + i] != 0) out[i] = true;
      }
    }
  }
  return out;
}

// the dof of an actuated joint that an active joint equality ties dof i to, or −1
int coupled_actuated_dof(const mjModel* m, int i, const std::vector<bool>& actuated) {
  const int j = m->dof_jntid[i];
  for (int e = 0; e < m->neq; ++e) {
    if (m->eq_type[e] != mjEQ_JOINT || !m->eq_active[e]) continue;
    const int a = m->eq_obj1id[e], b = m->eq_obj2id[e];
    const int other = a == j ? b : (b == j ? a : -1);
    if (other >= 0 && actuated[static_cast<std::size_t>(m->jnt_dofadr[other])]) return m->jnt_dofadr[other];
  }
  return -1;
}

// an actuator the controller can use: a motor (τ → ctrl) or a servo (replaced by τ)
struct JointActuator {
  int actuator = -1;
  bool motor = false;
};

Actuation import_actuation(const mjModel* m, const std::string& source, const ImportOptions& options) {
  Actuation act;
  std::vector<std::pair<int, int>> coupled;  // (dof, the actuated dof it is tied to)
  constexpr double kInf = std::numeric_limits<double>::infinity();
  act.torque_lower = VecX<double>::Constant(m->nv, -kInf);
  act.torque_upper = VecX<double>::Constant(m->nv, kInf);
  auto bound = [&](int dof, double a, double b) {
    act.torque_lower[dof] = std::max(act.torque_lower[dof], std::min(a, b));
    act.torque_upper[dof] = std::min(act.torque_upper[dof], std::max(a, b));
  };
  // joints without an actuator: direct torques drive them only on the user's confirmation;
  // without it the model is under-actuated and those joints stay passive
  auto bare_joints = [&](const std::vector<bool>& actuated, bool confirmed) {
    for (int i = 0; i < m->nv; ++i) {
      if (actuated[i]) continue;
      // a joint an active joint equality ties to an actuated one (a mimic joint, e.g. a second
      // finger) moves with that actuator's effort: driven too, within the same range
      const int leader = coupled_actuated_dof(m, i, actuated);
      if (leader >= 0) {
        act.coupled_joints.emplace_back(object_name(m, mjOBJ_JOINT, m->dof_jntid[i]),
                                        object_name(m, mjOBJ_JOINT, m->dof_jntid[leader]));
        coupled.emplace_back(i, leader);
      } else if (confirmed) {
        act.unactuated_joints.push_back(object_name(m, mjOBJ_JOINT, m->dof_jntid[i]));
      } else {
        act.passive_dofs.push_back(i);
      }
    }
  };
  // the file's own joint torque ranges, and what is left unbounded
  auto finish = [&] {
    for (const auto& [dof, leader] : coupled) bound(dof, act.torque_lower[leader], act.torque_upper[leader]);
    for (int j = 0; j < m->njnt; ++j) {
      if (static_cast<std::size_t>(j) < options.joint_force_lower.size() &&
          static_cast<std::size_t>(j) < options.joint_force_upper.size()) {
        // ±infinity where the file declares none
        const double lo = options.joint_force_lower[j], hi = options.joint_force_upper[j];
        if (!(lo <= hi)) {
          throw std::invalid_argument(joint_label(m, j) + " in '" + source + "' has actuatorfrcrange (" + number(lo) +
                                      " " + number(hi) + "): expected numbers, lower <= upper");
        }
        bound(m->jnt_dofadr[j], lo, hi);
      }
    }
    for (int i : act.passive_dofs) {
      act.torque_lower[i] = -kInf;
      act.torque_upper[i] = kInf;
    }
    for (int i = 0; i < m->nv; ++i) {
      if (act.passive(i)) continue;
      if (std::isinf(act.torque_lower[i]) || std::isinf(act.torque_upper[i])) {
        act.unbounded_joints.push_back(object_name(m, mjOBJ_JOINT, m->dof_jntid[i]));
      }
    }
    return act;
  };
  if (m->nu == 0) return finish();
  // a zero, denormal or non-finite gear is a broken number whatever drives the joints
  for (int u = 0; u < m->nu; ++u) {
    const double gear = m->actuator_gear[6 * u];
    if (!std::isfinite(gear) || std::abs(gear) < kMinGear) {
      throw std::invalid_argument("actuator '" + object_name(m, mjOBJ_ACTUATOR, u) + "' in '" + source +
                                  "' has gear " + number(gear) + ": expected a finite gear with |gear| >= " +
                                  number(kMinGear));
    }
  }
  if (options.direct_torque) {
    bare_joints(actuated_dofs(m), options.actuate_every_joint);
    return finish();
  }

  const std::string hint = " in '" + source +
                           "': only motors and servos on joints are supported (or use --direct-torque to "
                           "apply joint torques directly)";
  std::vector<JointActuator> of_dof(m->nv);
  std::vector<bool> actuated(m->nv, false);
  bool servos = false;
  for (int u = 0; u < m->nu; ++u) {
    const std::string name = "actuator '" + object_name(m, mjOBJ_ACTUATOR, u) + "'";
    const int type = m->actuator_trntype[u];
    if (type != mjTRN_JOINT && type != mjTRN_JOINTINPARENT) {
      throw std::invalid_argument(name + " does not act on a joint" + hint);
    }
    const int bias = m->actuator_biastype[u];
    if (m->actuator_gaintype[u] != mjGAIN_FIXED || (bias != mjBIAS_NONE && bias != mjBIAS_AFFINE)) {
      throw std::invalid_argument(name + " is neither a motor nor a servo (a muscle, or a user-defined gain or bias)" +
                                  hint);
    }
    const bool motor = m->actuator_dyntype[u] == mjDYN_NONE && bias == mjBIAS_NONE;
    // torque = gain·gear·ctrl: a zero, denormal or non-finite factor makes ctrl = τ/(gain·gear)
    // meaningless
    const double gear = m->actuator_gear[6 * u], gain = m->actuator_gainprm[u * mjNGAIN] * gear;
    if (motor && (!std::isfinite(gain) || std::abs(gain) < kMinGear)) {
      throw std::invalid_argument(name + " in '" + source + "' has gain×gear " + number(gain) +
                                  ": expected a finite product with |gain×gear| >= " + number(kMinGear));
    }
    const int dof = m->jnt_dofadr[m->actuator_trnid[2 * u]];
    if (actuated[dof]) {
      throw std::invalid_argument(name + " drives " + joint_label(m, m->actuator_trnid[2 * u]) +
                                  " which already has an actuator in '" + source +
                                  "': expected exactly one motor or servo per joint");
    }
    actuated[dof] = true;
    of_dof[dof] = JointActuator{u, motor};
    servos = servos || !motor;
    // the torque range: a motor's control range through gain and gear, any force range through
    // the gear (a servo's control range is a position or velocity, no torque)
    if (motor && m->actuator_ctrllimited[u]) {
      bound(dof, gain * m->actuator_ctrlrange[2 * u], gain * m->actuator_ctrlrange[2 * u + 1]);
    }
    if (m->actuator_forcelimited[u]) {
      bound(dof, gear * m->actuator_forcerange[2 * u], gear * m->actuator_forcerange[2 * u + 1]);
    } else if (!motor && m->actuator_ctrllimited[u]) {
      // a servo without a force range: the force it gives at rest, gain·ctrl + b0 + b1·q, over
      // its control range and its joint's range (the control range again where the joint has
      // none: a position servo's targets), times the gear
      const mjtNum* g = m->actuator_gainprm + u * mjNGAIN;
      const mjtNum* b = m->actuator_biasprm + u * mjNBIAS;
      const int joint = m->actuator_trnid[2 * u];
      const double c[2] = {m->actuator_ctrlrange[2 * u], m->actuator_ctrlrange[2 * u + 1]};
      const bool ranged = m->jnt_limited[joint];
      const double q[2] = {ranged ? m->jnt_range[2 * joint] : c[0], ranged ? m->jnt_range[2 * joint + 1] : c[1]};
      double lo = kInf, hi = -kInf;
      for (const double ci : c) {
        for (const double qi : q) {
          const double force = g[0] * ci + b[0] + b[1] * qi;
          lo = std::min(lo, force);
          hi = std::max(hi, force);
        }
      }
      if (std::isfinite(lo) && std::isfinite(hi) && hi > lo) {
        bound(dof, gear * lo, gear * hi);
        act.derived_limits.push_back(object_name(m, mjOBJ_ACTUATOR, u));
      }
    }
  }
  if (servos) {
    act.direct = true;
    for (int u = 0; u < m->nu; ++u) {
      const int dof = m->jnt_dofadr[m->actuator_trnid[2 * u]];
      if (!of_dof[dof].motor) act.replaced_servos.push_back(object_name(m, mjOBJ_ACTUATOR, u));
    }
    bare_joints(actuated, options.actuate_every_joint);
    return finish();
  }
  // motors: a joint without one is passive (a mimic joint follows its leader's motor)
  bare_joints(actuated, false);
  if (!act.coupled_joints.empty()) {
    throw std::invalid_argument("model '" + source + "': " + coupled_list(act.coupled_joints) +
                                ": no motor of their own, but a joint equality ties them to a motor's joint: use "
                                "--direct-torque to drive them with direct torques");
  }
  act.direct = false;
  act.actuator_of_dof.assign(m->nv, -1);
  act.ctrl_per_torque.assign(m->nv, 0.0);
  for (int i = 0; i < m->nv; ++i) {
    const int u = of_dof[i].actuator;
    if (u < 0) continue;
    act.actuator_of_dof[i] = u;
    act.ctrl_per_torque[i] = 1.0 / (m->actuator_gainprm[u * mjNGAIN] * m->actuator_gear[6 * u]);
  }
  return finish();
}

// what the import changed in how the model is driven, for the user
std::vector<std::string> actuation_notices(const mjModel* m, const Actuation& act) {
  std::vector<std::string> out;
  if (!act.replaced_servos.empty()) {
    std::vector<std::string> limited, unlimited;
    bool position = false, velocity = false;
    for (const std::string& name : act.replaced_servos) {
      const int u = actuator_id(m, name);
      const mjtNum* b = m->actuator_biasprm + (u >= 0 ? u : 0) * mjNBIAS;
      position = position || b[1] != 0;
      velocity = velocity || (b[1] == 0 && b[2] != 0);
      const bool derived = std::find(act.derived_limits.begin(), act.derived_limits.end(), name) != act.derived_limits.end();
      if (u >= 0 && m->actuator_forcelimited[u]) {
        limited.push_back(name);
      } else if (!derived) {
        unlimited.push_back(name);
      }
    }
    const std::string kind = position && velocity ? "position and velocity servos"
                             : position          ? "position servos"
                             : velocity          ? "velocity servos"
                                                 : "servos";
    std::string line = kind + " " + name_list(act.replaced_servos) +
                       " replaced by joint torques (applied directly; the plant disables the actuators)";
    if (!limited.empty()) line += ", limited by the forcerange × gear of " + name_list(limited);
    if (!act.derived_limits.empty()) {
      line += "; " + name_list(act.derived_limits) +
              " declare no forcerange: limited by the force they give at rest over their control and joint ranges";
    }
    if (!unlimited.empty()) line += "; " + name_list(unlimited) + " declare no forcerange nor a control range";
    out.push_back(line);
  }
  if (!act.coupled_joints.empty()) {
    out.push_back(coupled_list(act.coupled_joints) +
                  ": no actuator of their own, but an active joint equality: driven by direct torques too, within "
                  "that joint's range");
  }
  if (!act.unactuated_joints.empty()) {
    out.push_back("joint(s) " + name_list(act.unactuated_joints) +
                  " have no actuator in the model and are driven by direct torques, as confirmed");
  }
  if (!act.passive_dofs.empty()) {
    std::vector<std::string> names;
    for (int i : act.passive_dofs) names.push_back(object_name(m, mjOBJ_JOINT, m->dof_jntid[i]));
    out.push_back("under-actuated: joint(s) " + name_list(names) +
                  " have no actuator (their torque stays zero; --actuate-every-joint with --direct-torque would drive "
                  "them)");
  }
  return out;
}

std::vector<std::string> unmodeled_features(const mjModel* m) {
  std::vector<std::string> out;
  const bool contacts_on = !(m->opt.disableflags & (mjDSBL_CONTACT | mjDSBL_CONSTRAINT));
  int colliding = 0;
  for (int g = 0; g < m->ngeom; ++g) colliding += (m->geom_contype[g] || m->geom_conaffinity[g]);
  if (contacts_on && colliding > 1) {
    out.push_back("contacts (" + std::to_string(colliding) + " colliding geoms)");
  }
  // one line for all joint ranges (a 7-dof arm has seven), the joints named
  std::vector<std::string> limited;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_limited[j]) limited.push_back(object_name(m, mjOBJ_JOINT, j));
  }
  if (!limited.empty()) {
    out.push_back("range limits on joint(s) " + name_list(limited));
  }
  // friction loss: smooth in the horizon of both formulations; what it is not (stiction) is left
  // to the disturbance observer
  std::vector<std::string> rubbing;
  for (int i = 0; i < m->nv; ++i) {
    if (m->dof_frictionloss[i] > 0) rubbing.push_back(object_name(m, mjOBJ_JOINT, m->dof_jntid[i]));
  }
  if (!rubbing.empty()) {
    out.push_back("friction loss on " + std::to_string(rubbing.size()) + " joint(s) (" + name_list(rubbing) +
                  ") as a constraint with stiction (the horizon has it as smooth friction)");
  }
  if (m->ntendon > 0) out.push_back(std::to_string(m->ntendon) + " tendon(s)");
  // an equality between two bodies of one rigid body (a held gripper's closed linkage, welded)
  // does nothing
  int equalities = 0;
  for (int e = 0; e < m->neq; ++e) {
    const bool bodies = m->eq_type[e] == mjEQ_CONNECT || m->eq_type[e] == mjEQ_WELD;
    equalities += !(bodies && m->body_weldid[m->eq_obj1id[e]] == m->body_weldid[std::max(m->eq_obj2id[e], 0)]);
  }
  if (equalities > 0) out.push_back(std::to_string(equalities) + " equality constraint(s)");
  if (m->opt.density > 0 || m->opt.viscosity > 0) out.push_back("fluid forces (density/viscosity)");
  return out;
}

}  // namespace

std::string Actuation::summary() const {
  std::string out;
  if (!replaced_servos.empty()) {
    out = "servos " + name_list(replaced_servos) + " replaced by joint torques applied directly (qfrc_applied)";
  } else if (direct) {
    out = "joint torques applied directly (qfrc_applied)";
  } else {
    out = passive_dofs.empty() ? "one motor actuator per joint" : "one motor actuator per actuated joint";
  }
  if (!unactuated_joints.empty()) out += "; joints without an actuator driven too: " + name_list(unactuated_joints);
  if (!passive_dofs.empty()) {
    out += "; under-actuated, " + std::to_string(passive_dofs.size()) + " joint(s) without an actuator";
  }
  if (unbounded_joints.empty()) {
    out += "; every joint's torque is bounded";
  } else {
    out += "; no torque limit declared for joint(s) " + name_list(unbounded_joints);
  }
  return out;
}

ImportedModel import_model(const mjModel* m, const std::string& source, const ImportOptions& options) {
  require_one_dof_joints(m, source);
  if (m->nv == 0) throw std::invalid_argument("model '" + source + "' has no joints");
  require_finite(m, source);

  // one link per dof, in MuJoCo's dof order
  const LinkTree tree = link_tree(m, source);
  std::vector<Link> links(m->nv);
  const bool passive = !(m->opt.disableflags & mjDSBL_PASSIVE);
  for (int j = 0; j < m->njnt; ++j) {
    const int i = m->jnt_dofadr[j];
    Link& l = links[i];
    l.X_tree = tree.X_tree[i];
    l.parent = tree.parent[i];
    l.joint_type = m->jnt_type[j] == mjJNT_HINGE ? JointType::kRevolute : JointType::kPrismatic;
    l.axis = vec3(m->jnt_axis + 3 * j).normalized();
    l.joint_name = object_name(m, mjOBJ_JOINT, j);
    l.q_ref = m->qpos0[m->jnt_qposadr[j]];
    l.armature = m->dof_armature[i];
    l.damping = passive ? m->dof_damping[i] : 0.0;
    l.stiffness = passive ? m->jnt_stiffness[j] : 0.0;
    l.q_spring = m->qpos_spring[m->jnt_qposadr[j]];
  }
  // welded bodies merge into the link they hang from; those on the base carry nothing. The
  // compensated part of each, gravcomp·inertia, merges alike (a passive force: none without them)
  const std::vector<double> gravcomp = body_gravcomp(m);
  for (int b = 1; b < m->nbody; ++b) {
    const int link = tree.link_of_body[b];
    if (link < 0) continue;
    const Inertia<double> I = body_inertia(m, b).transformed_to_parent(tree.body_in_link[b]);
    links[link].I += I;
    const double c = passive ? gravcomp[static_cast<std::size_t>(b)] : 0.0;
    if (c != 0) links[link].I_gravcomp += Inertia<double>{c * I.m, c * I.h, c * I.Ibar};
  }
  const Vec3<double> gravity = (m->opt.disableflags & mjDSBL_GRAVITY) ? Vec3<double>::Zero()
                                                                      : vec3(m->opt.gravity);
  Actuation actuation = import_actuation(m, source, options);
  for (int i : actuation.passive_dofs) links[static_cast<std::size_t>(i)].actuated = false;
  ImportedModel out{Model(links, gravity, source), std::move(actuation), {}, {}};
  out.unmodeled = unmodeled_features(m);
  out.notices = actuation_notices(m, out.actuation);
  return out;
}

Frame import_frame(const mjModel* m, const std::string& name, const std::string& source) {
  require_one_dof_joints(m, source);
  require_finite(m, source);
  // MuJoCo matches the text up to a NUL byte, and "" names every unnamed site and body
  if (name.empty()) {
    throw std::invalid_argument("model '" + source + "': expected a site or body name, got an empty name");
  }
  if (name.find('\0') != std::string::npos) {
    throw std::invalid_argument("model '" + source + "': expected a site or body name, got '" +
                                abbreviate(name.substr(0, name.find('\0'))) + "' followed by a NUL byte");
  }
  const int site = mj_name2id(m, mjOBJ_SITE, name.c_str());
  const int body = site >= 0 ? m->site_bodyid[site] : mj_name2id(m, mjOBJ_BODY, name.c_str());
  if (body < 0) {
    std::string sites;
    for (int s = 0; s < m->nsite; ++s) {
      const char* site_name = mj_id2name(m, mjOBJ_SITE, s);
      if (site_name && site_name[0]) sites += (sites.empty() ? "" : ", ") + std::string(site_name);
    }
    throw std::invalid_argument("model '" + source + "' has no site or body '" + abbreviate(name) + "' (" +
                                (sites.empty() ? std::string("it has no named sites") : "sites: " + abbreviate(sites, 200)) +
                                ")");
  }
  const LinkTree tree = link_tree(m, source);
  Frame frame;
  frame.link = tree.link_of_body[body];
  frame.placement = tree.body_in_link[body];
  if (site < 0) {
    frame.name = "body '" + abbreviate(name) + "'";
    return frame;
  }
  frame.name = "site '" + abbreviate(name) + "'";
  if (!finite(m->site_pos + 3 * site, 3) || !finite(m->site_quat + 4 * site, 4)) {
    throw std::invalid_argument(frame.name + " in '" + source + "' has a non-finite placement (pos " +
                                numbers(m->site_pos + 3 * site, 3) + ", quat " + numbers(m->site_quat + 4 * site, 4) +
                                "): expected finite numbers");
  }
  // site placement in its body's frame, as a body's in its parent's
  Transform<double> T_site;
  T_site.E = rotation(m->site_quat + 4 * site).transpose();
  T_site.r = vec3(m->site_pos + 3 * site);
  frame.placement = T_site * frame.placement;
  return frame;
}

VecX<double> keyframe_qpos(const mjModel* m, const std::string& name, const std::string& source) {
  const int k = mj_name2id(m, mjOBJ_KEY, name.c_str());
  if (k < 0) {
    throw std::invalid_argument("model '" + source + "' has no keyframe '" + name +
                                "' (q0 \"" + name + "\" needs one; give q0 as joint values instead)");
  }
  const VecX<double> q = Eigen::Map<const VecX<double>>(m->key_qpos + static_cast<size_t>(k) * m->nq, m->nq);
  if (!q.allFinite()) {
    throw std::invalid_argument("keyframe '" + name + "' in '" + source + "' has a non-finite qpos (" +
                                numbers(q.data(), static_cast<int>(q.size())) + "): expected finite numbers");
  }
  return q;
}

std::vector<std::string> range_violations(const mjModel* m, const VecX<double>& q, const std::string& what) {
  std::vector<std::string> out;
  for (int j = 0; j < m->njnt && j < q.size(); ++j) {
    const int i = m->jnt_qposadr[j];
    const double lo = m->jnt_range[2 * j], hi = m->jnt_range[2 * j + 1];
    if (m->jnt_limited[j] && (q[i] < lo || q[i] > hi)) {
      std::ostringstream o;
      o << what << " of " << joint_label(m, j) << " is " << q[i] << ", outside its range [" << lo << ", " << hi
        << "]";
      out.push_back(o.str());
    }
  }
  return out;
}

}  // namespace idmpc::mj
