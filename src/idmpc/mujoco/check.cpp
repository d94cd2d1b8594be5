#include "idmpc/mujoco/check.hpp"

#include <random>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/reference.hpp"

namespace idmpc::mj {

double relative_error(const MatX<double>& x, const MatX<double>& y) {
  if (x.rows() != y.rows() || x.cols() != y.cols()) return INFINITY;
  const double scale = std::max(y.cwiseAbs().maxCoeff(), 1.0);
  return (x - y).cwiseAbs().maxCoeff() / scale;
}

std::vector<CheckEntry> check_model(const mjModel* m, const Model& model, int samples,
                                    unsigned seed, const CheckTolerances& tol) {
  Reference ref(m);
  Data data(model);
  const int n = model.n;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random = [&](double scale) {
    VecX<double> x(n);
    for (int i = 0; i < n; ++i) x[i] = scale * unit(rng);
    return x;
  };

  std::vector<CheckEntry> entries = {
      {"ID vs mj_inverse", 0, tol.mujoco},
      {"FD vs mj_forward", 0, tol.mujoco},
      {"M (CRBA) vs mj_fullM", 0, tol.mujoco},
      {"rnea(aba(tau)) = tau", 0, tol.adjoint},
      {"M from derivatives vs CRBA", 0, tol.adjoint},
      {"dtau/dq vs central differences of RNEA", 0, tol.derivative},
      {"dtau/dv vs central differences of RNEA", 0, tol.derivative},
      {"dtau/dq vs central differences of mj_inverse", 0, tol.derivative},
      {"da/dq vs central differences of ABA", 0, tol.derivative},
      {"da/dv vs central differences of ABA", 0, tol.derivative},
      {"da/dtau = M^-1 vs central differences of ABA", 0, tol.derivative},
      {"adjoint (dID/dq)^T w vs matrix", 0, tol.adjoint},
      {"adjoint (dID/dv)^T w vs matrix", 0, tol.adjoint},
      {"adjoint M w vs matrix", 0, tol.adjoint},
      {"M^-1 x (ABA sweep) vs matrix", 0, tol.adjoint},
  };
  auto record = [&](size_t k, double err) { entries[k].worst = std::max(entries[k].worst, err); };

  for (int s = 0; s < samples; ++s) {
    const VecX<double> q = model.q_ref + random(3.0), v = random(2.0), a = random(5.0),
                       tau = random(5.0), w = random(1.0);
    // MuJoCo references
    const VecX<double> tau_id = rnea(model, data, q, v, a);
    record(0, relative_error(tau_id, ref.inverse(q, v, a)));
    const VecX<double> qdd = aba(model, data, q, v, tau);
    record(1, relative_error(qdd, ref.forward(q, v, tau)));
    const MatX<double> M = crba(model, data, q);
    record(2, relative_error(M, ref.mass_matrix(q)));
    record(3, relative_error(rnea(model, data, q, v, qdd), tau));

    // RNEA derivatives against finite differences of ours and of MuJoCo's
    rnea_derivatives(model, data, q, v, a);
    const MatX<double> dtau_dq = data.dtau_dq, dtau_dv = data.dtau_dv;
    record(4, relative_error(data.M, M));
    record(5, relative_error(dtau_dq, central_difference_jacobian(
                                          [&](const VecX<double>& x) { return rnea(model, data, x, v, a); }, q)));
    record(6, relative_error(dtau_dv, central_difference_jacobian(
                                          [&](const VecX<double>& x) { return rnea(model, data, q, x, a); }, v)));
    record(7, relative_error(dtau_dq, central_difference_jacobian(
                                          [&](const VecX<double>& x) { return ref.inverse(x, v, a); }, q)));

    // forward-dynamics derivatives
    aba_derivatives(model, data, q, v, tau);
    const MatX<double> da_dq = data.da_dq, da_dv = data.da_dv, Minv = data.Minv;
    record(8, relative_error(da_dq, central_difference_jacobian(
                                        [&](const VecX<double>& x) { return aba(model, data, x, v, tau); }, q)));
    record(9, relative_error(da_dv, central_difference_jacobian(
                                        [&](const VecX<double>& x) { return aba(model, data, q, x, tau); }, v)));
    record(10, relative_error(Minv, central_difference_jacobian(
                                        [&](const VecX<double>& x) { return aba(model, data, q, v, x); }, tau)));

    // adjoints against the matrices they stand for
    rnea(model, data, q, v, a);
    rnea_vjp(model, data, w);
    record(11, relative_error(data.g_q, dtau_dq.transpose() * w));
    record(12, relative_error(data.g_v, dtau_dv.transpose() * w));
    record(13, relative_error(data.g_a, M * w));
    aba(model, data, q, v, tau);
    record(14, relative_error(minv_apply(model, data, w), Minv * w));
  }
  return entries;
}

}  // namespace idmpc::mj
