// Compiles every dynamics header once for double, so that template errors surface in the
// library build rather than in each user.
#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/spatial/pack.hpp"

namespace idmpc {

using Vd = VecX<double>;
template const Vd& rnea(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                        const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template const Vd& aba(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                       const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template const Vd& minv_apply(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template const Vd& rnea_after_aba(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                                  const Eigen::MatrixBase<Vd>&);
template const MatX<double>& crba(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template void ltdl_factor(const Model&, Data&);
template const Vd& ltdl_solve(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template void rnea_derivatives(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                               const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template void aba_derivatives_after_aba(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                                        const Eigen::MatrixBase<Vd>&);
template void aba_derivatives(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                              const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template void rnea_vjp(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template void minv_apply_columns(const Model&, Data&, int);
template const MatX<double>& minv_matrix_after_aba(const Model&, Data&);
template const MatX<double>& minv_matrix(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template struct DataTpl<double>;
template class FrameKinematics<double>;
template void FrameKinematics<double>::compute(const Model&, const Eigen::MatrixBase<Vd>&);

}  // namespace idmpc

// the SIMD-pack instantiation used for batched horizon stages
namespace idmpc {
using Vp = VecX<StagePack>;
template const Vp& rnea(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&,
                        const Eigen::MatrixBase<Vp>&, const Eigen::MatrixBase<Vp>&);
template void rnea_vjp(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&);
template const Vp& aba(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&,
                       const Eigen::MatrixBase<Vp>&, const Eigen::MatrixBase<Vp>&);
template const Vp& minv_apply(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&);
template const Vp& rnea_after_aba(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&,
                                  const Eigen::MatrixBase<Vp>&);
template void rnea_derivatives(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&,
                               const Eigen::MatrixBase<Vp>&, const Eigen::MatrixBase<Vp>&);
template void aba_derivatives_after_aba(const Model&, DataTpl<StagePack>&, const Eigen::MatrixBase<Vp>&,
                                        const Eigen::MatrixBase<Vp>&);
template class FrameKinematics<StagePack>;
template void FrameKinematics<StagePack>::compute(const Model&, const Eigen::MatrixBase<Vp>&);
}  // namespace idmpc
