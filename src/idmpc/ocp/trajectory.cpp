#include "idmpc/ocp/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace idmpc {
namespace {

constexpr double kTwoPi = 6.283185307179586476925286766559;

// a number as a user would type it
std::string text(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

std::string text(const Eigen::Ref<const VecX<double>>& x) {
  std::ostringstream o;
  o << '(';
  for (Eigen::Index i = 0; i < x.size(); ++i) o << (i ? ", " : "") << x[i];
  o << ')';
  return o.str();
}

[[noreturn]] void bad(const std::string& kind, const std::string& what) {
  throw std::invalid_argument(kind + ": " + what);
}

void check_vector(const std::string& kind, const char* name, const Eigen::Ref<const VecX<double>>& x) {
  if (!x.allFinite()) bad(kind, std::string(name) + " must be finite, got " + text(x));
}

// finite values with at least one row, one column per time
void check_values(const std::string& kind, const std::vector<double>& t, const MatX<double>& P) {
  if (P.rows() < 1) bad(kind, "values must have at least one row (dim >= 1), got 0");
  if (P.cols() != static_cast<Eigen::Index>(t.size())) {
    bad(kind, "values have " + std::to_string(P.cols()) + " columns, expected one per time (" +
                  std::to_string(t.size()) + ")");
  }
  for (Eigen::Index k = 0; k < P.cols(); ++k) {
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      if (!std::isfinite(P(i, k))) {
        bad(kind, "value " + std::to_string(i) + " at t[" + std::to_string(k) + "] must be finite, got " + text(P(i, k)));
      }
    }
  }
}

// the slope of every segment well within range: times so close (1e-310 s apart) or values so far apart
// that a rate overflows are refused (their samples would be NaN)
void check_slopes(const std::string& kind, const std::vector<double>& t, const MatX<double>& P) {
  for (std::size_t k = 0; k + 1 < t.size(); ++k) {
    const double h = t[k + 1] - t[k];
    const auto i = static_cast<Eigen::Index>(k);
    // 4: room for the interpolants' rates, a few slopes at most
    if (!std::isfinite(4 / h) || !(4 * ((P.col(i + 1) - P.col(i)) / h)).allFinite()) {
      bad(kind, "t[" + std::to_string(k) + "] = " + text(t[k]) + " and t[" + std::to_string(k + 1) + "] = " +
                    text(t[k + 1]) + " are too close for their values: the rate between them overflows");
    }
  }
}

void check_times(const std::string& kind, const std::vector<double>& t, std::size_t min_count) {
  if (t.size() < min_count) {
    bad(kind, "expected at least " + std::to_string(min_count) + " times, got " + std::to_string(t.size()));
  }
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (!std::isfinite(t[k])) bad(kind, "t[" + std::to_string(k) + "] must be finite, got " + text(t[k]));
    if (k > 0 && !(t[k] > t[k - 1])) {
      bad(kind, "times must be strictly increasing, got t[" + std::to_string(k) + "] = " + text(t[k]) + " after t[" +
                    std::to_string(k - 1) + "] = " + text(t[k - 1]));
    }
  }
}

// the segment [t_k, t_{k+1}] holding t, for t_0 <= t <= t_{K-1}: binary search
Eigen::Index segment(const std::vector<double>& times, double t) {
  const auto after = std::upper_bound(times.begin(), times.end(), t);
  const Eigen::Index k = static_cast<Eigen::Index>(after - times.begin()) - 1;
  return std::clamp<Eigen::Index>(k, 0, static_cast<Eigen::Index>(times.size()) - 2);
}

std::string span(const std::vector<double>& t) { return "[" + text(t.front()) + ", " + text(t.back()) + "] s"; }

}  // namespace

// constant

ConstantTrajectory::ConstantTrajectory(VecX<double> value) : value_(std::move(value)) {
  if (value_.size() < 1) bad("constant trajectory", "value must have at least one entry, got 0");
  check_vector("constant trajectory", "value", value_);
}

std::unique_ptr<Trajectory> ConstantTrajectory::clone() const { return std::make_unique<ConstantTrajectory>(*this); }

void ConstantTrajectory::sample(double, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const {
  value = value_;
  rate.setZero();
}

std::string ConstantTrajectory::describe() const { return "constant " + text(value_); }

// circle

CircleTrajectory::CircleTrajectory(const Vec3<double>& center, const Vec3<double>& normal, double radius,
                                   double frequency, const Vec3<double>& e1, double ramp)
    : c_(center), n_(normal), e1_(e1), r_(radius), f_(frequency), ramp_(ramp) {
  const std::string kind = "circle";
  check_vector(kind, "center", c_);
  check_vector(kind, "normal", n_);
  check_vector(kind, "start direction e1", e1_);
  if (!(r_ > 0) || !std::isfinite(r_)) bad(kind, "radius must be finite and positive, got " + text(r_));
  if (!(f_ > 0) || !std::isfinite(f_)) bad(kind, "frequency must be finite and positive, got " + text(f_));
  if (!(ramp_ >= 0) || !std::isfinite(ramp_)) bad(kind, "ramp must be finite and non-negative, got " + text(ramp_));
  // beyond these the phase or the speed overflows: NaN samples
  if (f_ > kMaxFrequency) bad(kind, "frequency must be at most " + text(kMaxFrequency) + " Hz, got " + text(f_));
  if (ramp_ > kMaxRamp) bad(kind, "ramp must be at most " + text(kMaxRamp) + " s, got " + text(ramp_));
  if (!std::isfinite(kTwoPi * f_ * r_)) {
    bad(kind, "the speed 2 pi frequency radius must be finite, got radius " + text(r_) + " m at " + text(f_) + " Hz");
  }
  if (std::abs(n_.norm() - 1) > kUnitTolerance) bad(kind, "normal must be a unit vector, got " + text(n_));
  if (std::abs(e1_.norm() - 1) > kUnitTolerance) bad(kind, "start direction e1 must be a unit vector, got " + text(e1_));
  if (std::abs(n_.dot(e1_)) > kUnitTolerance) {
    bad(kind, "start direction e1 must be perpendicular to the normal, got e1 = " + text(e1_) + ", normal = " + text(n_));
  }
  e2_ = n_.cross(e1_);
}

std::unique_ptr<Trajectory> CircleTrajectory::clone() const { return std::make_unique<CircleTrajectory>(*this); }

void CircleTrajectory::phase(double t, double& phi, double& omega) const {
  const double w = kTwoPi * f_;
  if (!(t >= 0)) {
    phi = 0;
    omega = 0;
  } else if (t < ramp_) {
    // ω = 2πf·σ(x), σ = 3x² − 2x³; φ its integral
    const double x = t / ramp_;
    const double x2 = x * x;
    phi = w * ramp_ * (x2 * x - 0.5 * x2 * x2);
    omega = w * (3 * x2 - 2 * x2 * x);
  } else {
    // full speed; the phase reduced to one period keeps cos and sin accurate on long runs
    const double turns = f_ * (t - 0.5 * ramp_);
    phi = kTwoPi * (turns - std::floor(turns));
    omega = w;
  }
}

void CircleTrajectory::sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const {
  double phi, omega;
  phase(t, phi, omega);
  const double cp = std::cos(phi), sp = std::sin(phi);
  value = c_ + r_ * (cp * e1_ + sp * e2_);
  rate = (r_ * omega) * (cp * e2_ - sp * e1_);
}

std::string CircleTrajectory::describe() const {
  return "circle r = " + text(r_) + " m at " + text(f_) + " Hz about " + text(c_) + ", normal " + text(n_) +
         ", from " + text(Vec3<double>(c_ + r_ * e1_)) + ", ramp " + text(ramp_) + " s";
}

// waypoints

WaypointTrajectory::WaypointTrajectory(std::vector<double> times, MatX<double> values)
    : t_(std::move(times)), P_(std::move(values)) {
  check_times("waypoints", t_, 1);
  check_values("waypoints", t_, P_);
  check_slopes("waypoints", t_, P_);
}

std::unique_ptr<Trajectory> WaypointTrajectory::clone() const { return std::make_unique<WaypointTrajectory>(*this); }

void WaypointTrajectory::sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const {
  // held before the first and after the last waypoint
  if (t_.size() == 1 || !(t > t_.front())) {
    value = P_.col(0);
    rate.setZero();
    return;
  }
  if (t >= t_.back()) {
    value = P_.col(P_.cols() - 1);
    rate.setZero();
    return;
  }
  // minimum-jerk blend s(τ), ds/dτ = 30τ²(1 − τ)²
  const Eigen::Index k = segment(t_, t);
  const double h = t_[k + 1] - t_[k];
  const double tau = (t - t_[k]) / h;
  const double tau2 = tau * tau;
  const double s = tau2 * tau * (10 + tau * (-15 + 6 * tau));
  const double ds = 30 * tau2 * (1 - tau) * (1 - tau) / h;
  value = P_.col(k) + s * (P_.col(k + 1) - P_.col(k));
  rate = ds * (P_.col(k + 1) - P_.col(k));
}

std::string WaypointTrajectory::describe() const {
  return "waypoints: " + std::to_string(t_.size()) + " of dim " + std::to_string(dim()) + " over " + span(t_) +
         ", minimum-jerk between them, from " + text(P_.col(0)) + " to " + text(P_.col(P_.cols() - 1));
}

// sampled

SampledTrajectory::SampledTrajectory(std::vector<double> times, MatX<double> values)
    : t_(std::move(times)), P_(std::move(values)) {
  check_times("sampled trajectory", t_, 2);
  check_values("sampled trajectory", t_, P_);
  check_slopes("sampled trajectory", t_, P_);
  // Catmull-Rom tangents: the secant over both neighbours inside, one-sided at the ends
  const Eigen::Index K = P_.cols();
  m_.resize(P_.rows(), K);
  m_.col(0) = (P_.col(1) - P_.col(0)) / (t_[1] - t_[0]);
  m_.col(K - 1) = (P_.col(K - 1) - P_.col(K - 2)) / (t_[K - 1] - t_[K - 2]);
  for (Eigen::Index k = 1; k + 1 < K; ++k) m_.col(k) = (P_.col(k + 1) - P_.col(k - 1)) / (t_[k + 1] - t_[k - 1]);
}

std::unique_ptr<Trajectory> SampledTrajectory::clone() const { return std::make_unique<SampledTrajectory>(*this); }

void SampledTrajectory::sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const {
  // held before the first and after the last sample
  if (t < t_.front()) {
    value = P_.col(0);
    rate.setZero();
    return;
  }
  if (t > t_.back()) {
    value = P_.col(P_.cols() - 1);
    rate.setZero();
    return;
  }
  // cubic Hermite basis on the segment and its derivative in τ
  const Eigen::Index k = segment(t_, t);
  const double h = t_[k + 1] - t_[k];
  const double tau = (t - t_[k]) / h;
  const double tau2 = tau * tau, tau3 = tau2 * tau;
  const double h00 = 2 * tau3 - 3 * tau2 + 1, h10 = tau3 - 2 * tau2 + tau;
  const double h01 = -2 * tau3 + 3 * tau2, h11 = tau3 - tau2;
  const double d00 = 6 * tau2 - 6 * tau, d10 = 3 * tau2 - 4 * tau + 1;
  const double d11 = 3 * tau2 - 2 * tau;
  value = h00 * P_.col(k) + h01 * P_.col(k + 1) + (h10 * h) * m_.col(k) + (h11 * h) * m_.col(k + 1);
  rate = (d00 / h) * (P_.col(k) - P_.col(k + 1)) + d10 * m_.col(k) + d11 * m_.col(k + 1);
}

std::string SampledTrajectory::describe() const {
  return "sampled: " + std::to_string(t_.size()) + " samples of dim " + std::to_string(dim()) + " over " + span(t_) +
         ", cubic Hermite (Catmull-Rom tangents)";
}

}  // namespace idmpc
