// References that move: every kind's rate is the derivative of its value (central differences
// with a tolerance from the error analysis), values and rates are continuous where the pieces
// meet, each kind has the shape it promises (a circle of radius r in its plane, waypoints hit at
// rest, samples interpolated C¹, ends held at rest), and sampling allocates nothing.
// Allocations are counted by support/count_allocations.hpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "idmpc/ocp/trajectory.hpp"
#include "support/count_allocations.hpp"


namespace idmpc {
namespace {

using test::CountAllocations;

constexpr double kPi = 3.14159265358979323846;
constexpr double kEps = std::numeric_limits<double>::epsilon();

struct Sample {
  VecX<double> value, rate;
};

Sample at(const Trajectory& traj, double t) {
  Sample s{VecX<double>(traj.dim()), VecX<double>(traj.dim())};
  traj.sample(t, s.value, s.rate);
  return s;
}

/// Bounds a test states for a trajectory, from which the central difference's error follows.
struct Bounds {
  double scale;     ///< largest magnitude of a term in a value (its rounding error is relative to it)
  double max_rate;  ///< largest |rate| entry
  double M3;        ///< largest |third derivative| on either side of any point
  double J;         ///< largest jump of the second derivative (0 where it is continuous)
  double M2 = 0;    ///< largest |second derivative| (for the continuity checks)
};

// Central difference (v(t+h) − v(t−h))/2h against the rate. Its error is at most
//   truncation  h²·M3/6 (Taylor to third order on each side), plus h·J/4 across a jump J of v'';
//   rounding    kValueUlps·ε·scale/h (each value a few flops on terms of size `scale`), plus
//               ε·|t|·max_rate/h (t ± h is rounded to a step off by up to ε|t|).
// h = 1e-6 balances the two for O(1) values and M3 up to ~1e3.
constexpr double kStep = 1e-6;
constexpr double kValueUlps = 8;

double central_difference_tolerance(const Bounds& b, double t) {
  const double h = kStep;
  return kValueUlps * kEps * b.scale / h + kEps * std::abs(t) * b.max_rate / h + h * h * b.M3 / 6 + h * b.J / 4;
}

void expect_rate_is_derivative(const Trajectory& traj, const std::vector<double>& times, const Bounds& b) {
  for (double t : times) {
    const Sample s = at(traj, t);
    const VecX<double> fd = (at(traj, t + kStep).value - at(traj, t - kStep).value) / (2 * kStep);
    const double tol = central_difference_tolerance(b, t);
    for (int i = 0; i < traj.dim(); ++i) {
      EXPECT_NEAR(s.rate[i], fd[i], tol) << traj.describe() << ": t = " << t << ", entry " << i;
    }
  }
}

std::vector<double> grid(double from, double to, int count) {
  std::vector<double> t;
  for (int i = 0; i < count; ++i) t.push_back(from + (to - from) * i / (count - 1));
  return t;
}

// each time, and the times a few steps either side of it
std::vector<double> around(const std::vector<double>& points) {
  std::vector<double> t;
  for (double p : points) {
    for (double d : {-3.0, -1.0, -0.5, 0.0, 0.5, 1.0, 3.0}) t.push_back(p + d * kStep);
  }
  return t;
}

std::vector<double> joined(std::vector<double> a, const std::vector<double>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// --- circle ---

// c = (0.3, −0.1, 0.5), tilted normal, r = 0.05 m, f = 0.5 Hz (ω = π rad/s), ramp 1 s
struct CircleSetup {
  Vec3<double> c{0.3, -0.1, 0.5};
  Vec3<double> n = Vec3<double>(0.2, -0.3, 1.0).normalized();
  Vec3<double> e1 = n.unitOrthogonal();
  double r = 0.05, f = 0.5, ramp = 1.0;
  CircleTrajectory make() const { return CircleTrajectory(c, n, r, f, e1, ramp); }
  // p''' = r·d³/dt³ e^{iφ}: |p'''| ≤ r(|ω''| + 3ω|ω'| + ω³) with ω ≤ 2πf, |ω'| ≤ 1.5·2πf/ramp and
  // |ω''| ≤ 6·2πf/ramp² (σ' ≤ 1.5, |σ''| ≤ 6)
  Bounds bounds() const {
    const double w = 2 * kPi * f;
    const double M3 = r * (6 * w / (ramp * ramp) + 3 * w * 1.5 * w / ramp + w * w * w);
    return {c.cwiseAbs().maxCoeff() + r, r * w, M3, 0};
  }
};

TEST(CircleTrajectory, StartsAtCentrePlusRadiusAlongE1AndHoldsBefore) {
  const CircleSetup s;
  const CircleTrajectory circle = s.make();
  for (double t : {-5.0, -1e-9, 0.0}) {
    const Sample p = at(circle, t);
    EXPECT_LT((p.value - (s.c + s.r * s.e1)).norm(), 1e-15) << "t = " << t;
    EXPECT_EQ(p.rate.norm(), 0) << "t = " << t;
  }
  EXPECT_EQ(circle.dim(), 3);
}

TEST(CircleTrajectory, StaysOnTheCircleInItsPlane) {
  const CircleSetup s;
  const CircleTrajectory circle = s.make();
  for (double t : grid(-1, 20, 2001)) {
    const Sample p = at(circle, t);
    const VecX<double> d = p.value - s.c;
    // a few roundings of terms of size |c| + r
    EXPECT_NEAR(d.norm(), s.r, 1e-15 * 8) << "t = " << t;
    EXPECT_NEAR(d.dot(s.n), 0, 1e-15 * 8) << "t = " << t;
    // the rate is tangent: in the plane and perpendicular to the radius
    EXPECT_NEAR(p.rate.dot(s.n), 0, 1e-15 * 8) << "t = " << t;
    EXPECT_NEAR(p.rate.dot(d), 0, 1e-15 * 8) << "t = " << t;
  }
}

TEST(CircleTrajectory, TravelsTowardsE2AtFullSpeedWithPeriodOneOverFAfterTheRamp) {
  const CircleSetup s;
  const CircleTrajectory circle = s.make();
  EXPECT_LT((circle.e2() - s.n.cross(s.e1)).norm(), 1e-15);
  const double w = 2 * kPi * s.f;
  for (double t : grid(s.ramp, s.ramp + 30, 301)) {
    const Sample p = at(circle, t), q = at(circle, t + 1 / s.f);
    EXPECT_LT((p.value - q.value).norm(), 1e-13) << "t = " << t;
    EXPECT_LT((p.rate - q.rate).norm(), 1e-13) << "t = " << t;
    EXPECT_NEAR(p.rate.norm(), s.r * w, 1e-14) << "t = " << t;
  }
  // φ(t) = 2πf(t − ramp/2) after the ramp: a quarter period after φ = 0 the point is at c + r·e2
  const double t0 = s.ramp / 2 + 1 / s.f * 5;  // φ = 2π·5
  const double quarter = 0.25 / s.f;
  EXPECT_LT((at(circle, t0).value - (s.c + s.r * s.e1)).norm(), 1e-13);
  EXPECT_LT((at(circle, t0 + quarter).value - (s.c + s.r * circle.e2())).norm(), 1e-13);
}

TEST(CircleTrajectory, RampsTheSpeedUpSmoothly) {
  const CircleSetup s;
  const CircleTrajectory circle = s.make();
  const double w = 2 * kPi * s.f;
  double phi, omega;
  circle.phase(0, phi, omega);
  EXPECT_EQ(phi, 0);
  EXPECT_EQ(omega, 0);
  circle.phase(s.ramp, phi, omega);
  EXPECT_NEAR(phi, w * s.ramp / 2, 1e-15);
  EXPECT_NEAR(omega, w, 1e-15);
  circle.phase(s.ramp / 2, phi, omega);
  EXPECT_NEAR(phi, w * s.ramp * (0.125 - 0.0625 / 2), 1e-15);
  EXPECT_NEAR(omega, w * 0.5, 1e-15);
  // zero angular acceleration at both ends of the ramp: ω moves by O(δ²) there, not O(δ)
  // (σ(x) = 3x² − 2x³ near 0, 1 − 3(1 − x)² + … near 1)
  for (double delta : {1e-2, 1e-3, 1e-4}) {
    const double x = delta / s.ramp;
    circle.phase(delta, phi, omega);
    EXPECT_NEAR(omega, 0, w * 3 * x * x * 1.0001) << "δ = " << delta;
    circle.phase(s.ramp - delta, phi, omega);
    EXPECT_NEAR(omega, w, w * 3 * x * x * 1.0001) << "δ = " << delta;
    circle.phase(s.ramp + delta, phi, omega);
    EXPECT_EQ(omega, w);
  }
}

TEST(CircleTrajectory, WithoutRampStartsAtFullSpeed) {
  CircleSetup s;
  s.ramp = 0;
  const CircleTrajectory circle = s.make();
  EXPECT_NEAR(at(circle, 0).rate.norm(), s.r * 2 * kPi * s.f, 1e-15);
  EXPECT_EQ(at(circle, -1e-12).rate.norm(), 0);
}

TEST(CircleTrajectory, RateIsTheDerivativeOfTheValue) {
  const CircleSetup s;
  const CircleTrajectory circle = s.make();
  // across t = 0, through the ramp and its end, and long after
  expect_rate_is_derivative(circle, joined(grid(-0.5, 12, 401), around({0, s.ramp / 2, s.ramp, 100.25})), s.bounds());
}

TEST(CircleTrajectory, RejectsBadParametersNamingThem) {
  const CircleSetup s;
  const auto message = [&s](const std::function<void(CircleSetup&)>& change) {
    CircleSetup bad = s;
    change(bad);
    try {
      bad.make();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  EXPECT_EQ(message([](CircleSetup& b) { b.r = -0.1; }), "circle: radius must be finite and positive, got -0.1");
  EXPECT_EQ(message([](CircleSetup& b) { b.r = 0; }), "circle: radius must be finite and positive, got 0");
  EXPECT_EQ(message([](CircleSetup& b) { b.f = std::nan(""); }), "circle: frequency must be finite and positive, got nan");
  EXPECT_EQ(message([](CircleSetup& b) { b.ramp = -1; }), "circle: ramp must be finite and non-negative, got -1");
  EXPECT_EQ(message([](CircleSetup& b) { b.n = Vec3<double>(0, 0, 2); }),
            "circle: normal must be a unit vector, got (0, 0, 2)");
  EXPECT_EQ(message([](CircleSetup& b) {
              b.n = Vec3<double>::UnitZ();
              b.e1 = Vec3<double>(0.6, 0, 0.8);
            }),
            "circle: start direction e1 must be perpendicular to the normal, got e1 = (0.6, 0, 0.8), normal = (0, 0, 1)");
  EXPECT_EQ(message([](CircleSetup& b) { b.c.x() = INFINITY; }), "circle: center must be finite, got (inf, -0.1, 0.5)");
}

TEST(CircleTrajectory, DescribesItself) {
  const CircleTrajectory circle(Vec3<double>(0, 0, 0.5), Vec3<double>::UnitX(), 0.05, 0.5, Vec3<double>::UnitZ(), 1);
  EXPECT_EQ(circle.describe(),
            "circle r = 0.05 m at 0.5 Hz about (0, 0, 0.5), normal (1, 0, 0), from (0, 0, 0.55), ramp 1 s");
}

// --- waypoints ---

WaypointTrajectory three_waypoints() {
  MatX<double> P(2, 4);
  P << 0.0, 1.0, 1.0, -0.5,  //
      2.0, 2.5, 1.5, 1.5;
  return WaypointTrajectory({0.5, 1.0, 2.5, 3.0}, P);
}

TEST(WaypointTrajectory, HitsItsValuesAtItsTimesAtRest) {
  const WaypointTrajectory traj = three_waypoints();
  for (std::size_t k = 0; k < traj.times().size(); ++k) {
    const Sample s = at(traj, traj.times()[k]);
    EXPECT_LT((s.value - traj.values().col(static_cast<Eigen::Index>(k))).norm(), 1e-15) << "waypoint " << k;
    EXPECT_EQ(s.rate.norm(), 0) << "waypoint " << k;
  }
}

TEST(WaypointTrajectory, HoldsItsEndsOutsideItsSpan) {
  const WaypointTrajectory traj = three_waypoints();
  for (double t : {-1.0, 0.0, 0.5}) {
    EXPECT_EQ(at(traj, t).value, traj.values().col(0)) << "t = " << t;
    EXPECT_EQ(at(traj, t).rate.norm(), 0) << "t = " << t;
  }
  for (double t : {3.0, 3.5, 1e9}) {
    EXPECT_EQ(at(traj, t).value, traj.values().col(3)) << "t = " << t;
    EXPECT_EQ(at(traj, t).rate.norm(), 0) << "t = " << t;
  }
}

TEST(WaypointTrajectory, TwoWaypointsAreAMinimumJerkLine) {
  MatX<double> P(3, 2);
  P << 0.1, 0.4,  //
      0.2, 0.2,   //
      0.3, -0.3;
  const WaypointTrajectory line({1.0, 3.0}, P);
  const VecX<double> d = P.col(1) - P.col(0);
  // s(½) = ½; peak speed s'(½)/T = 1.875/T
  EXPECT_LT((at(line, 2.0).value - (P.col(0) + 0.5 * d)).norm(), 1e-15);
  EXPECT_LT((at(line, 2.0).rate - 1.875 / 2.0 * d).norm(), 1e-15);
  // every point on the segment between the ends
  for (double t : grid(1, 3, 101)) {
    const VecX<double> p = at(line, t).value - P.col(0);
    EXPECT_LT((p - p.dot(d) / d.squaredNorm() * d).norm(), 1e-15) << "t = " << t;
  }
}

TEST(WaypointTrajectory, ValueAndRateAreContinuousAtTheWaypoints) {
  const WaypointTrajectory traj = three_waypoints();
  // with zero rate and acceleration at a waypoint, δ away the value moves by ≤ |ΔP|·10(δ/T)³ and
  // the rate by ≤ |ΔP|·30(δ/T)²/T (T ≥ 0.5, |ΔP| ≤ 1.5)
  const double delta = 1e-4, T = 0.5, dP = 1.5;
  for (double tk : traj.times()) {
    const Sample a = at(traj, tk - delta), b = at(traj, tk + delta), c = at(traj, tk);
    EXPECT_LE((a.value - c.value).cwiseAbs().maxCoeff(), dP * 10 * std::pow(delta / T, 3)) << "t = " << tk;
    EXPECT_LE((b.value - c.value).cwiseAbs().maxCoeff(), dP * 10 * std::pow(delta / T, 3)) << "t = " << tk;
    EXPECT_LE(a.rate.cwiseAbs().maxCoeff(), dP * 30 * std::pow(delta / T, 2) / T) << "t = " << tk;
    EXPECT_LE(b.rate.cwiseAbs().maxCoeff(), dP * 30 * std::pow(delta / T, 2) / T) << "t = " << tk;
  }
}

TEST(WaypointTrajectory, RateIsTheDerivativeOfTheValue) {
  const WaypointTrajectory traj = three_waypoints();
  // p''' = ΔP·s'''(τ)/T³ with |s'''| ≤ 60; v'' = 0 on both sides of every waypoint (J = 0)
  const double T = 0.5, dP = 1.5, w = 60 * dP / (T * T * T);
  const Bounds b{2.5, 1.875 * dP / T, w, 0};
  expect_rate_is_derivative(traj, joined(grid(0, 3.5, 351), around(traj.times())), b);
}

TEST(WaypointTrajectory, OneWaypointIsAConstant) {
  const WaypointTrajectory traj({1.0}, VecX<double>::Constant(2, 0.7));
  for (double t : {-1.0, 1.0, 2.0}) {
    EXPECT_EQ(at(traj, t).value, VecX<double>::Constant(2, 0.7));
    EXPECT_EQ(at(traj, t).rate.norm(), 0);
  }
}

std::string construction_error(const std::function<void()>& make) {
  try {
    make();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no exception";
}

TEST(WaypointTrajectory, RejectsBadInputNamingIt) {
  EXPECT_EQ(construction_error([] { WaypointTrajectory({0.0, 1.0, 1.0}, MatX<double>::Zero(2, 3)); }),
            "waypoints: times must be strictly increasing, got t[2] = 1 after t[1] = 1");
  EXPECT_EQ(construction_error([] { WaypointTrajectory({}, MatX<double>::Zero(2, 0)); }),
            "waypoints: expected at least 1 times, got 0");
  EXPECT_EQ(construction_error([] { WaypointTrajectory({0.0, 1.0}, MatX<double>::Zero(2, 3)); }),
            "waypoints: values have 3 columns, expected one per time (2)");
  EXPECT_EQ(construction_error([] {
              MatX<double> P = MatX<double>::Zero(2, 2);
              P(1, 1) = std::nan("");
              WaypointTrajectory({0.0, 1.0}, P);
            }),
            "waypoints: value 1 at t[1] must be finite, got nan");
  EXPECT_EQ(construction_error([] { WaypointTrajectory({0.0, INFINITY}, MatX<double>::Zero(2, 2)); }),
            "waypoints: t[1] must be finite, got inf");
}

// --- sampled ---

// non-uniform times; values sin t and cos 2t + t
SampledTrajectory sampled() {
  const std::vector<double> t{0.0, 0.3, 0.5, 1.1, 1.2, 2.0, 2.7};
  MatX<double> P(2, static_cast<Eigen::Index>(t.size()));
  for (std::size_t k = 0; k < t.size(); ++k) {
    P(0, static_cast<Eigen::Index>(k)) = std::sin(t[k]);
    P(1, static_cast<Eigen::Index>(k)) = std::cos(2 * t[k]) + t[k];
  }
  return SampledTrajectory(t, P);
}

// the interpolant's bounds from its pieces: on [t_k, t_k+1] with T = t_k+1 − t_k,
//   v''(τ) = ((12τ − 6)(P_k − P_k+1)/T + (6τ − 4)m_k + (6τ − 2)m_k+1)/T,  v''' = (12(P_k − P_k+1)/T + 6(m_k + m_k+1))/T²
// with the Catmull-Rom tangents computed here independently
Bounds sampled_bounds(const SampledTrajectory& traj) {
  const std::vector<double>& t = traj.times();
  const MatX<double>& P = traj.values();
  const Eigen::Index K = P.cols();
  MatX<double> m(P.rows(), K);
  m.col(0) = (P.col(1) - P.col(0)) / (t[1] - t[0]);
  m.col(K - 1) = (P.col(K - 1) - P.col(K - 2)) / (t[K - 1] - t[K - 2]);
  for (Eigen::Index k = 1; k + 1 < K; ++k) m.col(k) = (P.col(k + 1) - P.col(k - 1)) / (t[k + 1] - t[k - 1]);
  Bounds b{P.cwiseAbs().maxCoeff(), 0, 0, 0};
  VecX<double> left_second = VecX<double>::Zero(P.rows());
  for (Eigen::Index k = 0; k + 1 < K; ++k) {
    const double T = t[k + 1] - t[k];
    const VecX<double> dP = P.col(k) - P.col(k + 1);
    const VecX<double> second0 = (-6 * dP / T - 4 * m.col(k) - 2 * m.col(k + 1)) / T;
    const VecX<double> second1 = (6 * dP / T + 2 * m.col(k) + 4 * m.col(k + 1)) / T;
    const VecX<double> third = (12 * dP / T + 6 * (m.col(k) + m.col(k + 1))) / (T * T);
    b.M3 = std::max(b.M3, third.cwiseAbs().maxCoeff());
    if (k > 0) b.J = std::max(b.J, (second0 - left_second).cwiseAbs().maxCoeff());
    left_second = second1;
    // v'' is linear on a piece: largest at an end; |v'| ≤ |m_k| + T·max|v''| on the piece
    const double M2 = std::max(second0.cwiseAbs().maxCoeff(), second1.cwiseAbs().maxCoeff());
    b.M2 = std::max(b.M2, M2);
    b.max_rate = std::max(b.max_rate, m.col(k).cwiseAbs().maxCoeff() + T * M2);
  }
  EXPECT_LT((m - traj.tangents()).cwiseAbs().maxCoeff(), 1e-15) << "Catmull-Rom tangents";
  return b;
}

TEST(SampledTrajectory, InterpolatesItsSamples) {
  const SampledTrajectory traj = sampled();
  for (std::size_t k = 0; k < traj.times().size(); ++k) {
    EXPECT_LT((at(traj, traj.times()[k]).value - traj.values().col(static_cast<Eigen::Index>(k))).norm(), 1e-15)
        << "sample " << k;
  }
}

TEST(SampledTrajectory, RateIsTheDerivativeOfTheValue) {
  const SampledTrajectory traj = sampled();
  const Bounds b = sampled_bounds(traj);
  // inside the span, across every inner knot (where v'' jumps: the h·J/4 term)
  const std::vector<double>& t = traj.times();
  const std::vector<double> inner(t.begin() + 1, t.end() - 1);
  expect_rate_is_derivative(traj, joined(grid(t.front() + 1e-3, t.back() - 1e-3, 301), around(inner)), b);
}

TEST(SampledTrajectory, IsContinuouslyDifferentiableAtItsKnots) {
  const SampledTrajectory traj = sampled();
  const Bounds b = sampled_bounds(traj);
  // δ either side of a knot the value moves by ≤ 2δ·max|v'| and the rate by ≤ 2δ·max|v''|, plus
  // a few roundings (of values of size `scale`, and of rates ε·scale/T with T ≥ 0.1)
  const double delta = 1e-9;
  const std::vector<double>& t = traj.times();
  for (std::size_t k = 1; k + 1 < t.size(); ++k) {
    const Sample a = at(traj, t[k] - delta), c = at(traj, t[k] + delta);
    EXPECT_LE((a.value - c.value).cwiseAbs().maxCoeff(), 2 * delta * b.max_rate + 8 * kEps * b.scale) << "knot " << k;
    EXPECT_LE((a.rate - c.rate).cwiseAbs().maxCoeff(), 2 * delta * b.M2 + 8 * kEps * b.scale / 0.1) << "knot " << k;
  }
}

TEST(SampledTrajectory, ReproducesUniformMotionExactly) {
  const std::vector<double> t{0.0, 0.1, 0.5, 0.6, 2.0};
  MatX<double> P(1, 5);
  for (int k = 0; k < 5; ++k) P(0, k) = 3 - 2 * t[k];
  const SampledTrajectory traj(t, P);
  for (double s : grid(0, 2, 81)) {
    EXPECT_NEAR(at(traj, s).value[0], 3 - 2 * s, 1e-14) << "t = " << s;
    EXPECT_NEAR(at(traj, s).rate[0], -2, 1e-13) << "t = " << s;
  }
}

TEST(SampledTrajectory, HoldsItsEndsOutsideItsSpan) {
  const SampledTrajectory traj = sampled();
  const Eigen::Index K = traj.values().cols();
  for (double t : {-1.0, -1e-12}) {
    EXPECT_EQ(at(traj, t).value, traj.values().col(0)) << "t = " << t;
    EXPECT_EQ(at(traj, t).rate.norm(), 0) << "t = " << t;
  }
  for (double t : {2.7 + 1e-12, 4.0}) {
    EXPECT_EQ(at(traj, t).value, traj.values().col(K - 1)) << "t = " << t;
    EXPECT_EQ(at(traj, t).rate.norm(), 0) << "t = " << t;
  }
}

TEST(SampledTrajectory, FindsTheSegmentAmongManySamples) {
  // 10⁵ uniform samples of t²: each lookup lands on its own segment
  const int K = 100000;
  std::vector<double> t(K);
  MatX<double> P(1, K);
  for (int k = 0; k < K; ++k) {
    t[k] = 1e-3 * k;
    P(0, k) = t[k] * t[k];
  }
  const SampledTrajectory traj(t, P);
  // on a uniform grid the Catmull-Rom tangents of a parabola are exact inside (not on the
  // one-sided end pieces), and so is the interpolant: up to a few roundings of values of size s²
  // (in the rate, divided by the spacing)
  for (double s : {0.0123, 7.77777, 50.0, 99.9975}) {
    EXPECT_NEAR(at(traj, s).value[0], s * s, 8 * kEps * s * s) << "t = " << s;
    EXPECT_NEAR(at(traj, s).rate[0], 2 * s, 8 * kEps * s * s / 1e-3) << "t = " << s;
  }
}

TEST(SampledTrajectory, RejectsBadInputNamingIt) {
  EXPECT_EQ(construction_error([] { SampledTrajectory({0.0}, MatX<double>::Zero(1, 1)); }),
            "sampled trajectory: expected at least 2 times, got 1");
  EXPECT_EQ(construction_error([] { SampledTrajectory({0.0, -1.0}, MatX<double>::Zero(1, 2)); }),
            "sampled trajectory: times must be strictly increasing, got t[1] = -1 after t[0] = 0");
  EXPECT_EQ(construction_error([] { SampledTrajectory({0.0, 1.0}, MatX<double>::Zero(0, 2)); }),
            "sampled trajectory: values must have at least one row (dim >= 1), got 0");
}

// --- every kind ---

TEST(ConstantTrajectory, HoldsItsValueAtRest) {
  const ConstantTrajectory traj(Vec3<double>(0.1, 0.2, 0.3));
  for (double t : {-1.0, 0.0, 1e6}) {
    EXPECT_EQ(at(traj, t).value, Vec3<double>(0.1, 0.2, 0.3));
    EXPECT_EQ(at(traj, t).rate.norm(), 0);
  }
  expect_rate_is_derivative(traj, grid(-1, 1, 21), Bounds{0.3, 0, 0, 0});
  EXPECT_EQ(traj.describe(), "constant (0.1, 0.2, 0.3)");
  EXPECT_EQ(construction_error([] { ConstantTrajectory(VecX<double>()); }),
            "constant trajectory: value must have at least one entry, got 0");
  EXPECT_EQ(construction_error([] { ConstantTrajectory(VecX<double>::Constant(1, NAN)); }),
            "constant trajectory: value must be finite, got (nan)");
}

TEST(Trajectory, CloneIsIndependentOfTheOriginal) {
  std::vector<std::unique_ptr<Trajectory>> kinds;
  kinds.push_back(std::make_unique<ConstantTrajectory>(Vec3<double>(1, 2, 3)));
  kinds.push_back(CircleSetup().make().clone());
  kinds.push_back(std::make_unique<WaypointTrajectory>(three_waypoints()));
  kinds.push_back(std::make_unique<SampledTrajectory>(sampled()));
  for (auto& original : kinds) {
    const std::string what = original->describe();
    std::vector<Sample> expected;
    for (double t : grid(-1, 4, 11)) expected.push_back(at(*original, t));
    std::unique_ptr<Trajectory> copy = original->clone();
    original.reset();
    EXPECT_EQ(copy->describe(), what);
    int i = 0;
    for (double t : grid(-1, 4, 11)) {
      EXPECT_EQ(at(*copy, t).value, expected[i].value) << what << ", t = " << t;
      EXPECT_EQ(at(*copy, t).rate, expected[i].rate) << what << ", t = " << t;
      ++i;
    }
  }
}

TEST(Trajectory, AllocationCounterIsArmed) {
  EXPECT_GE(test::allocations_of_a_vector(), 1)
      << "the counter must see an Eigen allocation, or the test below proves nothing";
}

TEST(Trajectory, SamplesAHorizonWithoutAllocating) {
  std::vector<std::unique_ptr<Trajectory>> kinds;
  kinds.push_back(std::make_unique<ConstantTrajectory>(Vec3<double>(1, 2, 3)));
  kinds.push_back(CircleSetup().make().clone());
  kinds.push_back(std::make_unique<WaypointTrajectory>(three_waypoints()));
  kinds.push_back(std::make_unique<SampledTrajectory>(sampled()));
  for (const auto& traj : kinds) {
    // one column per stage of a horizon, as the controller holds them
    const int N = 25;
    MatX<double> values(traj->dim(), N + 1), rates(traj->dim(), N + 1);
    const std::vector<double> starts = grid(-1, 5, 61);
    long n = 0;
    {
      CountAllocations c;
      for (double t0 : starts) {
        for (int i = 0; i <= N; ++i) traj->sample(t0 + 0.02 * i, values.col(i), rates.col(i));
      }
      n = c.count();
    }
    EXPECT_EQ(n, 0) << traj->describe();
    EXPECT_TRUE(values.allFinite() && rates.allFinite()) << traj->describe();
  }
}

}  // namespace
}  // namespace idmpc
