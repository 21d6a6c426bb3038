#pragma once
// Pinhole camera.

#include <Eigen/Core>
#include <string>

namespace lambert {

/// A pinhole camera: position, target, up vector, vertical field of view and image size.
struct Camera {
  Eigen::Vector3d eye = Eigen::Vector3d(0, 0, -1);
  Eigen::Vector3d look_at = Eigen::Vector3d(0, 0, 0);
  Eigen::Vector3d up = Eigen::Vector3d(0, 1, 0);
  double vfov_degrees = 40.0;  ///< full vertical field of view
  int width = 512;
  int height = 512;
  bool defined = false;  ///< false until a scene or the user sets it
  /// True when framed by a rule (a loader's default view), not given by a camera file
  bool automatic = false;

  /// World-space direction (not normalised) through pixel position (px, py), with
  /// (0,0) the top-left corner of the image and (width, height) the bottom-right.
  Eigen::Vector3d ray_direction(double px, double py) const;
};

/// Why `camera` cannot form an image ("" when it can): `look_at` equal to (or, numerically,
/// indistinguishable from) `eye`, or `up` parallel to the view direction (|forward x up| of
/// the unit vectors <= 1e-6, where the image's right axis has lost about 6 of its 16
/// digits). Names the offending setting first ("look_at ...", "up ...").
std::string camera_problem(const Camera& camera);

/// The published Cornell box camera: eye (278, 273, -800) looking along +z, up +y,
/// 35 mm focal length on a 25 mm film: vfov = 2 atan(12.5/35) = 39.3077 degrees.
Camera cornell_camera();

/// A camera that frames the bounding box [lo, hi] from the -z side.
Camera framing_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);

/// A scene's default view when its file names none: the bounding box [lo, hi] framed from a
/// three-quarter view, 35° around the `up` axis (1 = y, 2 = z) from the front and 30° above
/// it, so a flat part is never seen edge-on and a box shows three faces. The front is -z for
/// a y-up scene (OBJ's convention) and -y for a z-up one (STL's, CAD's).
Camera three_quarter_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up);

/// A view from inside a closed room with bounding box [lo, hi]: from near its front-side
/// corner (the three-quarter view's side), a little above mid-height, across the room to the
/// far corner, 70° wide. `up` as for three_quarter_camera.
Camera room_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up);

/// The named views of a bounding box (--view): front (from the front, level), three-quarter
/// (three_quarter_camera) or top (from straight above, the front at the bottom of the
/// picture). `up` as for three_quarter_camera. Throws nothing; an unknown name is a check.
Camera view_camera(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int up,
                   const std::string& view);

}  // namespace lambert
