// Dual numbers carry f'(x)·w in their tangent. Each function's tangent is checked against its
// derivative written out here and against a central difference of its value, at points where
// the functions are far from linear (so a wrong factor, a dropped term or a wrong sign shows).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "idmpc/spatial/dual.hpp"

namespace idmpc {
namespace {

// central difference with step 1e-6: error ~ h²·f''' + ε/h, about 1e-10 for these functions
constexpr double kStep = 1e-6;
constexpr double kDifference = 1e-8;
// the tangent against the written-out derivative: the same arithmetic up to rounding
constexpr double kExact = 1e-14;

struct Function {
  std::string name;
  std::function<Dual(const Dual&)> f;
  std::function<double(double)> value;
  std::function<double(double)> derivative;
};

std::vector<Function> functions() {
  return {
      {"sin", [](const Dual& x) { return sin(x); }, [](double x) { return std::sin(x); },
       [](double x) { return std::cos(x); }},
      {"cos", [](const Dual& x) { return cos(x); }, [](double x) { return std::cos(x); },
       [](double x) { return -std::sin(x); }},
      {"sqrt", [](const Dual& x) { return sqrt(x); }, [](double x) { return std::sqrt(x); },
       [](double x) { return 0.5 / std::sqrt(x); }},
      {"tanh", [](const Dual& x) { return tanh(x); }, [](double x) { return std::tanh(x); },
       [](double x) { return 1.0 / (std::cosh(x) * std::cosh(x)); }},
      {"product", [](const Dual& x) { return x * x * 3.0; }, [](double x) { return 3 * x * x; },
       [](double x) { return 6 * x; }},
      {"quotient", [](const Dual& x) { return (x + 2.0) / (x * x + 1.0); },
       [](double x) { return (x + 2) / (x * x + 1); },
       [](double x) { return ((x * x + 1) - (x + 2) * 2 * x) / ((x * x + 1) * (x * x + 1)); }},
  };
}

TEST(Dual, TangentIsTheDerivativeTimesTheSeed) {
  // positive points (sqrt's domain), from near 0 (sqrt steep) to where tanh saturates
  const std::vector<double> points = {0.05, 0.3, 0.9, 1.7, 2.6};
  const double seed = -1.3;
  for (const Function& fn : functions()) {
    for (double x : points) {
      SCOPED_TRACE(fn.name + " at " + std::to_string(x));
      const Dual y = fn.f(Dual(x, seed));
      EXPECT_NEAR(y.x, fn.value(x), kExact * std::abs(fn.value(x)));
      const double exact = fn.derivative(x) * seed;
      EXPECT_NEAR(y.dx, exact, kExact * (1 + std::abs(exact)));
      const double difference = (fn.value(x + kStep) - fn.value(x - kStep)) / (2 * kStep) * seed;
      EXPECT_NEAR(y.dx, difference, kDifference * (1 + std::abs(exact)));
      // a constant (zero tangent) stays constant
      EXPECT_EQ(fn.f(Dual(x)).dx, 0.0);
    }
  }
}

// tanh's tangent is 1 − tanh², not 1 − tanh or 1 + tanh²: at x = 0 all three agree on 1, so
// the derivative is checked where they differ, on both sides of 0 (tanh is odd, its slope even)
TEST(Dual, TanhTangentIsEvenAndSaturates) {
  for (double x : {-2.0, -0.5, 0.5, 2.0}) {
    const double t = std::tanh(x);
    EXPECT_NEAR(tanh(Dual(x, 1.0)).dx, 1 - t * t, kExact) << x;
  }
  EXPECT_EQ(tanh(Dual(0.0, 2.0)).dx, 2.0);
  EXPECT_LT(tanh(Dual(20.0, 1.0)).dx, 1e-15);
}

}  // namespace
}  // namespace idmpc
