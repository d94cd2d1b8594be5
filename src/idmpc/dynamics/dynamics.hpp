#pragma once
/// @file dynamics.hpp
/// @brief All dynamics algorithms; explicitly instantiated for double in dynamics.cpp.

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/aba_derivatives.hpp"
#include "idmpc/dynamics/crba.hpp"
#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/dynamics/ltdl.hpp"
#include "idmpc/dynamics/minv.hpp"
#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/dynamics/rnea_derivatives.hpp"
#include "idmpc/dynamics/rnea_vjp.hpp"
