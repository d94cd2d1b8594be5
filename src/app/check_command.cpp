// idmpc check MODEL: summary of the imported model, then our dynamics against MuJoCo and our
// derivatives against finite differences at random states.
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include "app/commands.hpp"
#include "app/number_options.hpp"
#include "idmpc/mujoco/check.hpp"
#include "idmpc/mujoco/load.hpp"

namespace idmpc::app {
namespace {

struct CheckOptions {
  std::string model;
  int samples = 20;
  unsigned seed = 1;
  bool direct_torque = false;
  bool actuate_every_joint = false;
};

// `actuation_problem`: why the controller could not drive the model as it is ("" if it can)
void print_summary(const mjModel* m, const mj::ImportedModel& imported, const std::string& actuation_problem) {
  const Model& model = imported.model;
  std::printf("model %s: %d dofs, %d bodies, gravity (%g, %g, %g)\n", model.name.c_str(), model.n,
              m->nbody - 1, model.gravity.x(), model.gravity.y(), model.gravity.z());
  for (int i = 0; i < model.n; ++i) {
    const Vec3<double>& s = model.axis[i];
    // a hinge moves by an angle under a torque, a slide by a length under a force
    const bool hinge = model.joint_type[i] == JointType::kRevolute;
    const bool actuated =
        std::find(model.unactuated_joints.begin(), model.unactuated_joints.end(), i) == model.unactuated_joints.end();
    std::printf("  %2d %-16s %-6s axis (%+.3f %+.3f %+.3f)  parent %2d  mass %.4g  q [%s], tau [%s]%s%s\n",
                i, model.joint_names[i].c_str(), hinge ? "hinge" : "slide", s.x(), s.y(), s.z(),
                model.parent[i], model.I[i].m, hinge ? "rad" : "m", hinge ? "N m" : "N",
                model.armature[i] || model.damping[i] || model.stiffness[i] ? "  (passive/armature)" : "",
                actuated ? "" : "  UNACTUATED");
  }
  if (actuation_problem.empty()) {
    std::printf("actuation: %s\n", imported.actuation.summary().c_str());
    for (const auto& n : imported.notices) std::printf("  - %s\n", n.c_str());
  } else {
    std::printf("actuation: not usable by the controller as it is (%s)\n", actuation_problem.c_str());
  }
  if (imported.unmodeled.empty()) {
    std::printf("unmodeled by the controller: nothing\n");
  } else {
    std::printf("unmodeled by the controller (the plant still has them):\n");
    for (const auto& u : imported.unmodeled) std::printf("  - %s\n", u.c_str());
  }
}

void run(const CheckOptions& opt) {
  if (opt.samples < 1) {
    throw std::invalid_argument("--samples must be at least 1, got " + std::to_string(opt.samples));
  }
  // joints the controller holds (a gripper's fingers) are welded in its model, as in swingup,
  // at the model's reference configuration
  const mj::ControllerModel models = mj::load_controller_model(opt.model, "", !opt.direct_torque);
  const mj::LoadedModel& full = models.full;
  const mj::HeldJoints& held = models.held;
  if (!full.translations.empty()) {
    std::printf("%s\n", full.notice().c_str());
    for (const mj::Translation& t : full.translations) std::printf("  - %s\n", t.text.c_str());
  }
  const mj::LoadedModel& loaded = models.controller();
  const mjModel* m = loaded.model.get();
  if (!held.empty()) std::printf("%s\n", held.notice(full.model.get()).c_str());
  mj::ImportOptions options;
  options.direct_torque = opt.direct_torque;
  options.actuate_every_joint = opt.actuate_every_joint;
  options.joint_force_lower = loaded.joint_force_lower;
  options.joint_force_upper = loaded.joint_force_upper;
  // the comparison with MuJoCo needs no actuators: with actuators the controller cannot use, the
  // dynamics are still compared, then check fails with the reason swingup would give (a model
  // the import refuses whatever its actuators is refused at once)
  std::string actuation_problem;
  mj::ImportedModel imported = [&] {
    try {
      return mj::import_model(m, opt.model, options);
    } catch (const std::invalid_argument& e) {
      mj::ImportOptions direct = options;
      direct.direct_torque = direct.actuate_every_joint = true;
      mj::ImportedModel out = mj::import_model(m, opt.model, direct);
      actuation_problem = e.what();
      return out;
    }
  }();
  print_summary(m, imported, actuation_problem);
  auto entries = mj::check_model(m, imported.model, opt.samples, opt.seed);
  if (!held.empty()) {
    const auto rows = mj::check_held(full.model.get(), held, imported.model, opt.samples, opt.seed);
    entries.insert(entries.end(), rows.begin(), rows.end());
  }
  const auto simplified = mj::reference_simplifications(m);
  if (!simplified.empty()) {
    std::printf("\nMuJoCo reference without what the controller does not model:\n");
    for (const auto& s : simplified) std::printf("  - %s switched off\n", s.c_str());
  }
  std::printf("\n%-48s %12s %10s\n", "check (worst relative error)", "error", "tolerance");
  int failed = 0;
  for (const auto& e : entries) {
    std::printf("%-48s %12.3e %10.0e  %s\n", e.quantity.c_str(), e.worst, e.tolerance,
                e.ok() ? "ok" : "FAIL");
    failed += !e.ok();
  }
  const auto warnings = mj::take_warnings();
  for (const auto& w : warnings) std::printf("MuJoCo warning: %s\n", w.c_str());
  std::fflush(stdout);
  if (failed) {
    throw std::runtime_error(std::to_string(failed) + " check(s) exceed their tolerance or are NaN on '" +
                             opt.model + "'");
  }
  std::printf("all %zu checks passed at %d random states (seed %u)\n", entries.size(),
              opt.samples, opt.seed);
  // check accepts what swingup accepts: the dynamics above are compared all the same
  if (!actuation_problem.empty()) throw std::runtime_error(actuation_problem);
}

}  // namespace

void register_check(CLI::App& app) {
  auto opt = std::make_shared<CheckOptions>();
  CLI::App* sub = app.add_subcommand(
      "check", "Compare our ID, FD, M with MuJoCo and our derivatives with finite differences");
  sub->add_option("model", opt->model, "MJCF/URDF model file")->required();
  sub->add_option("--samples", opt->samples, "number of random states")->capture_default_str();
  sub->add_option("--seed", opt->seed, "random seed")->capture_default_str();
  sub->add_flag("--direct-torque", opt->direct_torque,
                "ignore the model's actuators and apply joint torques directly");
  sub->add_flag("--actuate-every-joint", opt->actuate_every_joint,
                "let direct torques drive the joints the model has no actuator for (under-actuated models)");
  require_decimal_numbers(*sub);
  sub->callback([opt] { run(*opt); });
}

}  // namespace idmpc::app
