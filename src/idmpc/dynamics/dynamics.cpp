// The dynamics kernels compiled once, for double and for the SIMD StagePack of the batched
// horizon stages: template errors surface in the library build, and users of dynamics.hpp link
// these instead of compiling the kernels again (the list is in dynamics.hpp).
#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {
IDMPC_DYNAMICS_INSTANTIATIONS_DOUBLE()
IDMPC_DYNAMICS_INSTANTIATIONS_PACK()
}  // namespace idmpc
