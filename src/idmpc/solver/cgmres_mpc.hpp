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
    u0_ = cgmres_.solution().head(shooting_.n());
    return r;
  }
  bool update(double t, In q, In v) override {
    if (!cgmres_.update(t, q, v)) return false;
    u0_ = cgmres_.solution().head(shooting_.n());
    return true;
  }
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
  Shooting shooting_;
  Cgmres cgmres_;
  Vec u0_;
};

}  // namespace idmpc
