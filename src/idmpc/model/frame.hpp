#pragma once
/// @file frame.hpp
/// @brief A frame rigidly attached to a link of a Model (a MuJoCo site or body: end effector,
/// flange, tool point), whose placement FrameKinematics (dynamics/kinematics.hpp) computes.

#include <string>

#include "idmpc/model/model.hpp"

namespace idmpc {

/// @brief A frame rigidly attached to a link: a MuJoCo site or body.
struct Frame {
  std::string name;             ///< for messages, e.g. "site 'tip'"
  int link = -1;                ///< the link it moves with; −1: fixed to the base
  Transform<double> placement;  ///< link frame → this frame (the base frame for link −1)
};

/// @brief Checks that `frame` can be attached to `model`: link in [−1, n), a finite placement
/// with an orthonormal rotation. Throws std::invalid_argument naming the frame and the model.
void check_frame(const Model& model, const Frame& frame);

}  // namespace idmpc
