#pragma once
/// @file gravcomp.hpp
/// @brief MuJoCo >= 2.3's gravity compensation (body `gravcomp`) on this build's MuJoCo 2.2.
///
/// A body with gravcomp c receives the force −c·m·g at its centre of mass, a passive force
/// (MuJoCo >= 2.3's qfrc_gravcomp, part of qfrc_passive; none when gravity or passive forces are
/// disabled). The translation (mjcf_translate.hpp) keeps each body's c in the compiled model as
/// the custom numeric field kGravcompField (one number per body, by body index), so that copies
/// of the model keep it; MuJoCo 2.2's passive-force callback then applies the force, inside
/// every mj_forward, mj_inverse and mj_step, at the positions of that very evaluation.

#include <vector>

#include <mujoco/mujoco.h>

namespace idmpc::mj {

/// name of the custom numeric field that holds each body's gravcomp
inline constexpr const char* kGravcompField = "idmpc.gravcomp";

/// @brief Each body's gravcomp (size nbody, zeros if the model has none).
std::vector<double> body_gravcomp(const mjModel* m);

/// @brief Sets MuJoCo's passive-force callback (mjcb_passive) to add the gravity compensation
/// of models that carry kGravcompField. Idempotent, thread-safe; models without the field are
/// untouched. Called by install_error_handlers (load.hpp), so every model idmpc loads has it.
void install_gravcomp_callback();

}  // namespace idmpc::mj
