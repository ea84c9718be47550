// Continuous-time trajectories: a uniform cubic B-spline on positions and a cumulative cubic
// B-spline on SO(3), plus the built-in trajectory generators.
//
// Conventions (used throughout this file and imu_simulation.cpp):
//  - Control pose k sits at knot time t_k = t0 + k dt. For t in segment i, i.e.
//    t in [t_i, t_{i+1}) with 1 <= i <= n-3, u = (t - t_i) / dt in [0, 1) and the segment uses
//    control poses i-1 .. i+2.
//  - Uniform cubic B-spline weights (Kim, Kim, Shin 1995, eq. 4 / Sommer et al. 2020, eq. 5):
//      b0 = (1-u)^3/6, b1 = (3u^3 - 6u^2 + 4)/6, b2 = (-3u^3 + 3u^2 + 3u + 1)/6, b3 = u^3/6,
//    and the cumulative weights B~_j = sum_{k>=j} b_k:
//      B~_0 = 1, B~_1 = (5 + 3u - 3u^2 + u^3)/6, B~_2 = (1 + 3u + 3u^2 - 2u^3)/6, B~_3 = u^3/6.
//  - Position: p(t) = sum_k b_k(u) p_{i-1+k}; v = dp/dt = sum_k b_k'(u) p_{i-1+k} / dt and
//    a = sum_k b_k''(u) p_{i-1+k} / dt^2 (exact; the spline is a cubic polynomial per segment).
//  - Rotation (cumulative form): R(t) = R_{i-1} A_1 A_2 A_3 with A_j = exp(B~_j(u) d_j) and
//    d_j = log(R_{i-2+j}^T R_{i-1+j}) (the *right* increment, expressed in the earlier control
//    frame). exp/log are the SO(3) maps with the tangent w in R^3 meaning exp([w]x).
//  - Angular velocity is the body rate, [omega_body]x = R^T dR/dt (right-trivialised), which is
//    what a gyroscope measures. Because d_j commutes with exp(B~_j d_j),
//    A_j^T dA_j/dt = (dB~_j/dt) [d_j]x, and R^T dR/dt accumulates as
//      w_0 = 0,  w_j = A_j^T w_{j-1} + (dB~_j/dt) d_j,  omega_body = w_3
//    (Sommer et al. 2020, Theorem 1, eq. 38 specialised to first order).
#include "vkloc/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <random>

#include "vkloc/core/random.hpp"
#include "vkloc/core/se3.hpp"

namespace vkloc {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// Plane curve parameter theta(t) such that the curve P(theta) is traversed at `speed(t)`:
/// integrates dtheta/dt = speed(t) / |dP/dtheta| with RK4 steps of 10 ms from t_begin and returns
/// theta at the requested (increasing) times.
std::vector<double> integrateCurveParameter(const std::function<Eigen::Vector2d(double)>& curve,
                                            const std::function<double(double)>& speed, double theta0, double direction,
                                            const std::vector<double>& times_s) {
  auto rate = [&](double t, double theta) {
    constexpr double kDelta = 1e-5;
    const double dp = ((curve(theta + kDelta) - curve(theta - kDelta)) / (2.0 * kDelta)).norm();
    return direction * speed(t) / std::max(dp, 1e-9);
  };
  std::vector<double> out;
  out.reserve(times_s.size());
  double t = times_s.empty() ? 0.0 : times_s.front();
  double theta = theta0;
  constexpr double kStep = 1e-2;
  for (double target : times_s) {
    while (t < target - 1e-12) {
      const double h = std::min(kStep, target - t);
      const double k1 = rate(t, theta);
      const double k2 = rate(t + 0.5 * h, theta + 0.5 * h * k1);
      const double k3 = rate(t + 0.5 * h, theta + 0.5 * h * k2);
      const double k4 = rate(t + h, theta + h * k3);
      theta += h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
      t += h;
    }
    out.push_back(theta);
  }
  return out;
}

/// Camera rotation looking along `forward` (world) with the image up towards +z, then rolled by
/// `roll` (rad) about the optical axis.
Result<Eigen::Matrix3d> cameraRotation(const Eigen::Vector3d& eye, const Eigen::Vector3d& forward, double roll) {
  auto look = lookAt(eye, eye + forward, Eigen::Vector3d::UnitZ());
  if (!look.ok()) return look.error();
  return Eigen::Matrix3d(look->linear() * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix());
}

/// Unit vector with heading `yaw` (from +x towards +y) and elevation `pitch` (rad, up positive).
Eigen::Vector3d direction(double yaw, double pitch) {
  return Eigen::Vector3d(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch));
}

struct BoxFrame {
  Eigen::Vector3d min;
  Eigen::Vector3d max;
  Eigen::Vector3d centre() const { return 0.5 * (min + max); }
  Eigen::Vector3d half() const { return 0.5 * (max - min); }
};

struct KnotTimes {
  int64_t dt_ns = 0;
  int64_t t0_ns = 0;
  std::vector<double> times_s;  ///< Times of all control poses, seconds.
};

/// Knots so that the usable part of the spline is [0, duration]: n - 3 segments of about
/// `nominal_dt_s`, control poses from t = -dt.
KnotTimes makeKnots(double duration_s, double nominal_dt_s) {
  KnotTimes k;
  const int64_t duration_ns = static_cast<int64_t>(std::llround(duration_s * 1e9));
  const int64_t segments = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(duration_s / nominal_dt_s - 1e-9)));
  k.dt_ns = std::max<int64_t>(1, static_cast<int64_t>(std::llround(static_cast<double>(duration_ns) / segments)));
  k.t0_ns = -k.dt_ns;
  for (int64_t j = 0; j < segments + 3; ++j) k.times_s.push_back(static_cast<double>(k.t0_ns + j * k.dt_ns) * 1e-9);
  return k;
}

// ------------------------------------------------------------------------------------------------
// Generators. Each returns T_world_camera at every knot time.
// ------------------------------------------------------------------------------------------------

/// Drone: a wobbly loop around the box centre (radius up to 0.65 of the half extent, slowly
/// breathing in and out), 23-47 m above the box floor and at least `options.drone_clearance_m`
/// above `options.obstacles`, horizontal speed 3.5-7 m/s, heading along the path, camera 45 deg
/// below the horizon.
Result<std::vector<Pose>> droneCameraPoses(const BoxFrame& box, const KnotTimes& knots, Mt19937& rnd,
                                           const TrajectoryOptions& options, double tilt_scale = 0.0) {
  const Eigen::Vector3d c = box.centre();
  const Eigen::Vector3d h = box.half();
  const double ax = 0.65 * h.x();
  const double ay = 0.65 * h.y();
  const double a1 = rnd.uniform(0.05, 0.12);
  const double a2 = rnd.uniform(0.04, 0.10);
  const double f1 = rnd.uniform(0.0, 2.0 * kPi);
  const double f2 = rnd.uniform(0.0, 2.0 * kPi);
  const double f3 = rnd.uniform(0.0, 2.0 * kPi);
  const double breathe = rnd.uniform(0.3, 0.45);
  auto curve = [=](double theta) {
    const double m = 0.85 + 0.15 * std::sin(breathe * theta + f3);
    return Eigen::Vector2d(c.x() + ax * m * (std::cos(theta) + a1 * std::cos(2.0 * theta + f1)) / (1.0 + a1),
                           c.y() + ay * m * (std::sin(theta) + a2 * std::sin(3.0 * theta + f2)) / (1.0 + a2));
  };
  // Small boxes get proportionally slower flight so that turns stay smooth.
  const double speed_scale = std::clamp(std::min(ax, ay) / 40.0, 0.05, 1.0);
  const double sv1 = rnd.uniform(0.0, 2.0 * kPi);
  const double sv2 = rnd.uniform(0.0, 2.0 * kPi);
  auto speed = [=](double t) {
    return speed_scale *
           (5.25 + 1.25 * std::sin(2.0 * kPi * t / 30.0 + sv1) + 0.5 * std::sin(2.0 * kPi * t / 11.0 + sv2));
  };
  const double dir = rnd.sign();
  const std::vector<double> theta =
      integrateCurveParameter(curve, speed, rnd.uniform(0.0, 2.0 * kPi), dir, knots.times_s);
  const double z1 = rnd.uniform(0.0, 2.0 * kPi);
  const double z2 = rnd.uniform(0.0, 2.0 * kPi);
  const double pitch = -kPi / 4.0;
  // Agile (tilt_scale 1): the airframe rolls and pitches about its heading (two sines each, 0.5-1.3
  // Hz, up to about 25 deg and 3 rad/s), as a multirotor does when it manoeuvres or fights gusts;
  // acro (tilt_scale 2) twice as far and as fast. The draws are the same for both.
  const double roll1 = rnd.uniform(0.25, 0.35), roll2 = rnd.uniform(0.06, 0.1);
  const double pitch1 = rnd.uniform(0.2, 0.3), pitch2 = rnd.uniform(0.05, 0.09);
  const double fr1 = rnd.uniform(0.5, 0.8), fr2 = rnd.uniform(1.0, 1.3);
  const double fp1 = rnd.uniform(0.45, 0.75), fp2 = rnd.uniform(0.9, 1.2);
  const double pr1 = rnd.uniform(0.0, 2.0 * kPi), pr2 = rnd.uniform(0.0, 2.0 * kPi);
  const double pp1 = rnd.uniform(0.0, 2.0 * kPi), pp2 = rnd.uniform(0.0, 2.0 * kPi);
  std::vector<double> heights(theta.size());
  for (size_t k = 0; k < theta.size(); ++k) {
    const double t = knots.times_s[k];
    heights[k] =
        box.min.z() + 35.0 + 8.0 * std::sin(2.0 * kPi * t / 60.0 + z1) + 4.0 * std::sin(2.0 * kPi * t / 25.0 + z2);
  }
  if (!options.obstacles.empty()) {
    // Clearance over the buildings on the way: the upper envelope of (top + clearance) cones
    // sloping down at the climb rate in time, so the drone climbs before it reaches them.
    // max_j (needed_j - rate |t_k - t_j|) in two linear passes (forward, then backward); -inf
    // (nothing below) constrains nothing.
    const size_t n = theta.size();
    std::vector<double> envelope(n);
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector2d xy = curve(theta[k]);
      envelope[k] = options.obstacles.top(xy.x(), xy.y()) + options.drone_clearance_m;
    }
    for (size_t k = 1; k < n; ++k) {
      const double dt = knots.times_s[k] - knots.times_s[k - 1];
      envelope[k] = std::max(envelope[k], envelope[k - 1] - options.drone_climb_rate * dt);
    }
    for (size_t k = n - 1; k-- > 0;) {
      const double dt = knots.times_s[k + 1] - knots.times_s[k];
      envelope[k] = std::max(envelope[k], envelope[k + 1] - options.drone_climb_rate * dt);
    }
    for (size_t k = 0; k < n; ++k) heights[k] = std::max(heights[k], envelope[k]);
  }
  std::vector<Pose> poses;
  for (size_t k = 0; k < theta.size(); ++k) {
    const double t = knots.times_s[k];
    const Eigen::Vector2d xy = curve(theta[k]);
    const double z = heights[k];
    const Eigen::Vector2d tangent = dir * (curve(theta[k] + 1e-5) - curve(theta[k] - 1e-5));
    const double yaw = std::atan2(tangent.y(), tangent.x());
    const Eigen::Vector3d eye(xy.x(), xy.y(), z);
    auto R = cameraRotation(eye, direction(yaw, pitch), 0.0);
    if (!R.ok()) return R.error();
    Pose T = Pose::Identity();
    T.linear() = *R;
    if (tilt_scale > 0.0) {
      const double roll =
          tilt_scale * (roll1 * std::sin(2.0 * kPi * fr1 * t + pr1) + roll2 * std::sin(2.0 * kPi * fr2 * t + pr2));
      const double tilt =
          tilt_scale * (pitch1 * std::sin(2.0 * kPi * fp1 * t + pp1) + pitch2 * std::sin(2.0 * kPi * fp2 * t + pp2));
      const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
      const Eigen::Vector3d left(-std::sin(yaw), std::cos(yaw), 0.0);
      const Eigen::Matrix3d wobble =
          (Eigen::AngleAxisd(roll, forward) * Eigen::AngleAxisd(tilt, left)).toRotationMatrix();
      T.linear() = wobble * T.linear();
    }
    T.translation() = eye;
    poses.push_back(T);
  }
  return poses;
}

/// Handheld and aggressive: walk a wobbly loop around the room centre, keeping `margin` from the
/// walls, looking inwards (across the room) with head motion.
struct WalkParams {
  double radius_mean = 0.8;   ///< Loop radius as a fraction of the inner half extent.
  double radius_amp2 = 0.12;  ///< Amplitude of the 2-per-loop radius wobble (fraction).
  double radius_amp5 = 0.05;  ///< Amplitude of the 5-per-loop radius wobble (fraction).
  double speed_mean = 0.75;   ///< m/s.
  double speed_amp_slow = 0.15;
  double speed_period_slow = 7.0;
  double speed_amp_fast = 0.08;
  double speed_period_fast = 3.1;
  double shake = 0.0;          ///< Amplitude of fast position shake, m (before scaling).
  double height_amp = 0.12;    ///< Slow height variation, m.
  double bob = 0.02;           ///< Step bobbing amplitude at ~1.8 Hz, m.
  double yaw_amp_slow = 0.25;  ///< rad.
  double yaw_freq_slow = 1.0 / 7.0;
  double yaw_amp_fast = 0.06;
  double yaw_freq_fast = 1.0 / 2.3;
  double pitch_mean = -0.21;  ///< rad (about 12 deg down).
  double pitch_amp = 0.09;
  double pitch_freq = 0.2;
  double roll_amp = 0.035;
  double roll_freq = 0.25;
};

Result<std::vector<Pose>> walkCameraPoses(const BoxFrame& box, const KnotTimes& knots, Mt19937& rnd,
                                          const WalkParams& w) {
  const Eigen::Vector3d c = box.centre();
  const Eigen::Vector3d h = box.half();
  // 0.4 m from the walls for rooms; at most a quarter of the width for tiny boxes.
  const double ix = h.x() - std::min(0.4, 0.5 * h.x());
  const double iy = h.y() - std::min(0.4, 0.5 * h.y());
  const double f2 = rnd.uniform(0.0, 2.0 * kPi);
  const double f5 = rnd.uniform(0.0, 2.0 * kPi);
  auto curve = [=](double theta) {
    const double r =
        w.radius_mean + w.radius_amp2 * std::sin(2.0 * theta + f2) + w.radius_amp5 * std::sin(5.0 * theta + f5);
    return Eigen::Vector2d(c.x() + ix * r * std::cos(theta), c.y() + iy * r * std::sin(theta));
  };
  const double speed_scale = std::clamp(std::min(ix, iy) / 2.0, 0.05, 1.0);
  const double sv1 = rnd.uniform(0.0, 2.0 * kPi);
  const double sv2 = rnd.uniform(0.0, 2.0 * kPi);
  auto speed = [=](double t) {
    return speed_scale * (w.speed_mean + w.speed_amp_slow * std::sin(2.0 * kPi * t / w.speed_period_slow + sv1) +
                          w.speed_amp_fast * std::sin(2.0 * kPi * t / w.speed_period_fast + sv2));
  };
  const std::vector<double> theta =
      integrateCurveParameter(curve, speed, rnd.uniform(0.0, 2.0 * kPi), rnd.sign(), knots.times_s);
  // Fast shake: bounded so that loop + shake stays inside the margins.
  const double shake = std::min(w.shake, 0.04 * std::min(ix, iy));
  Eigen::Vector3d shake_freq(rnd.uniform(1.0, 1.2), rnd.uniform(0.8, 1.0), rnd.uniform(1.2, 1.4));
  Eigen::Vector3d shake_phase(rnd.uniform(0.0, 2.0 * kPi), rnd.uniform(0.0, 2.0 * kPi), rnd.uniform(0.0, 2.0 * kPi));
  const double height = std::min(1.5, h.z());  // Eye height above the floor, m.
  const double hz = rnd.uniform(0.0, 2.0 * kPi);
  const double bob_freq = rnd.uniform(1.7, 1.9);
  const double bob_phase = rnd.uniform(0.0, 2.0 * kPi);
  const double yaw_freq_slow = w.yaw_freq_slow * rnd.uniform(0.9, 1.1);
  const double yaw_freq_fast = w.yaw_freq_fast * rnd.uniform(0.9, 1.1);
  const double pitch_freq = w.pitch_freq * rnd.uniform(0.9, 1.1);
  const double roll_freq = w.roll_freq * rnd.uniform(0.9, 1.1);
  const double py1 = rnd.uniform(0.0, 2.0 * kPi);
  const double py2 = rnd.uniform(0.0, 2.0 * kPi);
  const double pp = rnd.uniform(0.0, 2.0 * kPi);
  const double pr = rnd.uniform(0.0, 2.0 * kPi);
  std::vector<Pose> poses;
  for (size_t k = 0; k < theta.size(); ++k) {
    const double t = knots.times_s[k];
    const Eigen::Vector2d xy = curve(theta[k]);
    Eigen::Vector3d eye(xy.x(), xy.y(),
                        box.min.z() + height + w.height_amp * std::sin(2.0 * kPi * t / 9.0 + hz) +
                            w.bob * std::sin(2.0 * kPi * bob_freq * t + bob_phase));
    for (int a = 0; a < 3; ++a) eye[a] += shake * std::sin(2.0 * kPi * shake_freq[a] * t + shake_phase[a]);
    const double yaw = std::atan2(c.y() - xy.y(), c.x() - xy.x()) +
                       w.yaw_amp_slow * std::sin(2.0 * kPi * yaw_freq_slow * t + py1) +
                       w.yaw_amp_fast * std::sin(2.0 * kPi * yaw_freq_fast * t + py2);
    const double pitch = w.pitch_mean + w.pitch_amp * std::sin(2.0 * kPi * pitch_freq * t + pp);
    const double roll = w.roll_amp * std::sin(2.0 * kPi * roll_freq * t + pr);
    auto R = cameraRotation(eye, direction(yaw, pitch), roll);
    if (!R.ok()) return R.error();
    Pose T = Pose::Identity();
    T.linear() = *R;
    T.translation() = eye;
    poses.push_back(T);
  }
  return poses;
}

/// Orbit: a circle at 30 deg elevation and a distance that fits the box's bounding sphere in a
/// 50 deg field of view, looking at the centre; at most 6 m/s and one turn per 30 s.
Result<std::vector<Pose>> orbitCameraPoses(const BoxFrame& box, const KnotTimes& knots, Mt19937& rnd) {
  const Eigen::Vector3d c = box.centre();
  const double sphere = std::max(box.half().norm(), 0.5);
  const double distance = sphere / std::sin(25.0 * kPi / 180.0);
  const double radius = distance * std::cos(kPi / 6.0);
  const double height = distance * std::sin(kPi / 6.0);
  const double rate = rnd.sign() * std::min(2.0 * kPi / 30.0, 6.0 / radius);  // rad/s
  const double phase = rnd.uniform(0.0, 2.0 * kPi);
  // Control points on a larger circle so that the spline, which averages neighbouring control
  // points as (p_{k-1} + 4 p_k + p_{k+1}) / 6 at the knots, lies on the requested radius.
  const double step = rate * static_cast<double>(knots.dt_ns) * 1e-9;
  const double control_radius = radius * 6.0 / (4.0 + 2.0 * std::cos(step));
  std::vector<Pose> poses;
  for (size_t k = 0; k < knots.times_s.size(); ++k) {
    const double angle = phase + rate * knots.times_s[k];
    const Eigen::Vector3d eye(c.x() + control_radius * std::cos(angle), c.y() + control_radius * std::sin(angle),
                              c.z() + height);
    // Look at the centre as seen from the on-spline eye (same direction: the scale is radial).
    const Eigen::Vector3d on_spline(c.x() + radius * std::cos(angle), c.y() + radius * std::sin(angle), c.z() + height);
    auto look = lookAt(on_spline, c, Eigen::Vector3d::UnitZ());
    if (!look.ok()) return look.error();
    Pose T = *look;
    T.translation() = eye;
    poses.push_back(T);
  }
  return poses;
}

}  // namespace

// ================================================================================================
// SplineTrajectory
// ================================================================================================

Result<SplineTrajectory> SplineTrajectory::fromControlPoses(std::vector<Pose> T_world_body_control, int64_t t0_ns,
                                                            int64_t dt_ns) {
  const size_t n = T_world_body_control.size();
  if (n < 4) {
    return makeError(ErrorCode::kInvalidArgument,
                     "SplineTrajectory: need at least 4 control poses, got " + std::to_string(n));
  }
  if (dt_ns <= 0) {
    return makeError(ErrorCode::kInvalidArgument,
                     "SplineTrajectory: knot spacing must be positive, got " + std::to_string(dt_ns) + " ns");
  }
  const int64_t span = static_cast<int64_t>(n - 1);
  if (span > (std::numeric_limits<int64_t>::max() - std::max<int64_t>(t0_ns, 0)) / dt_ns ||
      t0_ns < std::numeric_limits<int64_t>::min() / 2) {
    return makeError(ErrorCode::kInvalidArgument, "SplineTrajectory: knot times overflow int64 nanoseconds");
  }
  for (size_t k = 0; k < n; ++k) {
    if (!isValidPose(T_world_body_control[k])) {
      return makeError(ErrorCode::kInvalidArgument,
                       "SplineTrajectory: control pose " + std::to_string(k) + " is not a finite rigid transform");
    }
  }
  SplineTrajectory s;
  s.control_ = std::move(T_world_body_control);
  s.t0_ns_ = t0_ns;
  s.dt_ns_ = dt_ns;
  return s;
}

int64_t SplineTrajectory::startNs() const { return t0_ns_ + dt_ns_; }

int64_t SplineTrajectory::endNs() const {
  const int64_t n = static_cast<int64_t>(control_.size());
  return n < 4 ? startNs() : t0_ns_ + (n - 2) * dt_ns_;
}

TrajectoryState SplineTrajectory::evaluate(int64_t t_ns) const {
  TrajectoryState state;
  state.t_ns = t_ns;
  const int64_t n = static_cast<int64_t>(control_.size());
  if (n < 4) return state;
  t_ns = std::clamp(t_ns, startNs(), endNs());
  state.t_ns = t_ns;
  // Segment index and fraction in integer nanoseconds (exact at the knots).
  const int64_t offset = t_ns - t0_ns_;
  int64_t i = offset / dt_ns_;
  int64_t rem = offset - i * dt_ns_;
  if (i > n - 3) {  // t == endNs(): end of the last segment.
    i = n - 3;
    rem = dt_ns_;
  }
  const double dt = static_cast<double>(dt_ns_) * 1e-9;
  const double u = static_cast<double>(rem) / static_cast<double>(dt_ns_);
  const double u2 = u * u;
  const double u3 = u2 * u;
  const double w = 1.0 - u;

  // Position: weights, first and second derivatives with respect to u.
  const double b[4] = {w * w * w / 6.0, (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0, (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
                       u3 / 6.0};
  const double db[4] = {-0.5 * w * w, 1.5 * u2 - 2.0 * u, -1.5 * u2 + u + 0.5, 0.5 * u2};
  const double ddb[4] = {w, 3.0 * u - 2.0, 1.0 - 3.0 * u, u};
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d& pk = control_[static_cast<size_t>(i - 1 + k)].translation();
    p += b[k] * pk;
    v += db[k] * pk;
    a += ddb[k] * pk;
  }
  state.v_world_body = v / dt;
  state.a_world_body = a / (dt * dt);

  // Rotation: cumulative weights B~_1..3 and their u-derivatives.
  const double cb[3] = {(5.0 + 3.0 * u - 3.0 * u2 + u3) / 6.0, (1.0 + 3.0 * u + 3.0 * u2 - 2.0 * u3) / 6.0, u3 / 6.0};
  const double dcb[3] = {0.5 * w * w, 0.5 + u - u2, 0.5 * u2};
  Eigen::Matrix3d R = control_[static_cast<size_t>(i - 1)].linear();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  for (int j = 0; j < 3; ++j) {
    const Eigen::Matrix3d Ra = control_[static_cast<size_t>(i - 1 + j)].linear();
    const Eigen::Matrix3d Rb = control_[static_cast<size_t>(i + j)].linear();
    const Eigen::Vector3d d = logSO3(Ra.transpose() * Rb);
    const Eigen::Matrix3d A = expSO3(cb[j] * d);
    omega = A.transpose() * omega + (dcb[j] / dt) * d;
    R = R * A;
  }
  // Re-orthonormalise (products of three exps drift by ~1e-16 only, but keep exact rotations).
  const Eigen::Quaterniond q(R);
  state.T_world_body.linear() = q.normalized().toRotationMatrix();
  state.T_world_body.translation() = p;
  state.omega_body = omega;
  return state;
}

// ================================================================================================
// Kinds and generators
// ================================================================================================

Result<TrajectoryKind> parseTrajectoryKind(const std::string& name) {
  if (name == "drone") return TrajectoryKind::kDroneFlight;
  if (name == "drone_agile") return TrajectoryKind::kDroneAgile;
  if (name == "drone_acro") return TrajectoryKind::kDroneAcro;
  if (name == "handheld") return TrajectoryKind::kHandheld;
  if (name == "aggressive") return TrajectoryKind::kAggressive;
  if (name == "orbit") return TrajectoryKind::kOrbit;
  return makeError(
      ErrorCode::kInvalidArgument,
      "trajectory kind '" + name + "' is unknown (use drone, drone_agile, drone_acro, handheld, aggressive or orbit)");
}

const char* trajectoryKindName(TrajectoryKind kind) {
  switch (kind) {
    case TrajectoryKind::kDroneFlight:
      return "drone";
    case TrajectoryKind::kDroneAgile:
      return "drone_agile";
    case TrajectoryKind::kDroneAcro:
      return "drone_acro";
    case TrajectoryKind::kHandheld:
      return "handheld";
    case TrajectoryKind::kAggressive:
      return "aggressive";
    case TrajectoryKind::kOrbit:
      return "orbit";
  }
  return "unknown";
}

bool isDroneKind(TrajectoryKind kind) {
  return kind == TrajectoryKind::kDroneFlight || kind == TrajectoryKind::kDroneAgile ||
         kind == TrajectoryKind::kDroneAcro;
}

Result<HeightField> HeightField::fromModel(const Model& model, double radius_m, double cell_m) {
  if (model.triangleCount() == 0 || model.bounds.empty()) {
    return makeError(ErrorCode::kInvalidArgument, "HeightField: the model has no triangles");
  }
  if (!std::isfinite(cell_m) || cell_m <= 0.0 || !std::isfinite(radius_m) || radius_m < 0.0) {
    return makeError(ErrorCode::kInvalidArgument, "HeightField: the cell must be positive and the radius non-negative");
  }
  constexpr int kMaxSide = 2048;
  const double extent_x = double(model.bounds.max[0]) - model.bounds.min[0];
  const double extent_y = double(model.bounds.max[1]) - model.bounds.min[1];
  HeightField field;
  field.cell_ = std::max(cell_m, std::max(extent_x, extent_y) / (kMaxSide - 1));
  field.x0_ = model.bounds.min[0];
  field.y0_ = model.bounds.min[1];
  field.width_ = static_cast<int>(std::floor(extent_x / field.cell_)) + 1;
  field.height_ = static_cast<int>(std::floor(extent_y / field.cell_)) + 1;
  const float none = -std::numeric_limits<float>::infinity();
  std::vector<float> raw(size_t(field.width_) * field.height_, none);
  const auto cellOf = [&](double v, double origin, int size) {  // clamped before the cast
    return static_cast<int>(std::clamp(std::floor((v - origin) / field.cell_), 0.0, double(size - 1)));
  };
  // Each triangle's highest corner over the cells its xy bounding box widened by the radius covers.
  for (size_t t = 0; t < model.triangleCount(); ++t) {
    double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    double hi[2] = {-lo[0], -lo[1]};
    float z = none;
    for (int c = 0; c < 3; ++c) {
      const float* p = &model.positions[3 * size_t{model.indices[3 * t + c]}];
      for (int a = 0; a < 2; ++a) lo[a] = std::min(lo[a], double(p[a])), hi[a] = std::max(hi[a], double(p[a]));
      z = std::max(z, p[2]);
    }
    const int x_lo = cellOf(lo[0] - radius_m, field.x0_, field.width_);
    const int x_hi = cellOf(hi[0] + radius_m, field.x0_, field.width_);
    const int y_lo = cellOf(lo[1] - radius_m, field.y0_, field.height_);
    const int y_hi = cellOf(hi[1] + radius_m, field.y0_, field.height_);
    for (int y = y_lo; y <= y_hi; ++y) {
      float* row = &raw[size_t(y) * field.width_];
      for (int x = x_lo; x <= x_hi; ++x) row[x] = std::max(row[x], z);
    }
  }
  field.tops_ = std::move(raw);
  return field;
}

double HeightField::top(double x, double y) const {
  if (tops_.empty() || !std::isfinite(x) || !std::isfinite(y)) return -std::numeric_limits<double>::infinity();
  const double cx = std::floor((x - x0_) / cell_), cy = std::floor((y - y0_) / cell_);
  if (cx < 0.0 || cy < 0.0 || cx >= width_ || cy >= height_) return -std::numeric_limits<double>::infinity();
  return tops_[static_cast<size_t>(cy) * width_ + static_cast<size_t>(cx)];
}

Result<SplineTrajectory> makeTrajectory(const TrajectoryOptions& options, const Aabb& scene_bounds) {
  if (scene_bounds.empty()) return makeError(ErrorCode::kInvalidArgument, "makeTrajectory: scene bounds are empty");
  BoxFrame box;
  for (int a = 0; a < 3; ++a) {
    box.min[a] = scene_bounds.min[static_cast<size_t>(a)];
    box.max[a] = scene_bounds.max[static_cast<size_t>(a)];
  }
  if (!box.min.allFinite() || !box.max.allFinite() || (box.max - box.min).minCoeff() < 0.0) {
    return makeError(ErrorCode::kInvalidArgument, "makeTrajectory: scene bounds are not a finite box");
  }
  if (!std::isfinite(options.duration_s) || options.duration_s <= 0.0 || options.duration_s > 1e4) {
    return makeError(ErrorCode::kInvalidArgument,
                     "makeTrajectory: duration must be in (0, 10000] s, got " + std::to_string(options.duration_s));
  }
  if (!isValidPose(options.T_body_camera)) {
    return makeError(ErrorCode::kInvalidArgument, "makeTrajectory: T_body_camera is not a finite rigid transform");
  }
  if (!std::isfinite(options.drone_clearance_m) || options.drone_clearance_m < 0.0 ||
      !std::isfinite(options.drone_climb_rate) || options.drone_climb_rate <= 0.0) {
    return makeError(ErrorCode::kInvalidArgument,
                     "makeTrajectory: drone_clearance_m must be finite and >= 0, drone_climb_rate finite and > 0");
  }
  // Different kinds draw different streams even for the same seed, but the acro drone draws the
  // agile one's: the same path and swings, twice as far.
  const TrajectoryKind stream = options.kind == TrajectoryKind::kDroneAcro ? TrajectoryKind::kDroneAgile : options.kind;
  Mt19937 rnd(options.seed * 0x9E3779B97F4A7C15ull + static_cast<uint64_t>(stream) + 1);
  const double nominal_dt = options.kind == TrajectoryKind::kAggressive ? 0.05 : 0.1;
  const KnotTimes knots = makeKnots(options.duration_s, nominal_dt);
  Result<std::vector<Pose>> cameras = std::vector<Pose>{};
  switch (options.kind) {
    case TrajectoryKind::kDroneFlight:
      cameras = droneCameraPoses(box, knots, rnd, options);
      break;
    case TrajectoryKind::kDroneAgile:
      cameras = droneCameraPoses(box, knots, rnd, options, 1.0);
      break;
    case TrajectoryKind::kDroneAcro:
      cameras = droneCameraPoses(box, knots, rnd, options, 2.0);
      break;
    case TrajectoryKind::kHandheld:
      cameras = walkCameraPoses(box, knots, rnd, WalkParams{});
      break;
    case TrajectoryKind::kAggressive: {
      WalkParams w;
      w.radius_mean = 0.75;
      w.radius_amp2 = 0.1;
      w.radius_amp5 = 0.05;
      w.speed_mean = 1.1;
      w.speed_amp_slow = 0.35;
      w.speed_period_slow = 3.0;
      w.speed_amp_fast = 0.2;
      w.speed_period_fast = 1.3;
      w.shake = 0.08;
      w.height_amp = 0.15;
      w.bob = 0.0;
      w.yaw_amp_slow = 0.45;
      w.yaw_freq_slow = 0.65;
      w.yaw_amp_fast = 0.08;
      w.yaw_freq_fast = 1.6;
      w.pitch_mean = -0.15;
      w.pitch_amp = 0.22;
      w.pitch_freq = 0.85;
      w.roll_amp = 0.12;
      w.roll_freq = 1.1;
      cameras = walkCameraPoses(box, knots, rnd, w);
      break;
    }
    case TrajectoryKind::kOrbit:
      cameras = orbitCameraPoses(box, knots, rnd);
      break;
  }
  if (!cameras.ok()) return cameras.error();
  const Pose T_camera_body = options.T_body_camera.inverse();
  std::vector<Pose> bodies;
  bodies.reserve(cameras->size());
  for (const Pose& T_world_camera : *cameras) bodies.push_back(T_world_camera * T_camera_body);
  return SplineTrajectory::fromControlPoses(std::move(bodies), knots.t0_ns, knots.dt_ns);
}

}  // namespace vkloc
