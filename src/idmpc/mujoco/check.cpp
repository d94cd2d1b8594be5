#include "idmpc/mujoco/check.hpp"

#include <random>
#include <stdexcept>

#include "idmpc/dynamics/dynamics.hpp"
#include "idmpc/dynamics/finite_difference.hpp"
#include "idmpc/mujoco/reference.hpp"

namespace idmpc::mj {

double relative_error(const MatX<double>& x, const MatX<double>& y) {
  if (x.rows() != y.rows() || x.cols() != y.cols()) return INFINITY;
  // Eigen's maxCoeff may skip NaNs
  if (!x.allFinite() || !y.allFinite()) return NAN;
  const double scale = std::max(y.cwiseAbs().maxCoeff(), 1.0);
  return (x - y).cwiseAbs().maxCoeff() / scale;
}

namespace {

bool has_fluid_forces(const mjModel* m) { return m->opt.density > 0 || m->opt.viscosity > 0; }

bool has_tendon_springs(const mjModel* m) {
  for (int t = 0; t < m->ntendon; ++t) {
    if (m->tendon_stiffness[t] != 0 || m->tendon_damping[t] != 0) return true;
  }
  return false;
}

// a copy of m without the passive forces the controller does not model
ModelPtr as_modeled(const mjModel* m) {
  install_error_handlers();
  ModelPtr copy(mj_copyModel(nullptr, m));
  if (!copy) throw std::runtime_error("MuJoCo could not copy the model");
  copy->opt.density = 0;
  copy->opt.viscosity = 0;
  for (int t = 0; t < copy->ntendon; ++t) {
    copy->tendon_stiffness[t] = 0;
    copy->tendon_damping[t] = 0;
  }
  return copy;
}

// vectors of n values uniform in [−scale, scale], drawn from one seeded generator
class RandomStates {
 public:
  RandomStates(int n, unsigned seed) : n_(n), rng_(seed) {}
  VecX<double> operator()(double scale) {
    VecX<double> x(n_);
    for (int i = 0; i < n_; ++i) x[i] = scale * unit_(rng_);
    return x;
  }

 private:
  int n_;
  std::mt19937 rng_;
  std::uniform_real_distribution<double> unit_{-1.0, 1.0};
};

}  // namespace

std::vector<std::string> reference_simplifications(const mjModel* m) {
  std::vector<std::string> out;
  if (has_fluid_forces(m)) out.emplace_back("fluid forces (density/viscosity)");
  if (has_tendon_springs(m)) out.emplace_back("tendon springs and dampers");
  return out;
}

std::vector<CheckEntry> check_model(const mjModel* m, const Model& model, int samples,
                                    unsigned seed, const CheckTolerances& tol) {
  const ModelPtr reference_model = as_modeled(m);
  Reference ref(reference_model.get());
  Data data(model);
  const int n = model.n;
  RandomStates random(n, seed);

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
      {"M^-1 x (sparse LTDL of CRBA) vs mj_solveM", 0, tol.mujoco},
  };
  auto record = [&](size_t k, double err) { entries[k].record(err); };

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
    crba(model, data, q);
    ltdl_factor(model, data);
    record(15, relative_error(ltdl_solve(model, data, w), ref.solve_mass(q, w)));
  }
  return entries;
}

std::vector<CheckEntry> check_held(const mjModel* full, const HeldJoints& held, const Model& model, int samples,
                                   unsigned seed, const CheckTolerances& tol) {
  const ModelPtr reference_model = as_modeled(full);
  Reference ref(reference_model.get());
  Data data(model);
  const int n = model.n;
  if (static_cast<int>(held.dof_of.size()) != n) {
    throw std::invalid_argument("check_held: the model has " + std::to_string(n) + " dofs, the held model " +
                                std::to_string(held.dof_of.size()));
  }
  RandomStates random(n, seed);
  // the held joints where held, at rest
  auto embed = [&](const VecX<double>& x) {
    VecX<double> out = VecX<double>::Zero(full->nv);
    for (int i = 0; i < n; ++i) out[held.dof_of[static_cast<std::size_t>(i)]] = x[i];
    return out;
  };
  std::vector<CheckEntry> entries = {
      {"ID vs mj_inverse, held joints at rest", 0, tol.mujoco},
      {"M vs mj_fullM rows, held joints at rest", 0, tol.mujoco},
  };
  for (int s = 0; s < samples; ++s) {
    const VecX<double> q = model.q_ref + random(3.0), v = random(2.0), a = random(5.0);
    const VecX<double> q_full = held.full_q(q);
    entries[0].record(relative_error(rnea(model, data, q, v, a), held.controlled(ref.inverse(q_full, embed(v), embed(a)))));
    const MatX<double> M_full = ref.mass_matrix(q_full);
    MatX<double> M_rows(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) M_rows(i, j) = M_full(held.dof_of[static_cast<std::size_t>(i)], held.dof_of[static_cast<std::size_t>(j)]);
    }
    entries[1].record(relative_error(crba(model, data, q), M_rows));
  }
  return entries;
}

}  // namespace idmpc::mj
