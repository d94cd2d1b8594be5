#include "idmpc/mujoco/import.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <vector>

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

// every number the import reads must be finite: MuJoCo's compiler lets e.g. axis="nan 1 0" pass
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
    const int a = m->jnt_qposadr[j];
    require(finite(m->qpos0 + a, 1), owner, "reference position", m->qpos0 + a, 1);
    require(finite(m->qpos_spring + a, 1), owner, "spring reference", m->qpos_spring + a, 1);
  }
  for (int i = 0; i < m->nv; ++i) {
    const std::string owner = joint_label(m, m->dof_jntid[i]);
    require(finite(m->dof_armature + i, 1), owner, "armature", m->dof_armature + i, 1);
    require(finite(m->dof_damping + i, 1), owner, "damping", m->dof_damping + i, 1);
  }
  for (int b = 1; b < m->nbody; ++b) {
    const std::string owner = "body '" + object_name(m, mjOBJ_BODY, b) + "'";
    require(finite(m->body_pos + 3 * b, 3), owner, "position", m->body_pos + 3 * b, 3);
    require(finite(m->body_quat + 4 * b, 4), owner, "orientation", m->body_quat + 4 * b, 4);
    require(finite(m->body_mass + b, 1), owner, "mass", m->body_mass + b, 1);
    require(finite(m->body_ipos + 3 * b, 3), owner, "centre of mass", m->body_ipos + 3 * b, 3);
    require(finite(m->body_iquat + 4 * b, 4), owner, "inertia frame", m->body_iquat + 4 * b, 4);
    require(finite(m->body_inertia + 3 * b, 3), owner, "inertia", m->body_inertia + 3 * b, 3);
  }
  require(finite(m->opt.gravity, 3), "the model", "gravity", m->opt.gravity, 3);
}

Actuation import_actuation(const mjModel* m, const std::string& source, const ImportOptions& options) {
  Actuation act;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  act.torque_lower = VecX<double>::Constant(m->nv, -kInf);
  act.torque_upper = VecX<double>::Constant(m->nv, kInf);
  if (options.direct_torque || m->nu == 0) return act;
  act.direct = false;
  act.actuator_of_dof.assign(m->nv, -1);
  act.ctrl_per_torque.assign(m->nv, 0.0);
  for (int u = 0; u < m->nu; ++u) {
    const std::string name = "actuator '" + object_name(m, mjOBJ_ACTUATOR, u) + "'";
    const std::string hint = " in '" + source +
                             "': only motor actuators on joints are supported (or use "
                             "--direct-torque to apply joint torques directly)";
    if (m->actuator_trntype[u] != mjTRN_JOINT) {
      throw std::invalid_argument(name + " does not act on a joint" + hint);
    }
    const bool motor = m->actuator_dyntype[u] == mjDYN_NONE &&
                       m->actuator_gaintype[u] == mjGAIN_FIXED &&
                       m->actuator_biastype[u] == mjBIAS_NONE;
    if (!motor) {
      throw std::invalid_argument(name + " is not a motor (it has activation dynamics, a "
                                         "non-fixed gain or a bias such as a position servo)" +
                                  hint);
    }
    // torque = gain·gear·ctrl: a zero, denormal or non-finite factor makes ctrl = τ/(gain·gear)
    // meaningless
    const double gear = m->actuator_gear[6 * u], gain = m->actuator_gainprm[u * mjNGAIN] * gear;
    if (!std::isfinite(gear) || std::abs(gear) < kMinGear) {
      throw std::invalid_argument(name + " in '" + source + "' has gear " + number(gear) +
                                  ": expected a finite gear with |gear| >= " + number(kMinGear));
    }
    if (!std::isfinite(gain) || std::abs(gain) < kMinGear) {
      throw std::invalid_argument(name + " in '" + source + "' has gain×gear " + number(gain) +
                                  ": expected a finite product with |gain×gear| >= " + number(kMinGear));
    }
    const int dof = m->jnt_dofadr[m->actuator_trnid[2 * u]];
    if (act.actuator_of_dof[dof] >= 0) {
      throw std::invalid_argument(name + " drives " +
                                  joint_label(m, m->actuator_trnid[2 * u]) +
                                  " which already has an actuator in '" + source +
                                  "': expected exactly one motor per joint");
    }
    act.actuator_of_dof[dof] = u;
    act.ctrl_per_torque[dof] = 1.0 / gain;
    // the torque range: control range through gain and gear, force range through the gear
    auto bound = [&](double a, double b) {
      act.torque_lower[dof] = std::max(act.torque_lower[dof], std::min(a, b));
      act.torque_upper[dof] = std::min(act.torque_upper[dof], std::max(a, b));
    };
    if (m->actuator_ctrllimited[u]) bound(gain * m->actuator_ctrlrange[2 * u], gain * m->actuator_ctrlrange[2 * u + 1]);
    if (m->actuator_forcelimited[u]) {
      bound(gear * m->actuator_forcerange[2 * u], gear * m->actuator_forcerange[2 * u + 1]);
    }
  }
  for (int i = 0; i < m->nv; ++i) {
    if (act.actuator_of_dof[i] < 0) {
      throw std::invalid_argument("model '" + source + "' is under-actuated: " +
                                  joint_label(m, m->dof_jntid[i]) +
                                  " has no motor actuator (expected one motor per joint, or no "
                                  "actuators at all, or --direct-torque)");
    }
  }
  return act;
}

std::vector<std::string> unmodeled_features(const mjModel* m) {
  std::vector<std::string> out;
  const bool contacts_on = !(m->opt.disableflags & (mjDSBL_CONTACT | mjDSBL_CONSTRAINT));
  int colliding = 0;
  for (int g = 0; g < m->ngeom; ++g) colliding += (m->geom_contype[g] || m->geom_conaffinity[g]);
  if (contacts_on && colliding > 1) {
    out.push_back("contacts (" + std::to_string(colliding) + " colliding geoms)");
  }
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_limited[j]) out.push_back("limit on " + joint_label(m, j));
  }
  for (int i = 0; i < m->nv; ++i) {
    if (m->dof_frictionloss[i] > 0) out.push_back("friction loss on " + joint_label(m, m->dof_jntid[i]));
  }
  if (m->ntendon > 0) out.push_back(std::to_string(m->ntendon) + " tendon(s)");
  if (m->neq > 0) out.push_back(std::to_string(m->neq) + " equality constraint(s)");
  if (m->opt.density > 0 || m->opt.viscosity > 0) out.push_back("fluid forces (density/viscosity)");
  return out;
}

}  // namespace

ImportedModel import_model(const mjModel* m, const std::string& source, const ImportOptions& options) {
  // joints: hinge and slide only, each one dof
  for (int j = 0; j < m->njnt; ++j) {
    const int type = m->jnt_type[j];
    if (type == mjJNT_BALL || type == mjJNT_FREE) {
      throw std::invalid_argument(joint_label(m, j) + " in '" + source + "' is a " +
                                  (type == mjJNT_BALL ? "ball" : "free") +
                                  " joint: only hinge and slide joints are supported");
    }
  }
  if (m->nv == 0) throw std::invalid_argument("model '" + source + "' has no joints");
  require_finite(m, source);
  if (m->nq != m->nv) {
    throw std::invalid_argument("model '" + source + "' has nq = " + std::to_string(m->nq) +
                                " but nv = " + std::to_string(m->nv) + ": expected 1-DoF joints");
  }

  // one link per dof, in MuJoCo's dof order
  std::vector<Link> links;
  links.reserve(m->nv);

  // per body: the link its frame is rigidly attached to and that link's frame → body frame
  std::vector<int> link_of_body(m->nbody, -1);
  std::vector<Transform<double>> body_in_link(m->nbody);
  const bool passive = !(m->opt.disableflags & mjDSBL_PASSIVE);
  for (int b = 1; b < m->nbody; ++b) {
    const int pb = m->body_parentid[b];
    // body placement in its parent's frame: coordinates map by Rᵀ, origin at body_pos
    Transform<double> T_body;
    T_body.E = rotation(m->body_quat + 4 * b).transpose();
    T_body.r = vec3(m->body_pos + 3 * b);
    Transform<double> pre = T_body * body_in_link[pb];
    int link = link_of_body[pb];
    Vec3<double> prev_anchor = Vec3<double>::Zero();
    for (int k = 0; k < m->body_jntnum[b]; ++k) {
      const int j = m->body_jntadr[b] + k;
      const int i = m->jnt_dofadr[j];
      if (i != static_cast<int>(links.size())) {
        throw std::invalid_argument("model '" + source + "': dofs are not in body order at " +
                                    joint_label(m, j));
      }
      // link frame: the body frame moved to the joint anchor; joints of one body compose
      const Vec3<double> anchor = vec3(m->jnt_pos + 3 * j);
      Link& l = links.emplace_back();
      l.X_tree = k == 0 ? translation(anchor) * pre : translation(anchor - prev_anchor);
      l.parent = link;
      l.joint_type = m->jnt_type[j] == mjJNT_HINGE ? JointType::kRevolute : JointType::kPrismatic;
      l.axis = vec3(m->jnt_axis + 3 * j).normalized();
      l.joint_name = object_name(m, mjOBJ_JOINT, j);
      l.q_ref = m->qpos0[m->jnt_qposadr[j]];
      l.armature = m->dof_armature[i];
      l.damping = passive ? m->dof_damping[i] : 0.0;
      l.stiffness = passive ? m->jnt_stiffness[j] : 0.0;
      l.q_spring = m->qpos_spring[m->jnt_qposadr[j]];
      link = i;
      prev_anchor = anchor;
    }
    link_of_body[b] = link;
    body_in_link[b] = m->body_jntnum[b] > 0 ? translation(-prev_anchor) : pre;
    // welded bodies merge into the link they hang from; those on the base carry nothing
    if (link >= 0) links[link].I += body_inertia(m, b).transformed_to_parent(body_in_link[b]);
  }
  const Vec3<double> gravity = (m->opt.disableflags & mjDSBL_GRAVITY) ? Vec3<double>::Zero()
                                                                      : vec3(m->opt.gravity);
  ImportedModel out{Model(links, gravity, source), import_actuation(m, source, options), {}};
  out.unmodeled = unmodeled_features(m);
  return out;
}

VecX<double> keyframe_qpos(const mjModel* m, const std::string& name, const std::string& source) {
  const int k = mj_name2id(m, mjOBJ_KEY, name.c_str());
  if (k < 0) {
    throw std::invalid_argument("model '" + source + "' has no keyframe '" + name +
                                "' (q0 \"" + name + "\" needs one; give q0 as joint values instead)");
  }
  return Eigen::Map<const VecX<double>>(m->key_qpos + static_cast<size_t>(k) * m->nq, m->nq);
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
