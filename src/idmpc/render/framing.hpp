#pragma once
/// @file framing.hpp
/// @brief Automatic framing: a free camera that fits a world box into a region of the image.

#include <array>
#include <vector>

namespace idmpc::render {

using Vec3 = std::array<double, 3>;

/// @brief An axis-aligned box in world coordinates, grown point by point.
struct Bounds {
  Vec3 lo{kEmptyLo, kEmptyLo, kEmptyLo};
  Vec3 hi{kEmptyHi, kEmptyHi, kEmptyHi};

  /// @brief Grows the box to contain the box of half-extents `half` centred at p[0..2].
  void extend(const double* p, const Vec3& half);
  bool empty() const { return !(lo[0] <= hi[0]); }
  Vec3 center() const;
  Vec3 extent() const;
  /// @brief The largest side.
  double size() const;

 private:
  static constexpr double kEmptyLo = 1e300;
  static constexpr double kEmptyHi = -1e300;
};

/// @brief A rectangle of the image in normalized device coordinates ([-1, 1], y up).
struct ScreenRegion {
  double x_lo = -1, x_hi = 1, y_lo = -1, y_hi = 1;
  double width() const { return x_hi - x_lo; }
  double height() const { return y_hi - y_lo; }
};

/// @brief Where something appears in the image: a grid of cells over normalized device
/// coordinates, each marked once anything touched it.
class ScreenMask {
 public:
  /// @brief An unmarked columns x rows grid (each at least 1).
  ScreenMask(int columns, int rows);
  /// @brief Marks every cell the region touches (its part inside the image).
  void mark(const ScreenRegion& r);
  /// @brief Marks every cell.
  void mark_all();
  /// @brief Number of marked cells the region touches.
  int count(const ScreenRegion& r) const;
  /// @brief Number of marked cells.
  int count() const;
  int columns() const { return columns_; }
  int rows() const { return rows_; }

 private:
  // the cells [c0, c1) x [r0, r1) a region touches; false when it misses the image
  bool cell_range(const ScreenRegion& r, int& c0, int& c1, int& r0, int& r1) const;

  int columns_ = 1;
  int rows_ = 1;
  std::vector<unsigned char> cells_;  // row-major, row 0 at the bottom (y = -1)
};

/// @brief A MuJoCo free camera (mjvCamera with type mjCAMERA_FREE).
struct FreeCamera {
  Vec3 lookat{0, 0, 0};
  double distance = 1;
  double azimuth = 90;    ///< degrees; 90 looks along +y
  double elevation = -12; ///< degrees; negative looks down
};

/// @brief Unit forward, up and right vectors of a free camera, as mjv_updateCamera builds them.
void camera_axes(double azimuth, double elevation, Vec3& forward, Vec3& up, Vec3& right);

/// @brief The closest free camera with the given angles (degrees) whose view of the whole box
/// lies inside `region`, centred in it. fovy_deg is the vertical field of view and aspect the
/// image width / height. Returns distance < 0 when no distance fits (a degenerate region).
FreeCamera fit_camera(const Bounds& box, double azimuth, double elevation, double fovy_deg,
                      double aspect, const ScreenRegion& region);

/// @brief Of several candidate regions, the camera that shows the box largest (smallest
/// distance); `regions` must not be empty.
FreeCamera fit_camera_best(const Bounds& box, double azimuth, double elevation, double fovy_deg,
                           double aspect, const std::vector<ScreenRegion>& regions);

}  // namespace idmpc::render
