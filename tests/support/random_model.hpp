#pragma once
/// @file random_model.hpp
/// @brief Seeded random kinematic trees (MJCF text) for the MuJoCo comparison tests.

#include <string>

namespace idmpc::test {

/// @brief Size and actuation of a random tree.
struct RandomTreeOptions {
  int min_dofs = 2;            ///< fewest dofs (>= 1)
  int max_dofs = 12;           ///< most dofs (>= min_dofs)
  bool with_actuators = true;  ///< one motor per dof (random gear in [0.5, 3]) or none at all
  /// every joint axis ±e_k (the drawn axis's largest component, with its sign), for the joint
  /// kernels' axis-aligned paths; the same draws as without
  bool aligned_axes = false;
  /// MuJoCo >= 2.3's body gravcomp on some bodies (about half: 1 now and then, else in
  /// (0, 1.5)), drawn from a stream of its own, so that the tree is the one drawn without it
  bool gravcomp = false;
};

/// @brief MJCF text of a random fixed-base kinematic tree, identical for a given seed on every
/// platform and standard library (std::mt19937 with our own uniform helpers).
///
/// The tree draws from every feature of mjcf/tree.xml: branches, random unit joint axes, slide
/// joints, welded (jointless, massive) bodies both as leaves and between jointed bodies, bodies
/// with two joints, joint anchors off the body origin, random body quaternions, explicit
/// rotated inertial frames (masses 0.2-3 kg, principal moments of a box with sides 0.1-0.8 m so
/// they satisfy the triangle inequality), armature, damping, stiffness with springref, and joint
/// ref (qpos0 != 0), each joint property drawn with some probability. Guaranteed once the size
/// allows: a body with two joints (>= 2 dofs); a slide joint (>= 3 dofs); a welded leaf (always);
/// with at least two jointed bodies, a welded body between two jointed bodies and a branch
/// point; with at least three jointed bodies, a branch point between jointed bodies. All joints
/// are 1-dof hinges or slides without limits; contacts are disabled; default gravity; timestep
/// 0.001. Now and then a second jointed body hangs from the world (several roots).
/// @throws std::invalid_argument if min_dofs < 1 or max_dofs < min_dofs.
std::string random_tree_mjcf(unsigned seed, const RandomTreeOptions& options = {});

}  // namespace idmpc::test
