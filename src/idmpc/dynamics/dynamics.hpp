#pragma once
/// @file dynamics.hpp
/// @brief All dynamics algorithms, explicitly instantiated in dynamics.cpp for `double` and for
/// the SIMD `StagePack` with VecX arguments. A file that includes this header links those
/// instantiations instead of compiling the kernels again (explicit instantiation declarations
/// below); calls with other argument types (Eigen expressions, maps) are compiled where they are
/// made, as for any template.

#include "idmpc/dynamics/aba.hpp"
#include "idmpc/dynamics/aba_derivatives.hpp"
#include "idmpc/dynamics/crba.hpp"
#include "idmpc/dynamics/kinematics.hpp"
#include "idmpc/dynamics/ltdl.hpp"
#include "idmpc/dynamics/minv.hpp"
#include "idmpc/dynamics/rnea.hpp"
#include "idmpc/dynamics/rnea_derivatives.hpp"
#include "idmpc/dynamics/rnea_vjp.hpp"
#include "idmpc/spatial/pack.hpp"

/// The instantiations for `double`; KEYWORD is `extern` for the declarations, empty for the
/// definitions in dynamics.cpp (one list for both).
#define IDMPC_DYNAMICS_INSTANTIATIONS_DOUBLE(KEYWORD)                                                          \
  KEYWORD template const VecX<double>& rnea(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&,       \
                                            const Eigen::MatrixBase<VecX<double>>&,                            \
                                            const Eigen::MatrixBase<VecX<double>>&);                           \
  KEYWORD template const VecX<double>& aba(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&,        \
                                           const Eigen::MatrixBase<VecX<double>>&,                             \
                                           const Eigen::MatrixBase<VecX<double>>&);                            \
  KEYWORD template const VecX<double>& minv_apply(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&); \
  KEYWORD template const VecX<double>& rnea_after_aba(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&, \
                                                      const Eigen::MatrixBase<VecX<double>>&);                 \
  KEYWORD template const MatX<double>& crba(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&);      \
  KEYWORD template void ltdl_factor(const Model&, Data&);                                                      \
  KEYWORD template const VecX<double>& ltdl_solve(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&); \
  KEYWORD template void rnea_derivatives(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&,          \
                                         const Eigen::MatrixBase<VecX<double>>&,                               \
                                         const Eigen::MatrixBase<VecX<double>>&);                              \
  KEYWORD template void aba_derivatives_after_aba(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&, \
                                                  const Eigen::MatrixBase<VecX<double>>&);                     \
  KEYWORD template void aba_derivatives(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&,           \
                                        const Eigen::MatrixBase<VecX<double>>&,                                \
                                        const Eigen::MatrixBase<VecX<double>>&);                               \
  KEYWORD template void rnea_vjp(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&);                 \
  KEYWORD template void minv_apply_columns(const Model&, Data&, int);                                          \
  KEYWORD template const MatX<double>& minv_matrix_after_aba(const Model&, Data&);                             \
  KEYWORD template const MatX<double>& minv_matrix(const Model&, Data&, const Eigen::MatrixBase<VecX<double>>&); \
  KEYWORD template struct DataTpl<double>;                                                                     \
  KEYWORD template class FrameKinematics<double>;                                                              \
  KEYWORD template void FrameKinematics<double>::compute(const Model&, const Eigen::MatrixBase<VecX<double>>&);

/// The instantiations for the SIMD `StagePack` (batched horizon stages), as above.
#define IDMPC_DYNAMICS_INSTANTIATIONS_PACK(KEYWORD)                                                            \
  KEYWORD template const VecX<StagePack>& rnea(const Model&, DataTpl<StagePack>&,                              \
                                               const Eigen::MatrixBase<VecX<StagePack>>&,                      \
                                               const Eigen::MatrixBase<VecX<StagePack>>&,                      \
                                               const Eigen::MatrixBase<VecX<StagePack>>&);                     \
  KEYWORD template void rnea_vjp(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<VecX<StagePack>>&); \
  KEYWORD template const VecX<StagePack>& aba(const Model&, DataTpl<StagePack>&,                               \
                                              const Eigen::MatrixBase<VecX<StagePack>>&,                       \
                                              const Eigen::MatrixBase<VecX<StagePack>>&,                       \
                                              const Eigen::MatrixBase<VecX<StagePack>>&);                      \
  KEYWORD template const VecX<StagePack>& minv_apply(const Model&, DataTpl<StagePack>&,                        \
                                                     const Eigen::MatrixBase<VecX<StagePack>>&);               \
  KEYWORD template const VecX<StagePack>& rnea_after_aba(const Model&, DataTpl<StagePack>&,                    \
                                                         const Eigen::MatrixBase<VecX<StagePack>>&,            \
                                                         const Eigen::MatrixBase<VecX<StagePack>>&);           \
  KEYWORD template void rnea_derivatives(const Model&, DataTpl<StagePack>&,                                    \
                                         const Eigen::MatrixBase<VecX<StagePack>>&,                            \
                                         const Eigen::MatrixBase<VecX<StagePack>>&,                            \
                                         const Eigen::MatrixBase<VecX<StagePack>>&);                           \
  KEYWORD template void aba_derivatives_after_aba(const Model&, DataTpl<StagePack>&,                           \
                                                  const Eigen::MatrixBase<VecX<StagePack>>&,                   \
                                                  const Eigen::MatrixBase<VecX<StagePack>>&);                  \
  KEYWORD template struct DataTpl<StagePack>;                                                                  \
  KEYWORD template class FrameKinematics<StagePack>;                                                           \
  KEYWORD template void FrameKinematics<StagePack>::compute(const Model&,                                      \
                                                            const Eigen::MatrixBase<VecX<StagePack>>&);

namespace idmpc {
IDMPC_DYNAMICS_INSTANTIATIONS_DOUBLE(extern)
IDMPC_DYNAMICS_INSTANTIATIONS_PACK(extern)
}  // namespace idmpc
