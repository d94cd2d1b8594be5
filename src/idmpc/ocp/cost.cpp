#include "idmpc/ocp/cost.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace idmpc {
namespace {

void check(const Eigen::Ref<const VecX<double>>& x, Eigen::Index n, const char* what, bool non_negative) {
  if (x.size() != n) {
    throw std::invalid_argument(std::string(what) + " has " + std::to_string(x.size()) +
                                " entries, expected " + std::to_string(n) + " (one per joint)");
  }
  if (!x.allFinite()) throw std::invalid_argument(std::string(what) + " is not finite");
  if (non_negative && (x.array() < 0).any()) {
    throw std::invalid_argument(std::string(what) + " must be non-negative");
  }
}

}  // namespace

QuadraticCost::QuadraticCost(OcpWeights weights, VecX<double> q_ref, int n)
    : w_(std::move(weights)), q_ref_(std::move(q_ref)) {
  check(q_ref_, n, "q_ref", false);
  check(w_.Qq, n, "weight Qq", true);
  check(w_.Qv, n, "weight Qv", true);
  check(w_.Qa, n, "weight Qa", true);
  check(w_.R, n, "weight R", true);
}

double rotation_angle(const Mat3<double>& R, const Mat3<double>& R_ref) {
  // atan2 of sin θ = ½‖vee(A − Aᵀ)‖ and cos θ = ½(tr A − 1), A = R_refᵀR: accurate at any angle
  const Mat3<double> A = R_ref.transpose() * R;
  const Vec3<double> s(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
  return std::atan2(0.5 * s.norm(), 0.5 * (A.trace() - 1.0));
}

void QuadraticCost::set_target(const In& q_ref) {
  check(q_ref, q_ref_.size(), "target q_ref", false);
  q_ref_ = q_ref;
}

}  // namespace idmpc
