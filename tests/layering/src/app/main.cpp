#include <mujoco/mujoco.h>               // allowed: the app may include anything below it
#include "idmpc/render/video.hpp"        // allowed
