// Compiles every dynamics header once for double, so that template errors surface in the
// library build rather than in each user.
#include "idmpc/dynamics/dynamics.hpp"

namespace idmpc {

using Vd = VecX<double>;
template const Vd& rnea(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                        const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template const Vd& aba(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                       const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template const Vd& minv_apply(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template const MatX<double>& crba(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template void rnea_derivatives(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                               const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template void aba_derivatives(const Model&, Data&, const Eigen::MatrixBase<Vd>&,
                              const Eigen::MatrixBase<Vd>&, const Eigen::MatrixBase<Vd>&);
template void rnea_vjp(const Model&, Data&, const Eigen::MatrixBase<Vd>&);
template struct DataTpl<double>;

}  // namespace idmpc
