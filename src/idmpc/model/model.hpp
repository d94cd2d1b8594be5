#pragma once
/// @file model.hpp
/// @brief Immutable kinematic tree of 1-DoF joints (one link per dof), in topological order.

#include <string>
#include <vector>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

enum class JointType { kRevolute, kPrismatic };

/// @brief One link and the 1-DoF joint that moves it: what a Model is built from.
///
/// The link's frame has its origin on the joint axis; X_tree maps the parent link's frame to
/// this link's frame at zero joint displacement; the joint then rotates about (or slides along)
/// `axis` through that origin by q − q_ref. The motion subspace is S = [axis; 0] for a revolute
/// and [0; axis] for a prismatic joint (angular-first).
struct Link {
  int parent = -1;                            ///< an earlier link, or −1 for the fixed base
  JointType joint_type = JointType::kRevolute;
  Vec3<double> axis = Vec3<double>::UnitZ();  ///< unit joint axis in the link frame
  Transform<double> X_tree;                   ///< parent link frame → link frame at q = q_ref
  Inertia<double> I;                          ///< link inertia (welded bodies merged)
  /// the part of I whose weight gravity compensation carries, Σ c_b·I_b over the link's bodies
  /// with gravcomp c_b (MuJoCo's body gravcomp): an upward force c_b·m_b·g at each body's centre
  /// of mass. Only its mass and first moment act. Zero: no compensation.
  Inertia<double> I_gravcomp;
  double q_ref = 0;                           ///< joint reference (MuJoCo qpos0)
  double armature = 0;                        ///< added to diag(M)
  double damping = 0;                         ///< passive −d·v
  double stiffness = 0;                       ///< passive −k·(q − q_spring)
  double q_spring = 0;
  double friction = 0;                        ///< friction loss f ≥ 0: passive −f·tanh(v/ε)
  double friction_velocity = 0;               ///< ε > 0 of the smooth friction (if f > 0)
  bool actuated = true;                       ///< whether an actuator drives the joint
  std::string joint_name;                     ///< for messages
};

/// @brief The rigid-body model the controllers use: built once from its links, checked, and
/// const from then on (every member is const). Link i carries joint i; parent[i] < i, −1 for
/// the fixed base. Any topological order is valid (depth-first is not required).
///
/// The members are the links' fields as arrays, read directly by the algorithms' inner loops,
/// plus derived fields (axis_index, run_start, the depth-first preorder), made once here.
class Model {
 public:
  /// @brief Checks and stores the tree. Throws std::invalid_argument naming the link for: no
  /// link; a parent that is not an earlier link or −1; an axis that is not a unit vector; a
  /// placement whose rotation is not orthonormal; a negative mass; a non-finite number.
  /// @param links    link i carries joint i, in topological order
  /// @param world_gravity  gravity vector (zero if disabled)
  /// @param model_name     for messages, e.g. the source file
  Model(const std::vector<Link>& links, const Vec3<double>& world_gravity,
        std::string model_name = {});

  const int n;                                 ///< number of links = dofs
  const std::vector<int> parent;               ///< size n, −1 for the base
  const std::vector<JointType> joint_type;     ///< size n
  const std::vector<Vec3<double>> axis;        ///< unit joint axis in the link frame; with
                                               ///< joint_type, the motion subspace S (joint.hpp)
  const std::vector<Transform<double>> X_tree; ///< parent link frame → link frame at q = q_ref
  const std::vector<Inertia<double>> I;        ///< link inertia (welded bodies merged)
  const std::vector<Inertia<double>> I_gravcomp;  ///< the compensated part of I (Link::I_gravcomp)
  const VecX<double> q_ref;                    ///< joint reference (MuJoCo qpos0)
  const VecX<double> armature;                 ///< added to diag(M)
  const VecX<double> damping;                  ///< passive −d·v
  const VecX<double> stiffness;                ///< passive −k·(q − q_spring)
  const VecX<double> q_spring;
  const VecX<double> friction;                 ///< friction loss f: passive −f·tanh(v/ε)
  const VecX<double> friction_velocity;        ///< ε of the smooth friction (joint.hpp)
  const Vec3<double> gravity;                  ///< world gravity (zero if disabled)
  /// some link's weight is (partly) compensated and gravity is not zero: the algorithms then
  /// take I_gravcomp·X_{i,0}g off each link's body force (formulations.md §Gravity compensation)
  const bool gravcomp;
  /// the joints an actuator drives and those none does (under-actuation), increasing; the
  /// actuators' torques u (size actuated_joints.size()) reach the joints as τ = Sᵀu, S the
  /// selection of the actuated rows
  const std::vector<int> actuated_joints, unactuated_joints;
  const std::vector<std::string> joint_names;  ///< for messages
  const std::string name;

  /// derived: k ∈ {0, 1, 2} if axis[i] = ±e_k (the joint transform's fast path), else −1
  const std::vector<int> axis_index;
  /// derived: the first link of the unbranched run of consecutive links that ends at i, the
  /// smallest r ≤ i with parent[t] = t − 1 for every t in (r, i]. The ancestors of i are then
  /// the runs [run_start[j], j] for j = parent[i], then parent[run_start[j]], …: contiguous
  /// index ranges (one on a chain), which sparse algorithms sweep as contiguous memory.
  const std::vector<int> run_start;
  /// derived: a depth-first preorder of the links (children in index order): preorder[t] is
  /// the link at position t, preorder_index[i] the position of link i, and the subtree of link
  /// i (i and its descendants) occupies the subtree_size[i] consecutive positions from
  /// preorder_index[i]. On depth-first models (MuJoCo's order) the preorder is the identity.
  const std::vector<int> preorder, preorder_index, subtree_size;

  /// @brief Link i as given to the constructor (to rebuild a variant of this model).
  Link link(int i) const;
  /// @brief Number of actuated joints, n_u ≤ n.
  int n_actuated() const { return static_cast<int>(actuated_joints.size()); }
  bool under_actuated() const { return !unactuated_joints.empty(); }
};

/// @brief The model whose forward dynamics integrate joint damping implicitly over a step dt:
/// armature + dt·damping. With it, explicit Euler v⁺ = v + dt·q̈ of the FD dynamics
/// q̈ = (M + dt·D)⁻¹(τ − c − D v) satisfies M (v⁺ − v)/dt = τ − c − D v⁺ (the damping at the
/// end of the step, as MuJoCo's Euler integrator does), stable for any dt; its inverse
/// dynamics are τ = M q̈ + c + D v⁺. Throws std::invalid_argument for dt < 0 or non-finite.
Model with_implicit_damping(const Model& model, double dt);

/// @brief The model with joint friction f·tanh(v/ε) (formulations.md §Passive forces): MuJoCo's friction loss, a
/// dry-friction constraint force of magnitude ≤ f, made smooth for the horizon. `friction` and
/// `velocity` have size n; ε must be positive where f is. Throws std::invalid_argument
/// otherwise, naming the joint.
Model with_joint_friction(const Model& model, const VecX<double>& friction, const VecX<double>& velocity);

}  // namespace idmpc
