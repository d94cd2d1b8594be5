#pragma once
/// @file cgmres_mpc.hpp
/// @brief C/GMRES as the Controller drives it (mpc_solver.hpp): the shooting residual of the
/// problem and the continuation over it, owned together (Cgmres keeps a reference to its
/// Shooting, so neither moves).

#include "idmpc/solver/cgmres.hpp"
#include "idmpc/solver/mpc_solver.hpp"

namespace idmpc {

class CgmresMpc final : public MpcSolver {
 public:
  CgmresMpc(OcpProblem problem, const CgmresSettings& settings)
      : shooting_(std::move(problem)), cgmres_(shooting_, settings), u0_(Vec::Zero(shooting_.n())) {}
  CgmresMpc(const CgmresMpc&) = delete;
  CgmresMpc& operator=(const CgmresMpc&) = delete;

  SolverKind kind() const override { return SolverKind::kCgmres; }
  OcpProblem& problem() override { return shooting_.problem(); }
  const OcpProblem& problem() const override { return shooting_.problem(); }
  double dt() const override { return cgmres_.settings().dt; }
  double initialize(double t, In q, In v) override {
    const double r = cgmres_.initialize(t, q, v);
    set_first_input();
    return r;
  }
  bool update(double t, In q, In v) override {
    if (!cgmres_.update(t, q, v)) return false;
    set_first_input();
    return true;
  }
  /// @brief Stage 0's input as joint values: FD the joint torques, ID the accelerations (size n).
  const Vec& first_input() const override { return u0_; }
  const std::string& failure() const override { return cgmres_.failure(); }
  double residual_norm() const override { return cgmres_.residual_norm(); }
  double constraint_violation() const override { return cgmres_.constraint_violation(); }
  int evaluations() const override { return cgmres_.evaluations(); }
  const UpdateTimes& last_times() const override { return cgmres_.last_times(); }
  void enable_timing(bool on) override { cgmres_.enable_timing(on); }
  void set_interrupt_check(std::function<void()> check) override { cgmres_.set_interrupt_check(std::move(check)); }

  Shooting& shooting() { return shooting_; }
  const Shooting& shooting() const { return shooting_; }
  Cgmres& cgmres() { return cgmres_; }
  const Cgmres& cgmres() const { return cgmres_; }

 private:
  // stage 0's input, as joint values (FD under-actuated: the passive joints' torques zero)
  void set_first_input() {
    const OcpProblem& p = shooting_.problem();
    const int ni = p.input_dim();
    if (ni == shooting_.n()) {
      u0_ = cgmres_.solution().head(ni);
      return;
    }
    u0_.setZero();
    for (int k = 0; k < ni; ++k) u0_[p.input_joints()[static_cast<std::size_t>(k)]] = cgmres_.solution()[k];
  }

  Shooting shooting_;
  Cgmres cgmres_;
  Vec u0_;
};

}  // namespace idmpc
