// Each stage's workspace holds what its formulation and derivative mode use: no derivative
// matrices in adjoint mode, none per stage when the stages run in lanes (ID), and never a full
// dynamics Data. Results kept between the calls of an evaluation are read only under its token.
#include <gtest/gtest.h>

#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "idmpc/solver/shooting.hpp"
#include "support/problems.hpp"

namespace idmpc {
namespace {

using test::load_problem;
using test::paper_weights;

// heap bytes one more stage adds to a problem's workspaces
std::size_t bytes_per_stage(const Model& model, Formulation f, DerivativeMode mode, bool lanes) {
  const int n = model.n;
  OcpProblem one(model, f, mode, paper_weights(n), VecX<double>::Zero(n), 1);
  OcpProblem two(model, f, mode, paper_weights(n), VecX<double>::Zero(n), 2);
  one.set_stages_in_lanes(lanes);
  two.set_stages_in_lanes(lanes);
  return two.workspace_bytes() - one.workspace_bytes();
}

// what a stage held when each owned a full Data: its buffers, the Data itself, and the
// products of the lanes (n × N, three of them)
std::size_t full_data_per_stage(const Model& model) {
  return heap_bytes(Data(model)) + sizeof(Data) + 3 * static_cast<std::size_t>(model.n) * sizeof(double);
}

TEST(StageWorkspace, HoldsWhatItsFormulationAndModeUse) {
  const Model small = load_problem(IDMPC_SOURCE_DIR "/mjcf/chain8.xml").model;
  const Model large = load_problem(IDMPC_SOURCE_DIR "/mjcf/chain32.xml").model;
  ASSERT_EQ(large.n, 4 * small.n);
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
      for (bool lanes : {true, false}) {
        const std::string name = to_string(f) + "_" + to_string(mode) + (lanes ? "_lanes" : "_scalar");
        SCOPED_TRACE(name);
        const std::size_t s = bytes_per_stage(small, f, mode, lanes), l = bytes_per_stage(large, f, mode, lanes);
        std::cout << name << ": " << s << " B per stage at n = " << small.n << " (full Data "
                  << full_data_per_stage(small) << "), " << l << " B at n = " << large.n << " (full Data "
                  << full_data_per_stage(large) << ")\n";
        EXPECT_LT(l, full_data_per_stage(large));
        // O(n): four times the joints, at most four times the bytes (a Data's own size is the
        // constant); one n×n buffer would make it sixteen
        const bool linear = mode == DerivativeMode::kAdjoint || (f == Formulation::kInverseDynamics && lanes);
        if (linear) {
          EXPECT_LE(l, 4 * s);
        }
        // ID in lanes keeps its three products per stage and nothing else
        if (f == Formulation::kInverseDynamics && lanes) {
          EXPECT_EQ(l, 3 * static_cast<std::size_t>(large.n) * sizeof(double));
        }
      }
    }
  }
}

// the same on a 7-joint arm, for the record
TEST(StageWorkspace, PrintsTheBytesPerStageOfAnArm) {
  const Model arm = load_problem(IDMPC_SOURCE_DIR "/mjcf/iiwa14.xml").model;
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
      for (bool lanes : {true, false}) {
        const std::size_t b = bytes_per_stage(arm, f, mode, lanes);
        std::cout << to_string(f) << "_" << to_string(mode) << (lanes ? "_lanes" : "_scalar") << ": " << b
                  << " B per stage at n = " << arm.n << " (full Data " << full_data_per_stage(arm) << ")\n";
        EXPECT_LT(b, full_data_per_stage(arm));
      }
    }
  }
}

// the Hamiltonian reads a stage's linearization only under the evaluation that made it
TEST(StageWorkspace, AHamiltonianNeedsItsEvaluationsDynamics) {
  const Model model = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml").model;
  const int n = model.n;
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    for (DerivativeMode mode : {DerivativeMode::kMatrix, DerivativeMode::kAdjoint}) {
      SCOPED_TRACE(to_string(f) + "_" + to_string(mode));
      OcpProblem p(model, f, mode, paper_weights(n), VecX<double>::Zero(n), 3);
      p.set_stages_in_lanes(false);
      const VecX<double> q = VecX<double>::Constant(n, 0.3), z = VecX<double>::Zero(n), none(0);
      VecX<double> out(n), hq(n), hv(n), F(p.stage_dim());
      const Evaluation first = p.begin_evaluation();
      p.stage_dynamics(first, 1, q, z, z, out);
      EXPECT_NO_THROW(p.stage_hamiltonian(first, 1, q, z, z, out, none, none, z, z, hq, hv, F, true));
      const Evaluation second = p.begin_evaluation();
      EXPECT_THROW(p.stage_hamiltonian(second, 1, q, z, z, out, none, none, z, z, hq, hv, F, true), std::logic_error);
    }
  }
}

// the problem keeps its model alive: built from a shared model the caller lets go of, or from a
// temporary, it evaluates as one built from a model that outlives it
TEST(StageWorkspace, TheProblemOwnsItsModel) {
  const Model model = load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml").model;
  const int n = model.n, N = 5;
  const VecX<double> q0 = VecX<double>::Constant(n, 0.2), v0 = VecX<double>::Constant(n, -0.1);
  const VecX<double> U = VecX<double>::LinSpaced(N * n, -1.0, 1.0);
  for (Formulation f : {Formulation::kForwardDynamics, Formulation::kInverseDynamics}) {
    SCOPED_TRACE(to_string(f));
    Shooting reference(model, f, DerivativeMode::kAdjoint, paper_weights(n), VecX<double>::Zero(n), N);
    auto shared = std::make_shared<const Model>(model);
    Shooting from_shared(shared, f, DerivativeMode::kAdjoint, paper_weights(n), VecX<double>::Zero(n), N);
    shared.reset();
    Shooting from_temporary(load_problem(IDMPC_SOURCE_DIR "/mjcf/arm4.xml").model, f, DerivativeMode::kAdjoint,
                            paper_weights(n), VecX<double>::Zero(n), N);
    VecX<double> F(N * n), F_shared(N * n), F_temporary(N * n);
    reference.residual(U, q0, v0, 0.3, F);
    from_shared.residual(U, q0, v0, 0.3, F_shared);
    from_temporary.residual(U, q0, v0, 0.3, F_temporary);
    EXPECT_EQ(F, F_shared);
    EXPECT_EQ(F, F_temporary);
  }
}

}  // namespace
}  // namespace idmpc
