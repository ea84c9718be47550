// Error-state EKF with delayed updates (fusion/error_state_ekf.hpp). Derivations in the comments
// use the header's conventions: R = R_hat Exp(dtheta), dx = [dp dv dtheta db_g db_a].
#include "vkloc/fusion/error_state_ekf.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "vkloc/core/numeric.hpp"

namespace vkloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr int kP = 0;    // dp
constexpr int kV = 3;    // dv
constexpr int kTh = 6;   // dtheta
constexpr int kBg = 9;   // db_g
constexpr int kBa = 12;  // db_a

double seconds(int64_t dt_ns) { return static_cast<double>(dt_ns) * 1e-9; }
int64_t nanoseconds(double s) { return static_cast<int64_t>(std::llround(s * 1e9)); }

Error invalid(const std::string& message) { return makeError(ErrorCode::kInvalidArgument, message); }

/// Rotation matrix re-orthonormalised through a unit quaternion (as integrateImu does).
Matrix3d orthonormalized(const Matrix3d& R) { return Eigen::Quaterniond(R).normalized().toRotationMatrix(); }

bool stateFinite(const EkfState& s) {
  return s.p_world_body.allFinite() && s.v_world_body.allFinite() && s.R_world_body.allFinite() &&
         s.gyro_bias.allFinite() && s.accel_bias.allFinite() && s.P.allFinite();
}

/// Linear interpolation of two readings at t_ns (a.t_ns <= t_ns <= b.t_ns, a.t_ns < b.t_ns).
ImuSample interpolate(const ImuSample& a, const ImuSample& b, int64_t t_ns) {
  const double s = seconds(t_ns - a.t_ns) / seconds(b.t_ns - a.t_ns);
  ImuSample r;
  r.t_ns = t_ns;
  r.gyro_body = (1.0 - s) * a.gyro_body + s * b.gyro_body;
  r.accel_body = (1.0 - s) * a.accel_body + s * b.accel_body;
  return r;
}

ImuSample heldAt(const ImuSample& reading, int64_t t_ns) {
  ImuSample r = reading;
  r.t_ns = t_ns;
  return r;
}

/// Symmetric matrix with every eigenvalue raised to at least floor^2.
Matrix3d floorEigenvalues(const Matrix3d& C, double floor) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> es(0.5 * (C + C.transpose()));
  const Vector3d lambda = es.eigenvalues().cwiseMax(floor * floor);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}

struct Innovation {
  Vector6d r = Vector6d::Zero();
  Matrix6x15d H = Matrix6x15d::Zero();
  Matrix6d S = Matrix6d::Zero();
  double mahalanobis_sq = 0.0;
  bool ok = false;
};

Innovation innovationOf(const EkfState& x, const Pose& T_world_body_measured, const Matrix6d& C) {
  Innovation in;
  in.r = ekfPoseResidual(x, T_world_body_measured, &in.H);
  in.S = in.H * x.P * in.H.transpose() + C;
  in.S = 0.5 * (in.S + in.S.transpose());
  const Eigen::LLT<Matrix6d> llt(in.S);
  if (llt.info() != Eigen::Success || !in.S.allFinite() || !in.r.allFinite()) return in;
  in.mahalanobis_sq = in.r.dot(llt.solve(in.r));
  in.ok = std::isfinite(in.mahalanobis_sq);
  return in;
}

/// Kalman update with the innovation `in` (measurement noise C), Joseph form, then the reset of
/// the error state: the attitude error after injecting dtheta_hat is (I - hat(dtheta_hat)/2)
/// dtheta - dtheta_hat to first order, so P <- G P G^T with that block in G. False (x unchanged)
/// when the result is not finite.
bool applyInnovation(EkfState& x, const Innovation& in, const Matrix6d& C) {
  const Eigen::LLT<Matrix6d> llt(in.S);
  const Eigen::Matrix<double, 15, 6> K = llt.solve(in.H * x.P).transpose();  // P H^T S^-1 (S, P symmetric)
  const Vector15d dx = K * in.r;
  Matrix15d IKH = Matrix15d::Identity() - K * in.H;
  Matrix15d P = IKH * x.P * IKH.transpose() + K * C * K.transpose();
  Matrix15d G = Matrix15d::Identity();
  G.block<3, 3>(kTh, kTh) = Matrix3d::Identity() - 0.5 * hat(dx.segment<3>(kTh));
  P = G * P * G.transpose();
  EkfState next = applyErrorState(x, dx);
  next.P = 0.5 * (P + P.transpose());
  if (!stateFinite(next)) return false;
  x = next;
  return true;
}

/// Regularised upper incomplete gamma Q(dof / 2, x / 2) = 1 - CDF of chi-square(dof) at x, in
/// closed form: Q(m, y) = e^-y sum_{i<m} y^i / i!, Q(m + 1/2, y) = erfc(sqrt y) + e^-y sum_{i<m}
/// y^(i+1/2) / Gamma(i + 3/2). Terms in log space (no overflow for large dof).
double chiSquareUpperTail(double x, int dof) {
  if (x <= 0.0) return 1.0;
  const double y = 0.5 * x;
  const double log_y = std::log(y);
  const int m = dof / 2;
  double q = 0.0;
  if (dof % 2 == 0) {
    for (int i = 0; i < m; ++i) q += std::exp(-y + i * log_y - std::lgamma(i + 1.0));
  } else {
    q = std::erfc(std::sqrt(y));
    for (int i = 0; i < m; ++i) q += std::exp(-y + (i + 0.5) * log_y - std::lgamma(i + 1.5));
  }
  return std::min(q, 1.0);
}

bool symmetricPositiveDefinite(const Matrix15d& P) {
  if (!P.allFinite()) return false;
  const double scale = std::max(1.0, P.cwiseAbs().maxCoeff());
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) return false;
  const Eigen::LLT<Matrix15d> llt(0.5 * (P + P.transpose()));
  return llt.info() == Eigen::Success;
}

}  // namespace

Status validateEkfOptions(const EkfOptions& o) {
  auto field = [](const char* name, const char* need) {
    return invalid(std::string("ekf options: ") + name + " must be " + need);
  };
  const ImuNoise& n = o.imu_noise;
  if (!finiteIn(n.gyro_noise_density, 0.0, 1e3)) return field("imu_noise.gyro_noise_density", "finite, >= 0");
  if (!finiteIn(n.accel_noise_density, 0.0, 1e3)) return field("imu_noise.accel_noise_density", "finite, >= 0");
  if (!finiteIn(n.gyro_random_walk, 0.0, 1e3)) return field("imu_noise.gyro_random_walk", "finite, >= 0");
  if (!finiteIn(n.accel_random_walk, 0.0, 1e3)) return field("imu_noise.accel_random_walk", "finite, >= 0");
  if (!o.gravity_world.allFinite() || o.gravity_world.norm() > 100.0) {
    return field("gravity_world", "finite with |g| <= 100 m/s^2");
  }
  if (!isValidPose(o.T_body_camera)) return field("T_body_camera", "a finite rigid transform");
  if (!finiteIn(o.initial_sigma_position_m, 1e-12, 1e6)) return field("initial_sigma_position_m", "in (0, 1e6]");
  if (!finiteIn(o.initial_sigma_velocity_m_s, 1e-12, 1e6)) {
    return field("initial_sigma_velocity_m_s", "in (0, 1e6]");
  }
  if (!finiteIn(o.initial_sigma_attitude_rad, 1e-12, 10.0)) return field("initial_sigma_attitude_rad", "in (0, 10]");
  if (!finiteIn(o.initial_sigma_gyro_bias_rad_s, 1e-12, 1e3)) {
    return field("initial_sigma_gyro_bias_rad_s", "in (0, 1e3]");
  }
  if (!finiteIn(o.initial_sigma_accel_bias_m_s2, 1e-12, 1e3)) {
    return field("initial_sigma_accel_bias_m_s2", "in (0, 1e3]");
  }
  if (!finiteIn(o.measurement_covariance_scale, 1e-12, 1e12)) {
    return field("measurement_covariance_scale", "in (0, 1e12]");
  }
  if (!finiteIn(o.min_measurement_sigma_m, 0.0, 1e3)) return field("min_measurement_sigma_m", "in [0, 1e3]");
  if (!finiteIn(o.min_measurement_sigma_rad, 0.0, 10.0)) return field("min_measurement_sigma_rad", "in [0, 10]");
  if (!(o.gate_probability > 0.0 && o.gate_probability <= 1.0)) return field("gate_probability", "in (0, 1]");
  if (!finiteIn(o.buffer_s, 1e-6, 3600.0)) return field("buffer_s", "in (0, 3600] seconds");
  if (!finiteIn(o.max_imu_gap_s, 1e-6, 3600.0)) return field("max_imu_gap_s", "in (0, 3600] seconds");
  if (!finiteIn(o.max_extrapolation_s, 0.0, 10.0)) return field("max_extrapolation_s", "in [0, 10] seconds");
  return Status::success();
}

double chiSquareQuantile(double probability, int dof) {
  if (!(probability > 0.0 && probability < 1.0) || dof < 1 || dof > 100000) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const double tail = 1.0 - probability;
  double lo = 0.0;
  double hi = dof + 10.0 * std::sqrt(2.0 * dof) + 100.0;
  while (chiSquareUpperTail(hi, dof) > tail) hi *= 2.0;
  for (int i = 0; i < 200 && hi - lo > 1e-13 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chiSquareUpperTail(mid, dof) > tail ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Pose EkfState::T_world_body() const {
  Pose T = Pose::Identity();
  T.linear() = R_world_body;
  T.translation() = p_world_body;
  return T;
}

EkfState applyErrorState(const EkfState& state, const Vector15d& dx) {
  EkfState x = state;
  x.p_world_body += dx.segment<3>(kP);
  x.v_world_body += dx.segment<3>(kV);
  x.R_world_body = orthonormalized(state.R_world_body * expSO3(dx.segment<3>(kTh)));
  x.gyro_bias += dx.segment<3>(kBg);
  x.accel_bias += dx.segment<3>(kBa);
  return x;
}

Vector15d errorStateBetween(const EkfState& estimate, const EkfState& truth) {
  Vector15d dx;
  dx.segment<3>(kP) = truth.p_world_body - estimate.p_world_body;
  dx.segment<3>(kV) = truth.v_world_body - estimate.v_world_body;
  dx.segment<3>(kTh) = logSO3(estimate.R_world_body.transpose() * truth.R_world_body);
  dx.segment<3>(kBg) = truth.gyro_bias - estimate.gyro_bias;
  dx.segment<3>(kBa) = truth.accel_bias - estimate.accel_bias;
  return dx;
}

EkfState propagateEkfState(const EkfState& state, const ImuSample& reading, const ImuSample& next,
                           const Vector3d& gravity_world, const ImuNoise& noise, Matrix15d* F_out, Matrix15d* Q_out) {
  if (F_out) F_out->setIdentity();
  if (Q_out) Q_out->setZero();
  if (next.t_ns <= state.t_ns) return state;
  const double dt = seconds(next.t_ns - state.t_ns);
  const Vector3d w0 = reading.gyro_body - state.gyro_bias;
  const Vector3d w1 = next.gyro_body - state.gyro_bias;
  const Vector3d f0 = reading.accel_body - state.accel_bias;
  const Vector3d f1 = next.accel_body - state.accel_bias;
  const Vector3d phi = 0.5 * dt * (w0 + w1);
  const Matrix3d dR = expSO3(phi);
  const Matrix3d& R0 = state.R_world_body;
  EkfState x = state;
  x.t_ns = next.t_ns;
  x.R_world_body = orthonormalized(R0 * dR);
  const Matrix3d& R1 = x.R_world_body;
  const Vector3d a0 = R0 * f0 + gravity_world;
  const Vector3d a1 = R1 * f1 + gravity_world;
  x.v_world_body = state.v_world_body + 0.5 * dt * (a0 + a1);
  x.p_world_body = state.p_world_body + dt * state.v_world_body + (dt * dt / 6.0) * (2.0 * a0 + a1);

  // Transition of dx over the step (first order in dx):
  //   R Exp(dth) Exp(phi - dt db_g) = R dR Exp(dR^T dth - Jr(phi) dt db_g)
  //     => dth' = dR^T dth - Jr(phi) dt db_g
  //   a0 + da0 = R0 Exp(dth)(f0 - db_a) + g     => da0 = -R0 [f0]x dth - R0 db_a
  //   a1 + da1 = R1 Exp(dth')(f1 - db_a) + g    => da1 = -R1 [f1]x dth' - R1 db_a
  //   dv' = dv + dt (da0 + da1) / 2,  dp' = dp + dt dv + dt^2 (2 da0 + da1) / 6.
  const Matrix3d I = Matrix3d::Identity();
  const Matrix3d Jr = rightJacobianSO3(phi);
  const Matrix3d A0_th = -R0 * hat(f0);
  const Matrix3d A1_th = -R1 * hat(f1) * dR.transpose();
  const Matrix3d A1_bg = R1 * hat(f1) * Jr * dt;
  const Matrix3d A0_ba = -R0;
  const Matrix3d A1_ba = -R1;
  Matrix15d F = Matrix15d::Identity();
  F.block<3, 3>(kP, kV) = dt * I;
  F.block<3, 3>(kP, kTh) = (dt * dt / 6.0) * (2.0 * A0_th + A1_th);
  F.block<3, 3>(kP, kBg) = (dt * dt / 6.0) * A1_bg;
  F.block<3, 3>(kP, kBa) = (dt * dt / 6.0) * (2.0 * A0_ba + A1_ba);
  F.block<3, 3>(kV, kTh) = 0.5 * dt * (A0_th + A1_th);
  F.block<3, 3>(kV, kBg) = 0.5 * dt * A1_bg;
  F.block<3, 3>(kV, kBa) = 0.5 * dt * (A0_ba + A1_ba);
  F.block<3, 3>(kTh, kTh) = dR.transpose();
  F.block<3, 3>(kTh, kBg) = -Jr * dt;

  // Noise over dt from the continuous densities: accelerometer white noise enters dv as a
  // random walk (sigma^2 dt) and dp as its integral (dt^3/3, cross dt^2/2; R sigma^2 I R^T =
  // sigma^2 I), gyro noise enters dtheta (sigma^2 dt), the biases walk (rw^2 dt).
  const double sa2 = noise.accel_noise_density * noise.accel_noise_density;
  const double sg2 = noise.gyro_noise_density * noise.gyro_noise_density;
  Matrix15d Q = Matrix15d::Zero();
  Q.block<3, 3>(kP, kP) = (sa2 * dt * dt * dt / 3.0) * I;
  Q.block<3, 3>(kP, kV) = (sa2 * dt * dt / 2.0) * I;
  Q.block<3, 3>(kV, kP) = (sa2 * dt * dt / 2.0) * I;
  Q.block<3, 3>(kV, kV) = (sa2 * dt) * I;
  Q.block<3, 3>(kTh, kTh) = (sg2 * dt) * I;
  Q.block<3, 3>(kBg, kBg) = (noise.gyro_random_walk * noise.gyro_random_walk * dt) * I;
  Q.block<3, 3>(kBa, kBa) = (noise.accel_random_walk * noise.accel_random_walk * dt) * I;

  const Matrix15d P = F * state.P * F.transpose() + Q;
  x.P = 0.5 * (P + P.transpose());
  if (F_out) *F_out = F;
  if (Q_out) *Q_out = Q;
  return x;
}

Vector6d ekfPoseResidual(const EkfState& state, const Pose& T_world_body_measured, Matrix6x15d* H) {
  Vector6d r;
  r.head<3>() = T_world_body_measured.translation() - state.p_world_body;
  r.tail<3>() = logSO3(state.R_world_body.transpose() * T_world_body_measured.linear());
  if (H) {
    // Log((R Exp(dth))^T R_m) = Log(Exp(-dth) Exp(r_phi)) ~= r_phi - Jl^-1(r_phi) dth.
    H->setZero();
    H->block<3, 3>(0, kP).setIdentity();
    H->block<3, 3>(3, kTh) = leftJacobianInverseSO3(r.tail<3>());
  }
  return r;
}

Matrix6d ekfMeasurementCovariance(const Pose& T_world_camera, const Matrix6d& covariance_camera,
                                  const Pose& T_body_camera) {
  // T_world_camera Exp(xi) T_body_camera^-1 = T_world_body Exp(Ad(T_body_camera) xi); the body's
  // rho maps to the world position error R_world_body rho.
  const Pose T_world_body = T_world_camera * T_body_camera.inverse();
  const Matrix6d Ad = adjointSE3(T_body_camera);
  Matrix6d J = Matrix6d::Identity();
  J.topLeftCorner<3, 3>() = T_world_body.linear();
  const Matrix6d JA = J * Ad;
  const Matrix6d C = JA * covariance_camera * JA.transpose();
  return 0.5 * (C + C.transpose());
}

Matrix6d bodyPoseCovariance(const EkfState& state) {
  Matrix6d C;
  C.topLeftCorner<3, 3>() = state.P.block<3, 3>(kP, kP);
  C.topRightCorner<3, 3>() = state.P.block<3, 3>(kP, kTh);
  C.bottomLeftCorner<3, 3>() = state.P.block<3, 3>(kTh, kP);
  C.bottomRightCorner<3, 3>() = state.P.block<3, 3>(kTh, kTh);
  Matrix6d J = Matrix6d::Identity();
  J.topLeftCorner<3, 3>() = state.R_world_body.transpose();  // rho = R^T dp
  const Matrix6d out = J * C * J.transpose();
  return 0.5 * (out + out.transpose());
}

Matrix6d cameraPoseCovariance(const EkfState& state, const Pose& T_body_camera) {
  // T_world_body Exp(xi_b) T_body_camera = T_world_camera Exp(Ad(T_body_camera^-1) xi_b).
  const Matrix6d Ad = adjointSE3(T_body_camera.inverse());
  const Matrix6d out = Ad * bodyPoseCovariance(state) * Ad.transpose();
  return 0.5 * (out + out.transpose());
}

ErrorStateEkf::ErrorStateEkf() : ErrorStateEkf(EkfOptions{}, chiSquareQuantile(EkfOptions{}.gate_probability, 6)) {}

ErrorStateEkf::ErrorStateEkf(const EkfOptions& options, double gate_threshold)
    : options_(options), gate_threshold_(gate_threshold) {}

Result<ErrorStateEkf> ErrorStateEkf::create(const EkfOptions& options) {
  VKLOC_TRY_STATUS(validateEkfOptions(options));
  const double threshold = options.gate_probability >= 1.0 ? std::numeric_limits<double>::infinity()
                                                           : chiSquareQuantile(options.gate_probability, 6);
  return ErrorStateEkf(options, threshold);
}

void ErrorStateEkf::reset() {
  nodes_.clear();
  readings_.clear();
  outputs_.clear();
  awaiting_fix_ = false;
}

Status ErrorStateEkf::initialize(int64_t t_ns, const Pose& T_world_body, const Vector3d& v_world_body,
                                 const std::optional<Matrix15d>& covariance) {
  if (!isValidPose(T_world_body)) return invalid("ekf initialize: T_world_body is not a finite rigid transform");
  EkfState s;
  s.t_ns = t_ns;
  s.p_world_body = T_world_body.translation();
  s.R_world_body = T_world_body.linear();
  s.v_world_body = v_world_body;
  if (covariance) {
    s.P = *covariance;
  } else {
    Vector15d sigma;
    sigma << Vector3d::Constant(options_.initial_sigma_position_m),
        Vector3d::Constant(options_.initial_sigma_velocity_m_s),
        Vector3d::Constant(options_.initial_sigma_attitude_rad),
        Vector3d::Constant(options_.initial_sigma_gyro_bias_rad_s),
        Vector3d::Constant(options_.initial_sigma_accel_bias_m_s2);
    s.P = sigma.cwiseProduct(sigma).asDiagonal();
  }
  return initialize(s);
}

Status ErrorStateEkf::initializeFromCamera(int64_t t_ns, const Pose& T_world_camera, const Vector3d& v_world_body,
                                           const std::optional<Matrix15d>& covariance) {
  if (!isValidPose(T_world_camera)) return invalid("ekf initialize: T_world_camera is not a finite rigid transform");
  return initialize(t_ns, T_world_camera * options_.T_body_camera.inverse(), v_world_body, covariance);
}

Status ErrorStateEkf::initialize(const EkfState& state) {
  if (!state.p_world_body.allFinite() || !state.v_world_body.allFinite() || !state.gyro_bias.allFinite() ||
      !state.accel_bias.allFinite()) {
    return invalid("ekf initialize: position, velocity and biases must be finite");
  }
  Pose T = Pose::Identity();
  T.linear() = state.R_world_body;
  if (!isValidPose(T)) return invalid("ekf initialize: R_world_body is not a rotation matrix");
  if (!symmetricPositiveDefinite(state.P)) {
    return invalid("ekf initialize: covariance must be finite, symmetric and positive definite");
  }
  return startAt(state);
}

Status ErrorStateEkf::startAt(const EkfState& state) {
  nodes_.clear();
  awaiting_fix_ = false;
  Node node;
  node.state = state;
  node.state.R_world_body = orthonormalized(state.R_world_body);
  node.state.P = 0.5 * (state.P + state.P.transpose());
  // The reading at the start time: measured, interpolated, or the one before held across a
  // short interval; else none (the first reading after it is held back to it).
  const int64_t t0 = state.t_ns;
  const auto after = std::upper_bound(readings_.begin(), readings_.end(), t0,
                                      [](int64_t t, const ImuSample& r) { return t < r.t_ns; });
  const int64_t max_gap_ns = nanoseconds(options_.max_imu_gap_s);
  if (after != readings_.begin()) {
    const ImuSample& before = *(after - 1);
    if (before.t_ns == t0) {
      node.reading = before;
      node.has_reading = true;
    } else if (after != readings_.end() && after->t_ns - before.t_ns <= max_gap_ns) {
      node.reading = interpolate(before, *after, t0);
      node.has_reading = true;
    } else if (t0 - before.t_ns <= max_gap_ns) {
      node.reading = heldAt(before, t0);
      node.has_reading = true;
    }
  }
  nodes_.push_back(node);
  // Readings after t0 were received already: propagate through them (gaps re-anchor as in
  // addImu; the filter is initialized either way).
  const std::vector<ImuSample> later(after, readings_.end());
  for (const ImuSample& r : later) (void)step(r);
  return Status::success();
}

EkfState ErrorStateEkf::propagate(const Node& from, const ImuSample& next) const {
  return propagateEkfState(from.state, from.has_reading ? from.reading : next, next, options_.gravity_world,
                           options_.imu_noise);
}

Status ErrorStateEkf::step(const ImuSample& sample) {
  Node& last = nodes_.back();
  const int64_t gap_ns = sample.t_ns - last.state.t_ns;
  if (gap_ns > nanoseconds(options_.max_imu_gap_s)) {
    // No propagation across the gap: re-anchor here with the nominal state kept.
    EkfState s = last.state;
    s.t_ns = sample.t_ns;
    const double gap = seconds(gap_ns);
    const double sp = options_.initial_sigma_position_m;
    const double sv = options_.initial_sigma_velocity_m_s;
    const double sa = options_.initial_sigma_attitude_rad;
    const double grow = gap * (s.v_world_body.norm() + sv);
    Matrix15d P = s.P;
    for (int i = 0; i < 9; ++i) {
      for (int j = 0; j < 15; ++j) {
        if (i != j) P(i, j) = P(j, i) = 0.0;
      }
    }
    for (int i = 0; i < 3; ++i) {
      P(kP + i, kP + i) = std::max(P(kP + i, kP + i), sp * sp) + grow * grow;
      P(kV + i, kV + i) = std::max(P(kV + i, kV + i), sv * sv);
      P(kTh + i, kTh + i) = std::max(P(kTh + i, kTh + i), sa * sa);
    }
    s.P = P;
    Node node;
    node.state = s;
    node.reading = sample;
    node.has_reading = true;
    nodes_.clear();
    nodes_.push_back(node);
    awaiting_fix_ = true;
    return invalid("IMU reading at " + std::to_string(sample.t_ns) + " ns: gap of " + std::to_string(gap) +
                   " s > max_imu_gap_s; not propagated across, the filter re-anchored here (awaitingFix)");
  }
  if (!last.has_reading) {
    last.reading = heldAt(sample, last.state.t_ns);
    last.has_reading = true;
  }
  Node node;
  node.state = propagate(last, sample);
  node.reading = sample;
  node.has_reading = true;
  if (!stateFinite(node.state)) {
    return invalid("IMU reading at " + std::to_string(sample.t_ns) + " ns: propagation is not finite; ignored");
  }
  nodes_.push_back(std::move(node));
  trim();
  return Status::success();
}

void ErrorStateEkf::trim() {
  // Keep the newest node at or before newest - buffer_s so that any time in the window has a
  // state before it.
  const int64_t oldest_ns = nodes_.back().state.t_ns - nanoseconds(options_.buffer_s);
  while (nodes_.size() > 1 && nodes_[1].state.t_ns <= oldest_ns) nodes_.pop_front();
}

Status ErrorStateEkf::addImu(const ImuSample& sample) {
  if (!sample.gyro_body.allFinite() || !sample.accel_body.allFinite()) {
    return invalid("IMU reading at " + std::to_string(sample.t_ns) + " ns: non-finite rate or acceleration; ignored");
  }
  const int64_t previous = !readings_.empty() ? readings_.back().t_ns : std::numeric_limits<int64_t>::min();
  const int64_t filter_t = initialized() ? nodes_.back().state.t_ns : std::numeric_limits<int64_t>::min();
  if (sample.t_ns <= previous || sample.t_ns <= filter_t) {
    return invalid("IMU reading at " + std::to_string(sample.t_ns) + " ns: not after the previous reading (" +
                   std::to_string(std::max(previous, filter_t)) + " ns); ignored");
  }
  readings_.push_back(sample);
  const int64_t keep_ns = sample.t_ns - nanoseconds(options_.buffer_s);
  while (readings_.size() > 1 && readings_[1].t_ns <= keep_ns) readings_.pop_front();
  if (!initialized()) return Status::success();
  const Status status = step(sample);
  if (nodes_.back().state.t_ns == sample.t_ns) {
    outputs_.push_back(nodes_.back().state);
    while (outputs_.size() > options_.max_queued_outputs) outputs_.pop_front();
  }
  return status;
}

struct ErrorStateEkf::PreparedUpdate {
  Measurement m;
  Node node;
  bool insert = false;  // node is new, to go after nodes_[index]
  size_t index = 0;     // Last node with t <= t_ns.
  Innovation in;
  EkfUpdate result;
};

Result<ErrorStateEkf::PreparedUpdate> ErrorStateEkf::prepareUpdate(int64_t t_ns, const Pose& T_world_camera,
                                                                   const Matrix6d& covariance_camera) const {
  const std::string where = "camera pose update at " + std::to_string(t_ns) + " ns: ";
  if (!initialized()) return invalid(where + "the filter is not initialized (call initialize first)");
  if (!isValidPose(T_world_camera)) return invalid(where + "T_world_camera is not a finite rigid transform");
  if (!covariance_camera.allFinite()) return invalid(where + "covariance is not finite");
  const double cov_scale = std::max(1e-300, covariance_camera.cwiseAbs().maxCoeff());
  if ((covariance_camera - covariance_camera.transpose()).cwiseAbs().maxCoeff() > 1e-6 * cov_scale) {
    return invalid(where + "covariance is not symmetric");
  }
  const Matrix6d cov_sym = 0.5 * (covariance_camera + covariance_camera.transpose());
  if (Eigen::SelfAdjointEigenSolver<Matrix6d>(cov_sym, Eigen::EigenvaluesOnly).eigenvalues().minCoeff() <
      -1e-9 * cov_scale) {
    return invalid(where + "covariance is not positive semi-definite");
  }
  if (t_ns > nodes_.back().state.t_ns) {
    return invalid(where + "after the newest IMU reading (" + std::to_string(nodes_.back().state.t_ns) +
                   " ns); add the readings up to the image time first");
  }
  if (t_ns < nodes_.front().state.t_ns) {
    return invalid(where + "older than the ring buffer (oldest state " + std::to_string(nodes_.front().state.t_ns) +
                   " ns; buffer_s too short?)");
  }

  PreparedUpdate p;
  Measurement& m = p.m;
  m.T_world_body = T_world_camera * options_.T_body_camera.inverse();
  m.T_world_body.linear() = orthonormalized(m.T_world_body.linear());
  Matrix6d C =
      options_.measurement_covariance_scale * ekfMeasurementCovariance(T_world_camera, cov_sym, options_.T_body_camera);
  C.topLeftCorner<3, 3>() = floorEigenvalues(C.topLeftCorner<3, 3>(), options_.min_measurement_sigma_m);
  C.bottomRightCorner<3, 3>() = floorEigenvalues(C.bottomRightCorner<3, 3>(), options_.min_measurement_sigma_rad);
  // Raising the diagonal blocks adds a PSD matrix, so C stays PSD with the cross terms kept.
  m.covariance = 0.5 * (C + C.transpose());

  // The node at t_ns: existing, or a new one propagated from the one before with the reading
  // interpolated between its neighbours.
  auto it =
      std::upper_bound(nodes_.begin(), nodes_.end(), t_ns, [](int64_t t, const Node& n) { return t < n.state.t_ns; });
  p.index = static_cast<size_t>(it - nodes_.begin()) - 1;
  p.insert = nodes_[p.index].state.t_ns != t_ns;
  if (p.insert) {
    const Node& before = nodes_[p.index];
    const Node& after = nodes_[p.index + 1];
    p.node.reading = interpolate(before.reading, after.reading, t_ns);
    p.node.has_reading = true;
    p.node.state = propagate(before, p.node.reading);
  } else {
    p.node = nodes_[p.index];
  }

  p.result.t_ns = t_ns;
  p.result.gate_threshold = gate_threshold_;
  p.in = innovationOf(p.node.state, m.T_world_body, m.covariance);
  p.result.innovation = p.in.r;
  p.result.innovation_covariance = p.in.S;
  p.result.mahalanobis_sq = p.in.mahalanobis_sq;
  if (!p.in.ok) return invalid(where + "innovation covariance is not positive definite or not finite");
  return p;
}

Result<EkfUpdate> ErrorStateEkf::testCameraPose(int64_t t_ns, const Pose& T_world_camera,
                                                const Matrix6d& covariance_camera) const {
  Result<PreparedUpdate> p = prepareUpdate(t_ns, T_world_camera, covariance_camera);
  if (!p.ok()) return p.error();
  EkfUpdate result = p->result;
  result.gate_skipped = awaiting_fix_;
  result.accepted = result.gate_skipped || p->in.mahalanobis_sq <= gate_threshold_;
  return result;
}

Result<EkfUpdate> ErrorStateEkf::updateCameraPose(int64_t t_ns, const Pose& T_world_camera,
                                                  const Matrix6d& covariance_camera, EkfGate gate) {
  const std::string where = "camera pose update at " + std::to_string(t_ns) + " ns: ";
  Result<PreparedUpdate> prepared = prepareUpdate(t_ns, T_world_camera, covariance_camera);
  if (!prepared.ok()) return prepared.error();
  PreparedUpdate& p = *prepared;
  const Measurement& m = p.m;
  const Innovation& in = p.in;
  Node& node = p.node;
  const size_t index = p.index;
  const bool insert = p.insert;
  EkfUpdate& result = p.result;
  result.gate_skipped = gate == EkfGate::kForceAccept || awaiting_fix_;
  if (!result.gate_skipped && !(in.mahalanobis_sq <= gate_threshold_)) return result;  // Rejected.

  if (!applyInnovation(node.state, in, m.covariance)) return invalid(where + "the update is not finite; ignored");
  node.measurements.push_back(m);

  // Propagate the later readings again from the updated node, re-applying their updates, into a
  // copy of the tail: the filter changes only when everything stayed finite.
  const size_t first = insert ? index + 1 : index;  // Where the updated node goes.
  std::vector<Node> tail;
  tail.reserve(nodes_.size() - index + 1);
  tail.push_back(std::move(node));
  for (size_t j = index + 1; j < nodes_.size(); ++j) {
    Node next = nodes_[j];
    next.state = propagate(tail.back(), next.reading);
    for (const Measurement& earlier : next.measurements) {
      const Innovation again = innovationOf(next.state, earlier.T_world_body, earlier.covariance);
      if (!again.ok || !applyInnovation(next.state, again, earlier.covariance)) {
        return invalid(where + "re-applying a later update failed numerically; ignored");
      }
    }
    if (!stateFinite(next.state)) return invalid(where + "re-propagation is not finite; ignored");
    tail.push_back(std::move(next));
    ++result.repropagated_steps;
  }
  nodes_.erase(nodes_.begin() + static_cast<std::ptrdiff_t>(first), nodes_.end());
  for (Node& n : tail) nodes_.push_back(std::move(n));
  awaiting_fix_ = false;
  result.accepted = true;
  return result;
}

const EkfState& ErrorStateEkf::current() const { return nodes_.empty() ? empty_state_ : nodes_.back().state; }

int64_t ErrorStateEkf::oldestNs() const { return nodes_.empty() ? 0 : nodes_.front().state.t_ns; }

int64_t ErrorStateEkf::newestNs() const { return nodes_.empty() ? 0 : nodes_.back().state.t_ns; }

Result<EkfState> ErrorStateEkf::stateAt(int64_t t_ns) const {
  const std::string where = "ekf state at " + std::to_string(t_ns) + " ns: ";
  if (!initialized()) return invalid(where + "the filter is not initialized");
  if (t_ns < nodes_.front().state.t_ns) {
    return invalid(where + "older than the ring buffer (oldest " + std::to_string(nodes_.front().state.t_ns) + " ns)");
  }
  const Node& last = nodes_.back();
  if (t_ns >= last.state.t_ns) {
    if (t_ns == last.state.t_ns) return last.state;
    if (t_ns - last.state.t_ns > nanoseconds(options_.max_extrapolation_s)) {
      return invalid(where + "more than max_extrapolation_s after the newest reading (" +
                     std::to_string(last.state.t_ns) + " ns)");
    }
    ImuSample held;
    if (last.has_reading) {
      held = heldAt(last.reading, t_ns);
    } else {
      // No reading yet: no rotation, no acceleration.
      held.t_ns = t_ns;
      held.gyro_body = last.state.gyro_bias;
      held.accel_body = last.state.accel_bias - last.state.R_world_body.transpose() * options_.gravity_world;
    }
    Node from = last;
    from.reading = held;
    from.has_reading = true;
    return propagate(from, held);
  }
  auto it =
      std::upper_bound(nodes_.begin(), nodes_.end(), t_ns, [](int64_t t, const Node& n) { return t < n.state.t_ns; });
  const Node& before = *(it - 1);
  if (before.state.t_ns == t_ns) return before.state;
  return propagate(before, interpolate(before.reading, it->reading, t_ns));
}

Result<EkfPrediction> ErrorStateEkf::predict(int64_t t_ns) const {
  Result<EkfState> s = stateAt(t_ns);
  if (!s.ok()) return s.error();
  EkfPrediction p;
  p.state = *s;
  p.T_world_body = s->T_world_body();
  p.T_world_camera = p.T_world_body * options_.T_body_camera;
  p.v_world_body = s->v_world_body;
  p.covariance_body = bodyPoseCovariance(*s);
  p.covariance_camera = cameraPoseCovariance(*s, options_.T_body_camera);
  p.extrapolated_s = std::max(0.0, seconds(t_ns - nodes_.back().state.t_ns));
  return p;
}

Pose ErrorStateEkf::cameraPose(const EkfState& state) const { return state.T_world_body() * options_.T_body_camera; }

Matrix6d ErrorStateEkf::cameraCovariance(const EkfState& state) const {
  return cameraPoseCovariance(state, options_.T_body_camera);
}

std::vector<EkfState> ErrorStateEkf::drainOutputs() {
  std::vector<EkfState> out(outputs_.begin(), outputs_.end());
  outputs_.clear();
  return out;
}

}  // namespace vkloc
