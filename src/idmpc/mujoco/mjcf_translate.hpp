#pragma once
/// @file mjcf_translate.hpp
/// @brief MJCF written for MuJoCo >= 2.3 (3.x), translated in memory for this build's MuJoCo 2.2:
/// every attribute with an exact MuJoCo 2.2 equivalent is rewritten (in the text MuJoCo parses,
/// or in the compiled mjModel where only the compiler knows the numbers), and what has none is
/// listed. The user's files are never written.
///
/// Before compilation (the text):
/// - `<compiler autolimits>` defaults to true from MuJoCo 3.0.0 on and to false before (2.2 and
///   2.3 included, which refuse a range without its limited flag): it is set to
///   true when the file leaves it out and some range (joint or tendon range, actuator ctrlrange,
///   forcerange or actrange) is given without its limited flag, directly or through default
///   classes.
/// - `integrator="implicitfast"` becomes `implicit` (a different integrator: implicit also keeps
///   the Coriolis and centrifugal derivatives that implicitfast leaves out).
/// - keyframe vectors lose leading and trailing blanks (MuJoCo 2.2 reads a trailing blank as a
///   missing number).
/// - `<compiler assetdir>` becomes meshdir and texturedir where those are not given.
/// - body `gravcomp` (any value, on any bodies) is kept as one custom numeric field, each body's
///   value by body index, which MuJoCo 2.2's passive-force callback applies (gravcomp.hpp); a
///   joint's `actuatorgravcomp="true"` is the same force when the joint has no actuatorfrcrange
///   (with one, the compensation shares the actuator's clamp: refused).
/// - no-op values are dropped: `gravcomp="0"`, `actuatorgravcomp="false"`, `actearly="false"`,
///   `<flag eulerdamp="enable">` (MuJoCo 2.2's Euler integrator always treats damping
///   implicitly); camera `resolution` is dropped too (MuJoCo 2.2 cameras have none, and it
///   affects no computation of MuJoCo 2.2).
///
/// After compilation (the mjModel), from the attributes as resolved through default classes
/// (`class`, `childclass` and the class tree), as MuJoCo >= 2.3 resolves them:
/// - `kv` and `dampratio` of `<position>`/`<intvelocity>`: actuator_biasprm[2] = −kv, or
///   −dampratio·2·√(kp·m) with m = Σ dof_M0/moment² at qpos0 (joint inertia with armature,
///   through the transmission), MuJoCo 3's formula. MuJoCo 2.2's position shortcut clears the
///   bias, so a kv inherited from a class is lost without this.
/// - `inheritrange="r"`: ctrlrange (actrange for `<intvelocity>`) = centre ± r·half-width of the
///   target joint's or tendon's range.
/// - joint `actuatorfrcrange`: when exactly one actuator (joint transmission, gear g) drives the
///   joint, that actuator's forcerange ∩ actuatorfrcrange/g, forcelimited; when none does, it
///   is kept as the joint's torque range (JointForceRanges) for the caller.
///
/// Not an XML validator: a file tinyxml2 cannot parse, or whose root is not `<mujoco>`, is left
/// to MuJoCo.

#include <string>
#include <utility>
#include <vector>

#include <mujoco/mujoco.h>

namespace idmpc::mj {

/// @brief A change to make in the compiled model, for one actuator.
struct ActuatorPatch {
  int actuator = -1;          ///< index in document order = compiled order
  std::string where;          ///< e.g. "<position> 'a1', line 40"
  bool set_bias = false;      ///< actuator_biasprm[2] as MuJoCo >= 2.3 sets it
  double bias = 0;            ///< < 0: −kv; > 0: a damping ratio
  std::string bias_source;    ///< "kv 450", "dampratio 1 (class 'arm')", …
  double inheritrange = 0;    ///< > 0: ctrlrange (actrange if `activation`) from the target
  bool activation = false;    ///< `<intvelocity>`: inheritrange sets actrange
};

/// @brief A joint's actuatorfrcrange (limited), to place after compilation.
struct JointForcePatch {
  int joint = -1;       ///< compiled joint index (body order)
  std::string where;    ///< e.g. "<joint> 'j1', line 12"
  double lower = 0, upper = 0;
};

/// @brief What translate_mjcf found.
struct GravcompPatch {
  int body = -1;        ///< compiled body index (depth-first order)
  std::string where;    ///< e.g. "<body> 'link1', line 72"
  double value = 0;     ///< gravcomp (≠ 0)
};

/// @brief One translation made: a few words naming its kind ("kv", "inheritrange", …; the
/// one-line notice counts them) and its full line (where, what became what).
struct Translation {
  std::string kind;
  std::string text;
};

struct MjcfTranslation {
  /// files to give MuJoCo in place of those on disk: (path, translated text); empty if the
  /// model needs no translation
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<Translation> notices;         ///< one per translation made in the text
  std::vector<std::string> untranslatable;  ///< one item per attribute/element without equivalent
  std::vector<ActuatorPatch> actuators;
  std::vector<JointForcePatch> joints;
  std::vector<GravcompPatch> gravcomp;
  /// true if anything is to be translated (text or compiled model)
  bool needed() const { return !files.empty() || !actuators.empty() || !joints.empty() || !gravcomp.empty(); }
};

/// @brief Joints to weld in the text: the controller's model of an arm whose gripper it holds
/// (hold.hpp). Each welded joint is removed and its body placed where the joint held it; what
/// names a welded joint goes with it (fixed tendons over welded joints only, the actuators on
/// those tendons or joints, joint equalities), and so do the keyframes and sensors (their sizes
/// change; neither acts on the dynamics).
struct Weld {
  struct Body {
    int body = -1;                ///< compiled body index
    double pos[3] = {0, 0, 0};    ///< its placement in its parent with the joints held
    double quat[4] = {1, 0, 0, 0};
  };
  std::vector<int> joints;        ///< compiled joint indices; each body's joints all, or none
  std::vector<Body> bodies;
};

/// @brief Reads the MJCF file at `path` and its includes (resolved against the directory of
/// `path`, as MuJoCo 2.2 does) and translates them, welding the joints of `weld` if given.
/// Untranslatable items are listed, not thrown; the translated text then leaves them out, so
/// that compiling it can still find what the compiled model alone reveals. Throws
/// std::invalid_argument for a weld the text cannot take (a fixed tendon over welded and other
/// joints).
MjcfTranslation translate_mjcf(const std::string& path, const Weld* weld = nullptr);

/// @brief Torque range per joint (mjModel joint index) from actuatorfrcrange on joints that no
/// actuator drives; ±infinity elsewhere.
struct JointForceRanges {
  std::vector<double> lower, upper;
};

/// @brief Applies the compiled-model part of `t` to `m`: appends a notice per change and an item
/// to `untranslatable` for what turns out to have no MuJoCo 2.2 equivalent (several actuators
/// behind one actuatorfrcrange, an inheritrange target without a range, …).
JointForceRanges apply_translation(mjModel* m, const MjcfTranslation& t, std::vector<Translation>& notices,
                                   std::vector<std::string>& untranslatable);

}  // namespace idmpc::mj
