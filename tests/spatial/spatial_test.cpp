// Spatial-algebra identities (Featherstone 2008, ch. 2): every fast 3×3-block helper in
// spatial.hpp against its dense 6×6 definition, on random inputs from fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {
namespace {

// identities of O(1) random inputs hold up to a few dozen roundings
constexpr double kRounding = 1e-12;
constexpr int kSamplesPerSeed = 20;

using V6 = Vec6<double>;
using M6 = Mat6<double>;
using M3 = Mat3<double>;
using V3 = Vec3<double>;

/// random inputs of the identities, all O(1)
class Random {
 public:
  explicit Random(unsigned seed) : rng_(seed) {}

  double scalar(double scale = 1.0) { return scale * unit_(rng_); }
  V3 vec3(double scale = 1.0) { return V3(scalar(scale), scalar(scale), scalar(scale)); }
  V6 vec6() {
    V6 x;
    for (int k = 0; k < 6; ++k) x[k] = scalar();
    return x;
  }
  V3 unit_vec3() {
    for (;;) {
      const V3 x = vec3();
      if (x.norm() > 0.1) return x.normalized();
    }
  }
  M3 rotation() {
    const Eigen::Vector4d c(scalar(), scalar(), scalar(), scalar());
    return Eigen::Quaterniond(c[0], c[1], c[2], c[3]).normalized().toRotationMatrix();
  }
  Transform<double> transform() {
    Transform<double> X;
    X.E = rotation();
    X.r = vec3(2.0);
    return X;
  }
  /// a physical rigid-body inertia about some origin: box moments, rotated, off-centre COM
  Inertia<double> inertia() {
    const double m = 0.2 + std::abs(scalar(3.0));
    const V3 sides(0.1 + std::abs(scalar()), 0.1 + std::abs(scalar()), 0.1 + std::abs(scalar()));
    const V3 moments(m / 12 * (sides.y() * sides.y() + sides.z() * sides.z()),
                     m / 12 * (sides.x() * sides.x() + sides.z() * sides.z()),
                     m / 12 * (sides.x() * sides.x() + sides.y() * sides.y()));
    const M3 R = rotation();
    return Inertia<double>::from_com(m, vec3(), R * moments.asDiagonal() * R.transpose());
  }
  /// a symmetric positive-definite 6×6 matrix (an articulated inertia stands in)
  M6 spd6() {
    M6 A;
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j) A(i, j) = scalar();
    return A * A.transpose() + M6::Identity();
  }

 private:
  std::mt19937 rng_;
  std::uniform_real_distribution<double> unit_{-1.0, 1.0};
};

/// dense force transform X* = X⁻ᵀ built from the blocks, independently of motion_matrix
M6 force_matrix(const Transform<double>& X) {
  M6 F = M6::Zero();
  F.topLeftCorner<3, 3>() = X.E;
  F.bottomRightCorner<3, 3>() = X.E;
  F.topRightCorner<3, 3>() = -X.E * skew<double>(X.r);
  return F;
}

double max_abs(const Eigen::MatrixXd& x) { return x.cwiseAbs().maxCoeff(); }

// the seed is in every test's name (…/seed7)
class SpatialIdentities : public ::testing::TestWithParam<unsigned> {};

TEST_P(SpatialIdentities, SkewIsTheCrossProduct) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const V3 x = rnd.vec3(), y = rnd.vec3();
    EXPECT_LE(max_abs(skew<double>(x) * y - x.cross(y)), kRounding);
    EXPECT_LE(max_abs(skew<double>(x) + skew<double>(x).transpose()), 0.0);
  }
}

TEST_P(SpatialIdentities, TransformTimesInverseIsIdentityOnMotions) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> X = rnd.transform();
    const V6 m = rnd.vec6();
    EXPECT_LE(max_abs(X.apply_inverse_motion(X.apply_motion(m)) - m), kRounding);
    EXPECT_LE(max_abs(X.apply_motion(X.apply_inverse_motion(m)) - m), kRounding);
    EXPECT_LE(max_abs(X.inverse().apply_motion(X.apply_motion(m)) - m), kRounding);
    EXPECT_LE(max_abs((X * X.inverse()).motion_matrix() - M6::Identity()), kRounding);
    EXPECT_LE(max_abs((X.inverse() * X).motion_matrix() - M6::Identity()), kRounding);
    EXPECT_LE(max_abs(X.inverse().motion_matrix() - X.motion_matrix().inverse()), kRounding);
  }
}

TEST_P(SpatialIdentities, ApplyMatchesTheDenseMatrices) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> X = rnd.transform();
    const M6 Xm = X.motion_matrix();
    const V6 m = rnd.vec6(), f = rnd.vec6();
    // the force transform is the inverse transpose of the motion transform
    EXPECT_LE(max_abs(force_matrix(X) - Xm.inverse().transpose()), kRounding);
    EXPECT_LE(max_abs(X.apply_motion(m) - Xm * m), kRounding);
    EXPECT_LE(max_abs(X.apply_inverse_motion(m) - Xm.inverse() * m), kRounding);
    EXPECT_LE(max_abs(X.apply_force(f) - Xm.inverse().transpose() * f), kRounding);
    EXPECT_LE(max_abs(X.apply_transpose_force(f) - Xm.transpose() * f), kRounding);
    EXPECT_LE(max_abs(X.apply_transpose_force(X.apply_force(f)) - f), kRounding);
  }
}

TEST_P(SpatialIdentities, PowerIsInvariant) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> X = rnd.transform();
    const V6 m = rnd.vec6(), f = rnd.vec6();
    // (X m)ᵀ(X* f) = mᵀf, and (X m)ᵀ f = mᵀ(Xᵀ f)
    EXPECT_NEAR(X.apply_motion(m).dot(X.apply_force(f)), m.dot(f), kRounding);
    EXPECT_NEAR(X.apply_motion(m).dot(f), m.dot(X.apply_transpose_force(f)), kRounding);
  }
}

TEST_P(SpatialIdentities, CompositionAppliesRightToLeft) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> A = rnd.transform(), B = rnd.transform();
    const V6 m = rnd.vec6(), f = rnd.vec6();
    const Transform<double> AB = A * B;
    EXPECT_LE(max_abs(AB.apply_motion(m) - A.apply_motion(B.apply_motion(m))), kRounding);
    EXPECT_LE(max_abs(AB.apply_force(f) - A.apply_force(B.apply_force(f))), kRounding);
    EXPECT_LE(max_abs(AB.motion_matrix() - A.motion_matrix() * B.motion_matrix()), kRounding);
    EXPECT_LE(max_abs(AB.inverse().motion_matrix() -
                      (B.inverse() * A.inverse()).motion_matrix()),
              kRounding);
  }
}

TEST_P(SpatialIdentities, CrossProductsMatchTheirMatrices) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const V6 m = rnd.vec6(), m2 = rnd.vec6(), f = rnd.vec6();
    EXPECT_LE(max_abs(cross_motion<double>(m, m2) - cross_motion_matrix<double>(m) * m2), kRounding);
    EXPECT_LE(max_abs(cross_force<double>(m, f) - cross_force_matrix<double>(m) * f), kRounding);
    EXPECT_LE(max_abs(cross_force_matrix<double>(m) + cross_motion_matrix<double>(m).transpose()),
              kRounding);
    EXPECT_LE(max_abs(cross_force_bar_matrix<double>(f) * m - cross_force<double>(m, f)), kRounding);
    // m × m = 0 and (m ×* f)·m = 0 (a velocity does no work on its own gyroscopic force)
    EXPECT_LE(max_abs(cross_motion<double>(m, m)), kRounding);
    EXPECT_NEAR(cross_force<double>(m, f).dot(m), 0.0, kRounding);
  }
}

TEST_P(SpatialIdentities, CrossProductsTransformCovariantly) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> X = rnd.transform();
    const V6 m = rnd.vec6(), m2 = rnd.vec6(), f = rnd.vec6();
    // X(m × m2) = (Xm) × (Xm2);  X*(m ×* f) = (Xm) ×* (X* f)
    EXPECT_LE(max_abs(X.apply_motion(cross_motion<double>(m, m2)) -
                      cross_motion<double>(X.apply_motion(m), X.apply_motion(m2))),
              kRounding);
    EXPECT_LE(max_abs(X.apply_force(cross_force<double>(m, f)) -
                      cross_force<double>(X.apply_motion(m), X.apply_force(f))),
              kRounding);
  }
}

TEST_P(SpatialIdentities, InertiaApplyMatchesItsMatrix) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Inertia<double> I = rnd.inertia();
    const V6 m = rnd.vec6();
    const M6 Im = I.matrix();
    EXPECT_LE(max_abs(I.apply(m) - Im * m), kRounding);
    EXPECT_LE(max_abs(Im - Im.transpose()), kRounding);
    // a physical inertia is positive definite: kinetic energy ½ vᵀIv > 0
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<M6>(Im).eigenvalues().minCoeff(), 0.0);
  }
}

TEST_P(SpatialIdentities, InertiaFromComIsTheCentralInertiaTranslated) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const double mass = 0.5 + std::abs(rnd.scalar());
    const V3 c = rnd.vec3();
    const M3 R = rnd.rotation();
    const M3 Ic = R * V3(0.3, 0.2, 0.15).asDiagonal() * R.transpose();
    // about the COM: diag(Ic, m·1); moved to a frame whose origin is −c from the COM
    M6 central = M6::Zero();
    central.topLeftCorner<3, 3>() = Ic;
    central.bottomRightCorner<3, 3>() = mass * M3::Identity();
    Transform<double> to_com;  // frame at the origin → frame at the COM, same orientation
    to_com.r = c;
    const M6 Xm = to_com.motion_matrix();
    EXPECT_LE(max_abs(Inertia<double>::from_com(mass, c, Ic).matrix() -
                      Xm.transpose() * central * Xm),
              kRounding);
  }
}

TEST_P(SpatialIdentities, InertiaTransformedToParentIsCongruence) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Inertia<double> I = rnd.inertia();
    const Transform<double> X = rnd.transform();
    const M6 Xm = X.motion_matrix();
    const M6 expected = Xm.transpose() * I.matrix() * Xm;
    EXPECT_LE(max_abs(I.transformed_to_parent(X).matrix() - expected), kRounding);
    // composing two re-expressions equals one with the composed transform
    const Transform<double> Y = rnd.transform();
    EXPECT_LE(max_abs(I.transformed_to_parent(X).transformed_to_parent(Y).matrix() -
                      I.transformed_to_parent(X * Y).matrix()),
              kRounding);
    // the inertia of two bodies is the sum of their matrices
    const Inertia<double> J = rnd.inertia();
    Inertia<double> sum = I;
    sum += J;
    EXPECT_LE(max_abs(sum.matrix() - (I.matrix() + J.matrix())), kRounding);
    // accumulated into another inertia without the intermediate: the same sum
    Inertia<double> acc = J;
    I.add_transformed_to_parent(X, acc);
    EXPECT_LE(max_abs(acc.matrix() - (J.matrix() + expected)), kRounding);
  }
}

TEST_P(SpatialIdentities, SetTransformIsTheTransformOfEachColumnInItsRange) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const Transform<double> X = rnd.transform();
    SpatialSet<double> F(6, 7);
    for (int t = 0; t < 7; ++t) F.col(t) = rnd.vec6();
    const SpatialSet<double> before = F;
    X.apply_transpose_force_to_columns(F, 2, 6);
    for (int t = 0; t < 7; ++t) {
      const V6 f = before.col(t);
      const V6 expected = t >= 2 && t < 6 ? V6(X.apply_transpose_force(f)) : f;
      EXPECT_LE(max_abs(V6(F.col(t)) - expected), kRounding) << "column " << t;
    }
  }
}

TEST_P(SpatialIdentities, CongruenceToParentIsTheSixBySixProduct) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const M6 IA = rnd.spd6();
    const Transform<double> X = rnd.transform();
    const M6 Xm = X.motion_matrix();
    const M6 expected = Xm.transpose() * IA * Xm;
    const M6 got = congruence_to_parent<double>(IA, X);
    EXPECT_LE(max_abs(got - expected) / std::max(1.0, max_abs(expected)), kRounding);
    // on a rigid-body inertia it agrees with Inertia::transformed_to_parent
    const Inertia<double> I = rnd.inertia();
    EXPECT_LE(max_abs(congruence_to_parent<double>(I.matrix(), X) -
                      I.transformed_to_parent(X).matrix()),
              kRounding);
  }
}

TEST_P(SpatialIdentities, AxisRotationIsARotationAboutTheAxis) {
  Random rnd(GetParam());
  for (int s = 0; s < kSamplesPerSeed; ++s) {
    const V3 axis = rnd.unit_vec3();
    const double theta = rnd.scalar(M_PI);
    const M3 R = axis_rotation<double>(axis, theta);
    EXPECT_LE(max_abs(R.transpose() * R - M3::Identity()), kRounding);
    EXPECT_NEAR(R.determinant(), 1.0, kRounding);
    // the axis is fixed, a perpendicular vector turns by θ in the right-handed sense
    EXPECT_LE(max_abs(R * axis - axis), kRounding);
    const V3 u = axis.cross(rnd.unit_vec3()).normalized();
    EXPECT_LE(max_abs(R * u - (std::cos(theta) * u + std::sin(theta) * axis.cross(u))), kRounding);
    EXPECT_LE(max_abs(R - Eigen::AngleAxisd(theta, axis).toRotationMatrix()), kRounding);
    // rotations about one axis add
    const double phi = rnd.scalar(M_PI);
    EXPECT_LE(max_abs(axis_rotation<double>(axis, theta) * axis_rotation<double>(axis, phi) -
                      axis_rotation<double>(axis, theta + phi)),
              kRounding);
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, SpatialIdentities, ::testing::Range(1u, 11u),
                         [](const ::testing::TestParamInfo<unsigned>& info) {
                           return "seed" + std::to_string(info.param);
                         });

}  // namespace
}  // namespace idmpc
