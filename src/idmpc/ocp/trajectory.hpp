#pragma once
/// @file trajectory.hpp
/// @brief References that move: a value and its rate at any time, sampled per horizon stage so
/// that the controller previews where the reference is going over its horizon.
///
/// Four kinds: a constant; a circle (a 3-D position, smooth start); waypoints joined by
/// rest-to-rest minimum-jerk segments; and samples (e.g. a planner's CSV) joined by a C¹
/// piecewise-cubic Hermite interpolant. Constructors validate their parameters and throw
/// std::invalid_argument naming the bad one and its value; sample() is allocation-free.

#include <memory>
#include <string>
#include <vector>

#include "idmpc/spatial/spatial.hpp"

namespace idmpc {

/// @brief A reference that moves: its value and rate at any time t (seconds). Before its start
/// and after its end it holds its end values with zero rate.
class Trajectory {
 public:
  virtual ~Trajectory() = default;
  virtual std::unique_ptr<Trajectory> clone() const = 0;
  virtual int dim() const = 0;
  /// @brief Value and rate (size dim() each) at t; allocation-free (called per horizon stage in
  /// the control loop).
  virtual void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const = 0;
  /// @brief One line saying what it is, for run summaries ("circle r = 0.05 m at 0.5 Hz …").
  virtual std::string describe() const = 0;
};

/// @brief A fixed value (size ≥ 1, finite), rate zero.
class ConstantTrajectory final : public Trajectory {
 public:
  explicit ConstantTrajectory(VecX<double> value);
  std::unique_ptr<Trajectory> clone() const override;
  int dim() const override { return static_cast<int>(value_.size()); }
  void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const override;
  std::string describe() const override;

 private:
  VecX<double> value_;
};

/// @brief A circle in 3-D, run for ever after a smooth start:
///   p(t) = c + r(cos φ(t) e1 + sin φ(t) e2),  e2 = n × e1,
///   ω(t) = φ'(t) = 2πf·σ(t/ramp),  σ(x) = 3x² − 2x³ on [0, 1], 1 after,
///   φ(t) = 2πf·ramp·(x³ − x⁴/2) for 0 ≤ t < ramp (x = t/ramp), 2πf(t − ramp/2) after, 0 before 0.
/// The angular acceleration is continuous (σ'(0) = σ'(1) = 0); with ramp = 0 the speed jumps to
/// 2πf at t = 0. p(0) = c + r·e1.
class CircleTrajectory final : public Trajectory {
 public:
  /// @param center c; @param normal n, the plane's unit normal; @param radius r > 0 [m];
  /// @param frequency f > 0 [Hz]; @param e1 unit start direction, ⟂ n; @param ramp ≥ 0 [s].
  /// Unit and ⟂ within kUnitTolerance; everything finite; f ≤ kMaxFrequency, ramp ≤ kMaxRamp
  /// and the speed 2π f r finite, so that every sample is finite.
  CircleTrajectory(const Vec3<double>& center, const Vec3<double>& normal, double radius, double frequency,
                   const Vec3<double>& e1, double ramp);
  /// how far from 1 a unit vector's norm, and from 0 the cosine between n and e1, may be
  static constexpr double kUnitTolerance = 1e-9;
  /// the largest frequency [Hz] (a thousand times a fast control rate) and ramp [s] (30 years)
  static constexpr double kMaxFrequency = 1e6, kMaxRamp = 1e9;

  std::unique_ptr<Trajectory> clone() const override;
  int dim() const override { return 3; }
  void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const override;
  std::string describe() const override;

  const Vec3<double>& center() const { return c_; }
  const Vec3<double>& normal() const { return n_; }
  const Vec3<double>& e1() const { return e1_; }
  const Vec3<double>& e2() const { return e2_; }
  double radius() const { return r_; }
  double frequency() const { return f_; }
  double ramp() const { return ramp_; }
  /// @brief The phase φ(t) (reduced to [0, 2π) after the ramp) and angular speed ω(t) [rad, rad/s].
  void phase(double t, double& phi, double& omega) const;

 private:
  Vec3<double> c_, n_, e1_, e2_;
  double r_, f_, ramp_;
};

/// @brief Values P_k at strictly increasing times t_k, joined by rest-to-rest minimum-jerk
/// segments: on [t_k, t_{k+1}], with τ = (t − t_k)/(t_{k+1} − t_k),
///   p = P_k + s(τ)(P_{k+1} − P_k),  s(τ) = 10τ³ − 15τ⁴ + 6τ⁵,
/// so velocity and acceleration are zero at every waypoint. Holds P_0 before t_0 and the last
/// after the last time. A straight line is two waypoints.
class WaypointTrajectory final : public Trajectory {
 public:
  /// @param times K ≥ 1 finite, strictly increasing times [s]; @param values dim × K, column k
  /// is P_k (finite, dim ≥ 1).
  WaypointTrajectory(std::vector<double> times, MatX<double> values);
  std::unique_ptr<Trajectory> clone() const override;
  int dim() const override { return static_cast<int>(P_.rows()); }
  void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const override;
  std::string describe() const override;

  const std::vector<double>& times() const { return t_; }
  const MatX<double>& values() const { return P_; }

 private:
  std::vector<double> t_;
  MatX<double> P_;
};

/// @brief Samples P_k at strictly increasing times t_k (what a planner's CSV gives), joined by
/// a piecewise-cubic Hermite interpolant with Catmull-Rom tangents for non-uniform spacing,
///   m_k = (P_{k+1} − P_{k−1})/(t_{k+1} − t_{k−1}),  one-sided secants at both ends,
/// so value and rate are continuous (C¹) and a uniform motion is reproduced exactly. The rate is
/// the interpolant's derivative. Holds the first sample before t_0 and the last after t_{K−1}
/// (rate zero there). Sampling finds the segment by binary search: O(log K).
class SampledTrajectory final : public Trajectory {
 public:
  /// @param times K ≥ 2 finite, strictly increasing times [s]; @param values dim × K, column k
  /// is P_k (finite, dim ≥ 1).
  SampledTrajectory(std::vector<double> times, MatX<double> values);
  std::unique_ptr<Trajectory> clone() const override;
  int dim() const override { return static_cast<int>(P_.rows()); }
  void sample(double t, Eigen::Ref<VecX<double>> value, Eigen::Ref<VecX<double>> rate) const override;
  std::string describe() const override;

  const std::vector<double>& times() const { return t_; }
  const MatX<double>& values() const { return P_; }
  /// @brief The tangents m_k, dim × K.
  const MatX<double>& tangents() const { return m_; }

 private:
  std::vector<double> t_;
  MatX<double> P_, m_;
};

}  // namespace idmpc
