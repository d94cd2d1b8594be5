// The 3×3-block Coriolis matrix of the RNEA derivatives equals its 6×6 definition.
#include <gtest/gtest.h>

#include <random>

#include "idmpc/dynamics/rnea_derivatives.hpp"

namespace idmpc {
namespace {

// both sides are sums of a few products of O(1) entries: rounding only
constexpr double kRounding = 1e-13;

TEST(CoriolisMatrix, EqualsCrossForceTimesInertiaMinusInertiaTimesCrossMotionPlusBar) {
  for (unsigned seed = 1; seed <= 50; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::srand(seed);
    const Mat3<double> A = Mat3<double>::Random();
    const Inertia<double> I =
        Inertia<double>::from_com(0.5 + seed * 0.1, Vec3<double>::Random(), A * A.transpose());
    const Vec6<double> v = Vec6<double>::Random(), h = I.apply(v);
    const Mat6<double> I6 = I.matrix();
    const Mat6<double> reference = cross_force_matrix<double>(v) * I6 -
                                   I6 * cross_motion_matrix<double>(v) +
                                   cross_force_bar_matrix<double>(h);
    EXPECT_LE((coriolis_matrix<double>(I, v, h) - reference).cwiseAbs().maxCoeff(), kRounding);
  }
}

}  // namespace
}  // namespace idmpc
