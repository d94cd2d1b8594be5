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

  // the frame's position and target at (t, q), accumulated; false without a frame; q is the
  // model's whole qpos
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

// the run ends at t, diverged for `reason`
void record_divergence(RunResult& result, double t, const std::string& reason) {
  result.diverged = true;
  result.diverged_at = t;
  result.divergence_reason = reason;
}

// the control steps of a run, its settings checked
long control_steps(const Controller& controller, const ClosedLoopSettings& settings) {
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
  return steps;
}

// the plant at (q0, v0); false after a MuJoCo error (load.hpp: its handler throws), the run
// recorded as diverged at the start with nothing to run
bool reset_plant(Plant& plant, const Controller& controller, const ClosedLoopSettings& settings, RunResult& result) {
  try {
    plant.reset(settings.q0, settings.v0);
  } catch (const std::runtime_error& e) {
    record_divergence(result, 0, e.what());
    result.final_q = settings.q0;
    result.final_v = settings.v0;
    result.saturated_steps.assign(static_cast<size_t>(controller.n()), 0);
    result.final_disturbance = controller.disturbance();
    return false;
  }
  return true;
}

// a run of the closed loop on a reset plant: start, then each control step until the run's end
// or a divergence, then end; the steps share the measured state, the torques and the sums over
// the run, and fill in the result
class ClosedLoop {
 public:
  ClosedLoop(Plant& plant, Controller& controller, const ClosedLoopSettings& settings,
             const std::function<void(const StepRecord&)>& on_step, long steps, RunResult& result)
      : plant_(plant),
        controller_(controller),
        settings_(settings),
        on_step_(on_step),
        result_(result),
        n_(controller.n()),
        dt_(controller.dt()),
        steps_(steps),
        kept_(std::max(1L, settings.kept_update_times)),
        q_(plant.q()),
        v_(plant.v()),
        meter_(plant.model(), settings.tracking, n_),
        terms_(controller.problem().terms()),
        cost_scratch_(terms_.cost_scratch()),
        period_ms_(1e3 * dt_),
        late_(settings.latency.on()),
        substeps_(plant.substeps()),
        plant_dt_(dt_ / static_cast<double>(substeps_)) {}

  // the controller initialized at the plant's state, its torque the one applied over the first
  // period; false when it has none (a divergence at t = 0, nothing applied, nothing logged)
  bool start() {
    result_.update_ms.reserve(static_cast<size_t>(std::min(steps_, kept_)));
    tau_ = controller_.initialize(q_, v_);
    tau_cmd_ = controller_.commanded_torque();
    result_.init_residual = controller_.residual_norm();
    result_.saturated_steps.assign(static_cast<size_t>(n_), 0);
    if (!controller_.failure().empty()) {
      record_divergence(result_, 0, controller_.failure());
      result_.final_q = q_;
      result_.final_v = v_;
      result_.final_q_error = meter_.joint_error(0, q_, controller_);
      result_.final_v_norm = v_.norm();
      return false;
    }
    pending_ = tau_;
    pending_cmd_ = tau_cmd_;
    applied_mean_ = tau_;
    return true;
  }

  // control step k: the plant's state measured, an update unless the controller is busy, the
  // row logged, the plant stepped over the period; false when the run ends at it (a divergence)
  bool step(long k) {
    const double t = static_cast<double>(k) * dt_;
    q_ = plant_.q();
    v_ = plant_.v();
    bool tracked = false;
    try {
      tracked = meter_.measure(t, plant_.full_q());  // held joints included
    } catch (const std::runtime_error& e) {
      record_divergence(result_, t, e.what());
      return false;
    }
    error_sum_ += meter_.joint_error_squared(t, q_, controller_);
    const long first = k * substeps_;  // the plant step at t
    if (late_ && arrival_ == first) apply_pending();
    // one control update at t: the torque for t + Δt (latency: for when it is computed)
    const bool updating = !late_ || k >= free_at_;
    double ms = std::numeric_limits<double>::quiet_NaN();
    bool ok = true;
    if (updating) ok = update(k, t, first, ms);

    std::string reason = ok ? "" : controller_.failure();
    // the row holds the measured state, the torque applied at t (over [t, t + Δt) unless a late
    // torque arrives within the period) and this update
    on_step_(StepRecord{t, q_, v_, tau_, tau_cmd_, controller_.residual_norm(), ms,
                        tracked ? &meter_.position() : nullptr, tracked ? &meter_.target() : nullptr});
    result_.steps = static_cast<int>(k + 1);
    if (reason.empty()) {
      if (updating) record_update(ms);
      record_applied_torque(t);
      step_plant(first, reason);
    }
    if (!reason.empty()) {
      record_divergence(result_, t, reason);
      return false;
    }
    if (!late_) {
      tau_ = controller_.torque();
      tau_cmd_ = controller_.commanded_torque();
    }
    return true;
  }

  // the means over the run, the state it ends in and its tracking error
  void end() {
    const double m = std::max<double>(1.0, static_cast<double>(result_.updates));
    result_.mean_residual = residual_sum_ / m;
    result_.mean_phase_ms = UpdateTimes{1e3 * phase_sum_.total / m, 1e3 * phase_sum_.rollout / m,
                                        1e3 * phase_sum_.costate / m, 1e3 * phase_sum_.gmres / m};
    // after a divergence the plant may have been reset: the last measured state is the outcome
    result_.final_q = result_.diverged ? q_ : plant_.q();
    result_.final_v = result_.diverged ? v_ : plant_.v();
    const double t_end = static_cast<double>(result_.diverged ? result_.steps - 1 : result_.steps) * dt_;
    result_.final_q_error = meter_.joint_error(t_end, result_.final_q, controller_);
    if (!result_.diverged) {
      try {
        meter_.measure(t_end, plant_.full_q());  // the state the run ends in
      } catch (const std::runtime_error& e) {
        record_divergence(result_, t_end, e.what());
      }
    }
    result_.tracking = meter_.result();
    result_.final_v_norm = result_.final_v.norm();
    result_.joint_error_rms = std::sqrt(error_sum_ / std::max<double>(1.0, static_cast<double>(result_.steps)));
    result_.contact_steps = plant_.contact_steps();
    result_.max_contact_force = plant_.max_contact_force();
    result_.final_disturbance = controller_.disturbance();
  }

 private:
  // the control update at step k (time t, plant step `first`), its wall time in `ms`; false when
  // it failed
  bool update(long k, double t, long first, double& ms) {
    const auto start = std::chrono::steady_clock::now();
    bool ok = late_ && last_update_ >= 0
                  ? controller_.update(t, q_, v_, static_cast<double>(k - last_update_) * dt_, applied_mean_)
                  : controller_.update(t, q_, v_);
    ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    const double compute_ms = settings_.latency.kind == Latency::Kind::kFixed ? settings_.latency.ms : ms;
    if (ok && compute_ms > period_ms_) ++result_.deadline_misses;
    if (ok && late_) ok = send_late(k, first, compute_ms);
    return ok;
  }

  // with latency: the torque of the update at step k, computed in `compute_ms`, becomes the
  // pending one and the controller busy until it arrives; false when aiming it failed
  bool send_late(long k, long first, double compute_ms) {
    // its torque reaches the plant after the whole plant steps its computation took
    // at least one plant step (a torque never acts at its own measurement's instant: a compute
    // time of 0 runs as the paper's timing), and one after the run's end when it would arrive
    // later (1e19 ms and more do not fit a long)
    const double ratio = 1e-3 * compute_ms / plant_dt_;
    const long never = steps_ * substeps_ + 1;
    const long delay = !(ratio < static_cast<double>(never))
                           ? never
                           : std::max(1L, static_cast<long>(std::ceil(ratio - 1e-9 * std::max(1.0, ratio))));
    free_at_ = k + std::max(1L, (delay + substeps_ - 1) / substeps_);
    const bool ok = controller_.aim(dt_ * (static_cast<double>(delay) / static_cast<double>(substeps_)));
    pending_ = controller_.torque();
    pending_cmd_ = controller_.commanded_torque();
    arrival_ = first + delay;
    last_update_ = k;
    applied_steps_ = 0;
    return ok;
  }

  // with latency: the pending torque has arrived and is applied from now on
  void apply_pending() {
    tau_ = pending_;
    tau_cmd_ = pending_cmd_;
    arrival_ = -1;
  }

  // the figures of a successful update that took `ms`
  void record_update(double ms) {
    ++result_.updates;
    result_.mean_update_ms += (ms - result_.mean_update_ms) / static_cast<double>(result_.updates);
    result_.max_update_ms = std::max(result_.max_update_ms, ms);
    if (result_.updates <= kept_) {
      result_.update_ms.push_back(ms);
    } else {
      const auto slot = std::uniform_int_distribution<long>(0, result_.updates - 1)(sampler_);
      if (slot < kept_) result_.update_ms[static_cast<size_t>(slot)] = ms;
    }
    residual_sum_ += controller_.residual_norm();
    result_.max_constraint_violation = std::max(result_.max_constraint_violation, controller_.constraint_violation());
    const UpdateTimes& ph = controller_.solver().last_times();
    phase_sum_.total += ph.total;
    phase_sum_.rollout += ph.rollout;
    phase_sum_.costate += ph.costate;
    phase_sum_.gmres += ph.gmres;
    result_.evaluations_per_update = controller_.solver().evaluations();
  }

  // the cost and the saturation of the torque applied over the step at t
  void record_applied_torque(double t) {
    // the task's stage cost of the measured state and the torque applied from it, every step
    result_.closed_loop_cost += dt_ * terms_.stage_cost_at(t, q_, v_, tau_, cost_scratch_);
    // saturation of the torque applied over this step
    bool any = false;
    for (int j = 0; j < n_; ++j) {
      if (tau_[j] != tau_cmd_[j]) {
        ++result_.saturated_steps[static_cast<size_t>(j)];
        any = true;
      }
    }
    result_.saturated_any += any;
  }

  // the plant stepped over the control period from plant step `first`; `reason` says why when it
  // blew up
  void step_plant(long first, std::string& reason) {
    bool stepped = false;
    try {
      if (!late_) {
        stepped = plant_.step(tau_, &reason);
      } else {
        stepped = step_plant_late(first, reason);
      }
    } catch (const std::runtime_error& e) {
      // a MuJoCo error in the step (its handler throws): the run ends here, as on a divergence
      stepped = false;
      reason = e.what();
    }
    if (!stepped) {
      // the plant blew up under this torque: reason says how
    } else if (plant_.v().cwiseAbs().maxCoeff() > kMaxSpeed) {
      reason = "joint speed exceeded 1e4";
    }
  }

  // with latency: a late torque arriving within the period takes over from its plant step on
  bool step_plant_late(long first, std::string& reason) {
    const long switch_at = arrival_ >= first && arrival_ < first + substeps_ ? arrival_ - first : substeps_;
    const bool stepped = plant_.step(tau_, static_cast<int>(switch_at), pending_, &reason);
    count_applied(tau_, switch_at);
    count_applied(pending_, substeps_ - switch_at);
    if (switch_at < substeps_) apply_pending();
    return stepped;
  }

  // with latency: `count` more plant steps under the torque x in the mean torque the plant applied
  // since the last update's measurement (what the observer learns)
  void count_applied(const VecX<double>& x, long count) {
    if (count == 0) return;
    applied_steps_ += count;
    // a running mean, exact while the torque does not change
    if (applied_steps_ == count) {
      applied_mean_ = x;
    } else {
      applied_mean_ += (x - applied_mean_) * (static_cast<double>(count) / static_cast<double>(applied_steps_));
    }
  }

  Plant& plant_;
  Controller& controller_;
  const ClosedLoopSettings& settings_;
  const std::function<void(const StepRecord&)>& on_step_;
  RunResult& result_;
  const int n_;
  const double dt_;
  const long steps_;
  const long kept_;                   // update times kept, beyond them a sample (RunResult::update_ms)
  std::mt19937_64 sampler_{0x1d3c};  // reservoir sampling beyond `kept_`, reproducible
  VecX<double> q_, v_;                // the state measured at the current step
  TrackingMeter meter_;
  // the task's stage cost at each step's own time (the controller's references are those of its
  // last update, which latency and the solver's look-ahead h move away from t)
  const StageTerms& terms_;
  StageTerms::CostScratch cost_scratch_;
  // the torque applied over the current period; the controller's output applies over the next
  VecX<double> tau_, tau_cmd_;
  double residual_sum_ = 0, error_sum_ = 0;
  UpdateTimes phase_sum_;
  const double period_ms_;

  // compute latency (formulations.md §Compute latency): plant steps are counted in MuJoCo steps δt,
  // `substeps_` per control period; the torque of the last update waits for its arrival, the
  // controller is busy until control step `free_at_`, and the observer learns the mean torque the
  // plant applied since the last update's measurement
  const bool late_;
  const long substeps_;
  const double plant_dt_;
  long free_at_ = 0, arrival_ = -1, last_update_ = -1, applied_steps_ = 0;
  VecX<double> pending_, pending_cmd_, applied_mean_;
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
  const long steps = control_steps(controller, settings);
  const std::string timestep_warning = plant.set_control_period(controller.dt());
  RunResult result;
  if (!timestep_warning.empty()) result.warnings.push_back(timestep_warning);
  if (!reset_plant(plant, controller, settings, result)) return result;
  controller.solver().enable_timing(settings.phase_timing);
  ClosedLoop loop(plant, controller, settings, on_step, steps, result);
  if (!loop.start()) return result;
  for (long k = 0; k < steps; ++k) {
    if (!loop.step(k)) break;
  }
  loop.end();
  return result;
}

}  // namespace idmpc::mj
