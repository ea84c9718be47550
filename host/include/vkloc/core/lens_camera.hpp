// vkloc: lens camera models (pinhole with radial-tangential distortion, equidistant /
// Kannala-Brandt, Mei unified, double sphere): projection, unprojection, their Jacobians and the
// field of view where they are valid. Eigen only.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>

#include "vkloc/core/camera.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Projection models. Pixel convention and intrinsics as PinholeCamera (pixel centres at
/// integers, x right, y down, z forward); every model maps a camera-frame direction to a point
/// (mx, my) of a normalized plane first, then u = fx mx + cx, v = fy my + cy.
enum class LensModel {
  kPinhole,        ///< m = (x, y) / z, then radial-tangential distortion (Brown-Conrady,
                   ///< OpenCV's k1 k2 p1 p2 k3; all zero = ideal pinhole).
  kKannalaBrandt,  ///< Equidistant: theta = atan2(r, z), theta_d = theta (1 + k1 t^2 + k2 t^4 +
                   ///< k3 t^6 + k4 t^8), m = theta_d (x, y) / r (OpenCV fisheye, Kalibr "equi").
  kMei,            ///< Unified (Mei 2007, CamOdoCal "MEI", Kalibr "omni"): p / |p| shifted by xi
                   ///< along z, m = (xs, ys) / (zs + xi), then radial-tangential k1 k2 p1 p2.
  kDoubleSphere,   ///< Usenko 2018: d1 = |p|, d2 = |(x, y, xi d1 + z)|,
                   ///< m = (x, y) / (alpha d2 + (1 - alpha)(xi d1 + z)).
};

/// "pinhole", "kannala_brandt", "mei", "double_sphere".
const char* lensModelName(LensModel model);
/// Parses the names above; kUnsupported naming the known ones otherwise.
Result<LensModel> parseLensModel(const std::string& name);

/// A calibrated camera: model, intrinsics (fx fy cx cy, pixels; image size) and lens parameters.
struct LensCamera {
  LensModel model = LensModel::kPinhole;
  PinholeCamera intrinsics;
  /// kPinhole: k1 k2 p1 p2 k3; kKannalaBrandt: k1 k2 k3 k4 (k[4] unused); kMei: k1 k2 p1 p2
  /// (k[4] unused); kDoubleSphere: unused. Unused entries must be zero.
  std::array<double, 5> k{};
  double xi = 0.0;     ///< kMei: mirror parameter (>= 0); kDoubleSphere: xi (-1..1).
  double alpha = 0.0;  ///< kDoubleSphere: alpha (0..1).
  /// Optional limit on the angle between a ray and the optical axis, degrees (half the field of
  /// view); 0: the model's own limit only. A real lens's image circle ends before its model does.
  double max_angle_deg = 0.0;

  bool isIdealPinhole() const;  ///< kPinhole with k all zero (max_angle_deg may still cap it).
};

/// Checks intrinsics (validateCamera), finite parameters in the ranges above, and that the model
/// is invertible somewhere (a distortion that folds over within one pixel of the optical axis is
/// refused). kInvalidArgument naming the parameter and what is wrong ("k1 = nan: not finite",
/// "k[4] = 0.1: unused by kannala_brandt, must be 0").
Status validateLensCamera(const LensCamera& camera);

/// Largest angle from the optical axis (radians) at which project() is valid: the model's own
/// domain (pinhole: z > 0 and, with distortion, the radius before the radial distortion r radial(r)
/// stops growing, and |m| <= 1e6; Kannala-Brandt: where theta_d(theta) is increasing, < pi; Mei:
/// zs > -1/xi for xi > 1, zs > -xi (and |m| <= 1e6) otherwise, and before its radial distortion
/// stops growing; double sphere: z > -w2 |p|, Usenko 2018 sec. III-F), capped by max_angle_deg.
/// Whether a ray exactly at this angle projects depends on rounding; any ray beyond it does not.
/// The limit is radial: close to a radial fold, tangential terms can fold the image a little
/// earlier in some directions, where two rays share a pixel and unprojection returns one of them.
/// Costs a root search of the distortion's slope (under a microsecond).
double lensMaxAngle(const LensCamera& camera);

/// Projects a camera-frame point (metres, any non-zero length) to a pixel. Returns false, with
/// uv and J unchanged, when the point lies outside the valid field of view (lensMaxAngle) or at
/// the centre, or is not finite; never produces NaN. J (optional): d(u, v) / d(x, y, z), analytic
/// (false also when J overflows: rays within about 1e-150 of a pole of the model).
/// O(1) for rays well inside the field; near a distortion's fold it also searches for the fold.
bool projectLens(const LensCamera& camera, const Eigen::Vector3d& p_camera, Eigen::Vector2d& uv,
                 Eigen::Matrix<double, 2, 3>* J = nullptr);

/// The unit ray (camera frame) that projects to pixel `uv`. Returns false, with ray and J
/// unchanged, when no ray inside the valid field of view projects there (beyond the image
/// circle) or the iteration that inverts a distortion does not converge to 1e-12 (in the
/// normalized plane, relative beyond |m| = 1). J (optional): d(ray) / d(u, v), in the tangent
/// plane of the unit sphere at the ray.
bool unprojectLens(const LensCamera& camera, const Eigen::Vector2d& uv, Eigen::Vector3d& ray,
                   Eigen::Matrix<double, 3, 2>* J = nullptr);

}  // namespace vkloc
