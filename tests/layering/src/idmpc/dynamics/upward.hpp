#pragma once
// four violations, one per kind, and three allowed includes
#include <vector>                      // allowed: standard library
#include "idmpc/model/model.hpp"       // allowed: a lower layer
#include "idmpc/dynamics/rnea.hpp"     // allowed: the same layer
#include "idmpc/ocp/ocp.hpp"           // violation: a higher layer
#include <mujoco/mujoco.h>             // violation: MuJoCo below mujoco/
#include "app/commands.hpp"            // violation: the app from the core
#include "../solver/cgmres.hpp"        // violation: a relative include out of the layer
