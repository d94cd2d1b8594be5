#include "idmpc/mujoco/closed_loop.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>

#include "idmpc/mujoco/load.hpp"

namespace idmpc::mj {
namespace {

// a measured joint speed beyond this [rad/s or m/s] means the loop has blown up
constexpr double kMaxSpeed = 1e4;

// the tracking error of a run's steps, by MuJoCo's kinematics of the measured states
class TrackingMeter {
 public:
  TrackingMeter(const mjModel* m, const TrackingSettings& s, int n)
      : m_(m), s_(s), d_(s.frame() ? make_data(m) : nullptr), q_ref_(n), rate_(n) {}

  // the frame's position and target at (t, q), accumulated; false without a frame
  bool measure(double t, const VecX<double>& q) {
    if (!s_.frame()) return false;
    Eigen::Map<VecX<double>>(d_->qpos, q.size()) = q;
    mj_kinematics(m_, d_.get());
    const mjtNum* x = s_.site >= 0 ? d_->site_xpos + 3 * s_.site : d_->xpos + 3 * s_.body;
    const mjtNum* R = s_.site >= 0 ? d_->site_xmat + 9 * s_.site : d_->xmat + 9 * s_.body;
    p_ = Eigen::Map<const Vec3<double>>(x);
    if (s_.position) {
      s_.position->sample(t, target_, rate3_);
    } else {
      target_ = s_.fixed_position;
    }
    const double e = (p_ - target_).norm();
    const double angle = rotation_angle(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R), s_.rotation);
    r_.position_max = std::max(r_.position_max, e);
    r_.orientation_max = std::max(r_.orientation_max, angle);
    position_sq_ += e * e;
    orientation_sq_ += angle * angle;
    r_.final_position_error = e;
    ++r_.samples;
    return true;
  }
  const Vec3<double>& position() const { return p_; }
  const Vec3<double>& target() const { return target_; }

  // max |q − q_ref| at t, q_ref moving or the controller's
  double joint_error(double t, const VecX<double>& q, const Controller& c) {
    if (!s_.joints) return (q - c.q_ref()).cwiseAbs().maxCoeff();
    s_.joints->sample(t, q_ref_, rate_);
    return (q - q_ref_).cwiseAbs().maxCoeff();
  }
  // ‖q − q_ref‖² at t
  double joint_error_squared(double t, const VecX<double>& q, const Controller& c) {
    if (!s_.joints) return (q - c.q_ref()).squaredNorm();
    s_.joints->sample(t, q_ref_, rate_);
    return (q - q_ref_).squaredNorm();
  }

  std::optional<TrackingResult> result() const {
    if (!s_.frame()) return std::nullopt;
    TrackingResult r = r_;
    const double k = std::max<double>(1.0, static_cast<double>(r.samples));
    r.position_rms = std::sqrt(position_sq_ / k);
    r.orientation_rms = std::sqrt(orientation_sq_ / k);
    return r;
  }

 private:
  const mjModel* m_;
  const TrackingSettings& s_;
  DataPtr d_;
  Vec3<double> p_ = Vec3<double>::Zero(), target_ = Vec3<double>::Zero(), rate3_;
  VecX<double> q_ref_, rate_;
  TrackingResult r_;
  double position_sq_ = 0, orientation_sq_ = 0;
};

}  // namespace

double percentile(std::vector<double> x, double p) {
  if (x.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(x.begin(), x.end());
  const double pos = p / 100.0 * static_cast<double>(x.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, x.size() - 1);
  return x[lo] + (pos - static_cast<double>(lo)) * (x[hi] - x[lo]);
}

RunResult run_closed_loop(Plant& plant, Controller& controller, const ClosedLoopSettings& settings,
                          const std::function<void(const StepRecord&)>& on_step) {
  const int n = controller.n();
  if (settings.q0.size() != n || settings.v0.size() != n) {
    throw std::invalid_argument("initial state must have " + std::to_string(n) + " entries, got " +
                                std::to_string(settings.q0.size()));
  }
  if (!(settings.duration > 0)) {
    throw std::invalid_argument("duration must be positive, got " + std::to_string(settings.duration));
  }
  const double dt = controller.dt();
  if (!(settings.duration / dt <= kMaxSteps)) {
    throw std::invalid_argument("duration " + std::to_string(settings.duration) + " s is more than 1e9 control steps of " +
                                std::to_string(dt) + " s");
  }
  const long steps = std::lround(settings.duration / dt);
  if (steps < 1) {
    throw std::invalid_argument("duration " + std::to_string(settings.duration) +
                                " s is shorter than one control step (dt = " + std::to_string(dt) + " s)");
  }
  const std::string timestep_warning = plant.set_control_period(dt);
  RunResult result;
  if (!timestep_warning.empty()) result.warnings.push_back(timestep_warning);
  try {
    plant.reset(settings.q0, settings.v0);
  } catch (const std::runtime_error& e) {
    // a MuJoCo error (load.hpp: its handler throws) at the start: nothing to run
    result.diverged = true;
    result.diverged_at = 0;
    result.divergence_reason = e.what();
    result.final_q = settings.q0;
    result.final_v = settings.v0;
    result.saturated_steps.assign(static_cast<size_t>(n), 0);
    result.final_disturbance = controller.disturbance();
    return result;
  }
  controller.solver().enable_timing(settings.phase_timing);

  const long kept = std::max(1L, settings.kept_update_times);
  result.update_ms.reserve(static_cast<size_t>(std::min(steps, kept)));
  std::mt19937_64 sampler(0x1d3c);  // reservoir sampling beyond `kept`, reproducible
  VecX<double> q = plant.q(), v = plant.v();
  TrackingMeter meter(plant.model(), settings.tracking, n);
  // the task's stage cost at each step's own time (the controller's references are those of its
  // last update, which latency and the solver's look-ahead h move away from t)
  const StageTerms& terms = controller.problem().terms();
  StageTerms::CostScratch cost_scratch = terms.cost_scratch();
  // the torque applied over the current period; the controller's output applies over the next
  VecX<double> tau = controller.initialize(q, v), tau_cmd = controller.commanded_torque();
  result.init_residual = controller.residual_norm();
  result.saturated_steps.assign(static_cast<size_t>(n), 0);
  if (!controller.failure().empty()) {
    // no torque to start with: a divergence at t = 0, nothing applied, nothing logged
    result.diverged = true;
    result.diverged_at = 0;
    result.divergence_reason = controller.failure();
    result.final_q = q;
    result.final_v = v;
    result.final_q_error = meter.joint_error(0, q, controller);
    result.final_v_norm = v.norm();
    return result;
  }
  double residual_sum = 0, error_sum = 0;
  UpdateTimes phase_sum;
  const double period_ms = 1e3 * dt;

  // compute latency (formulations.md §Compute latency): plant steps are counted in MuJoCo steps δt, `substeps` per
  // control period; the torque of the last update waits for its arrival, the controller is busy
  // until control step `free_at`, and the observer learns the mean torque the plant applied since
  // the last update's measurement
  const bool late = settings.latency.on();
  const long substeps = plant.substeps();
  const double plant_dt = dt / static_cast<double>(substeps);
  long free_at = 0, arrival = -1, last_update = -1, applied_steps = 0;
  VecX<double> pending = tau, pending_cmd = tau_cmd, applied_mean = tau;
  auto applied = [&](const VecX<double>& x, long count) {
    if (count == 0) return;
    applied_steps += count;
    // a running mean, exact while the torque does not change
    if (applied_steps == count) {
      applied_mean = x;
    } else {
      applied_mean += (x - applied_mean) * (static_cast<double>(count) / static_cast<double>(applied_steps));
    }
  };

  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * dt;
    q = plant.q();
    v = plant.v();
    bool tracked = false;
    try {
      tracked = meter.measure(t, q);
    } catch (const std::runtime_error& e) {
      result.diverged = true;
      result.diverged_at = t;
      result.divergence_reason = e.what();
      break;
    }
    error_sum += meter.joint_error_squared(t, q, controller);
    const long first = k * substeps;  // the plant step at t
    if (late && arrival == first) {
      tau = pending;
      tau_cmd = pending_cmd;
      arrival = -1;
    }
    // one control update at t: the torque for t + Δt (latency: for when it is computed)
    const bool updating = !late || k >= free_at;
    double ms = std::numeric_limits<double>::quiet_NaN();
    bool ok = true;
    if (updating) {
      const auto start = std::chrono::steady_clock::now();
      ok = late && last_update >= 0
               ? controller.update(t, q, v, static_cast<double>(k - last_update) * dt, applied_mean)
               : controller.update(t, q, v);
      ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      const double compute_ms = settings.latency.kind == Latency::Kind::kFixed ? settings.latency.ms : ms;
      if (ok && compute_ms > period_ms) ++result.deadline_misses;
      if (ok && late) {
        // its torque reaches the plant after the whole plant steps its computation took
        // at least one plant step (a torque never acts at its own measurement's instant: a compute
        // time of 0 runs as the paper's timing), and one after the run's end when it would arrive
        // later (1e19 ms and more do not fit a long)
        const double ratio = 1e-3 * compute_ms / plant_dt;
        const long never = steps * substeps + 1;
        const long delay = !(ratio < static_cast<double>(never))
                               ? never
                               : std::max(1L, static_cast<long>(std::ceil(ratio - 1e-9 * std::max(1.0, ratio))));
        free_at = k + std::max(1L, (delay + substeps - 1) / substeps);
        ok = controller.aim(dt * (static_cast<double>(delay) / static_cast<double>(substeps)));
        pending = controller.torque();
        pending_cmd = controller.commanded_torque();
        arrival = first + delay;
        last_update = k;
        applied_steps = 0;
      }
    }

    std::string reason = ok ? "" : controller.failure();
    // the row holds the measured state, the torque applied at t (over [t, t + Δt) unless a late
    // torque arrives within the period) and this update
    on_step(StepRecord{t, q, v, tau, tau_cmd, controller.residual_norm(), ms, tracked ? &meter.position() : nullptr,
                       tracked ? &meter.target() : nullptr});
    result.steps = static_cast<int>(k + 1);
    if (reason.empty()) {
      if (updating) {
        ++result.updates;
        result.mean_update_ms += (ms - result.mean_update_ms) / static_cast<double>(result.updates);
        result.max_update_ms = std::max(result.max_update_ms, ms);
        if (result.updates <= kept) {
          result.update_ms.push_back(ms);
        } else {
          const auto slot = std::uniform_int_distribution<long>(0, result.updates - 1)(sampler);
          if (slot < kept) result.update_ms[static_cast<size_t>(slot)] = ms;
        }
        residual_sum += controller.residual_norm();
        result.max_constraint_violation =
            std::max(result.max_constraint_violation, controller.constraint_violation());
        const UpdateTimes& ph = controller.solver().last_times();
        phase_sum.total += ph.total;
        phase_sum.rollout += ph.rollout;
        phase_sum.costate += ph.costate;
        phase_sum.gmres += ph.gmres;
        result.evaluations_per_update = controller.solver().evaluations();
      }
      // the task's stage cost of the measured state and the torque applied from it, every step
      result.closed_loop_cost += dt * terms.stage_cost_at(t, q, v, tau, cost_scratch);
      // saturation of the torque applied over this step
      bool any = false;
      for (int j = 0; j < n; ++j) {
        if (tau[j] != tau_cmd[j]) {
          ++result.saturated_steps[static_cast<size_t>(j)];
          any = true;
        }
      }
      result.saturated_any += any;
      bool stepped = false;
      try {
        if (!late) {
          stepped = plant.step(tau, &reason);
        } else {
          // a late torque arriving within the period takes over from its plant step on
          const long switch_at = arrival >= first && arrival < first + substeps ? arrival - first : substeps;
          stepped = plant.step(tau, static_cast<int>(switch_at), pending, &reason);
          applied(tau, switch_at);
          applied(pending, substeps - switch_at);
          if (switch_at < substeps) {
            tau = pending;
            tau_cmd = pending_cmd;
            arrival = -1;
          }
        }
      } catch (const std::runtime_error& e) {
        // a MuJoCo error in the step (its handler throws): the run ends here, as on a divergence
        stepped = false;
        reason = e.what();
      }
      if (!stepped) {
        // the plant blew up under this torque: reason says how
      } else if (plant.v().cwiseAbs().maxCoeff() > kMaxSpeed) {
        reason = "joint speed exceeded 1e4";
      }
    }
    if (!reason.empty()) {
      result.diverged = true;
      result.diverged_at = t;
      result.divergence_reason = reason;
      break;
    }
    if (!late) {
      tau = controller.torque();
      tau_cmd = controller.commanded_torque();
    }
  }

  const double m = std::max<double>(1.0, static_cast<double>(result.updates));
  result.mean_residual = residual_sum / m;
  result.mean_phase_ms = UpdateTimes{1e3 * phase_sum.total / m, 1e3 * phase_sum.rollout / m,
                                     1e3 * phase_sum.costate / m, 1e3 * phase_sum.gmres / m};
  // after a divergence the plant may have been reset: the last measured state is the outcome
  result.final_q = result.diverged ? q : plant.q();
  result.final_v = result.diverged ? v : plant.v();
  const double t_end = static_cast<double>(result.diverged ? result.steps - 1 : result.steps) * dt;
  result.final_q_error = meter.joint_error(t_end, result.final_q, controller);
  if (!result.diverged) {
    try {
      meter.measure(t_end, result.final_q);  // the state the run ends in
    } catch (const std::runtime_error& e) {
      result.diverged = true;
      result.diverged_at = t_end;
      result.divergence_reason = e.what();
    }
  }
  result.tracking = meter.result();
  result.final_v_norm = result.final_v.norm();
  result.joint_error_rms = std::sqrt(error_sum / std::max<double>(1.0, static_cast<double>(result.steps)));
  result.contact_steps = plant.contact_steps();
  result.max_contact_force = plant.max_contact_force();
  result.final_disturbance = controller.disturbance();
  return result;
}

}  // namespace idmpc::mj
