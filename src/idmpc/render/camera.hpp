#pragma once
/// @file camera.hpp
/// @brief The video's camera: a camera of the model, or a free camera that frames the whole
/// motion of the replayed runs beside the overlays.

#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "idmpc/render/frame_path.hpp"
#include "idmpc/render/framing.hpp"
#include "idmpc/render/replay.hpp"

namespace idmpc::render {

/// @brief A parsed --camera option.
struct CameraSpec {
  enum class Kind { kAuto, kFixed, kOrbit } kind = Kind::kAuto;
  std::string name;                                 ///< kFixed
  double azimuth = 0, elevation = 0, distance = 0;  ///< kOrbit
};

/// @brief Parses "auto", "fixed:<name>" or "azimuth,elevation,distance"; throws
/// std::invalid_argument naming the option, the expected forms and the text otherwise.
CameraSpec parse_camera(const std::string& text);

/// @brief Id of the model camera a "fixed:<name>" spec names (-1 for other specs); throws
/// std::invalid_argument listing the model's cameras when there is no such camera.
int find_fixed_camera(const mjModel* m, const CameraSpec& spec, const std::string& model_path);

/// @brief Where the runs go over the whole video.
struct Motion {
  Bounds visible;  ///< every visible geom (moving and static) over all frames, and the frame paths
  Bounds bodies;   ///< origins of the moving bodies: tells a planar motion
};

/// @brief Replays every frame of the schedule (one mjData per run) and bounds the motion, with
/// every position and target of the runs' frame paths (logs with frame columns).
Motion measure_motion(const mjModel* m, const std::vector<mjData*>& datas,
                      const std::vector<Replay>& replays, const Schedule& schedule,
                      const mjvOption& opt);

/// @brief Where the robot's moving geoms appear in the image over the whole video, as MuJoCo
/// projects them with `cam` (fixed, free or tracking) on a width x height viewport: per frame
/// and run, the screen box of each geom in pieces about as long as it is thick (a diagonal link
/// marks a band, not its whole bounding square), on a grid of cells of at most 8 pixels. A geom
/// reaching behind the camera marks the whole image. The frame paths' dots and trail vertices
/// are marked too, each as large as the current target's marker. `scn` is scratch.
ScreenMask robot_footprint(const mjModel* m, const std::vector<mjData*>& datas,
                           const std::vector<Replay>& replays, const Schedule& schedule,
                           const mjvOption& opt, mjvCamera& cam, mjvScene& scn, int width,
                           int height, const std::vector<FramePath>& paths = {});

/// @brief Where the motion may go: the frame minus a margin, beside or above/below each
/// overlay (normalized device coordinates); one candidate region per combination.
std::vector<ScreenRegion> free_regions(const std::vector<ScreenRegion>& overlays);

/// @brief The camera: a fixed one of the model, or a free one placed so the whole motion fits
/// in one of the free regions (a planar motion seen square-on, a spatial one from the front
/// left; an orbit spec fixes the angles and the distance). `free_cam` receives the free
/// camera's placement.
mjvCamera make_camera(const mjModel* m, const CameraSpec& spec, int fixed_camid,
                      const Motion& motion, const std::vector<ScreenRegion>& regions,
                      double aspect, FreeCamera& free_cam);

}  // namespace idmpc::render
