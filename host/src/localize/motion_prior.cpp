#include "vkloc/localize/motion_prior.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "vkloc/core/numeric.hpp"
#include "vkloc/core/se3.hpp"

namespace vkloc {
Status validateInertialAiding(const InertialAiding& ia) {
  if (!isValidPose(ia.T_body_camera)) {
    return makeError(ErrorCode::kInvalidArgument, "Localizer: inertial.T_body_camera is not a finite rigid transform");
  }
  if (!finiteIn(ia.gate_depth_ratio, 0.0, 1e3) || !finiteIn(ia.gate_sigmas, 0.0, 1e3) ||
      !finiteIn(ia.gate_rotation_deg, 0.0, 180.0) || !finiteIn(ia.max_inertial_s, 0.0, 1e4) ||
      !finiteIn(ia.unknown_velocity_depths_per_s, 0.0, 1e3)) {
    return makeError(ErrorCode::kInvalidArgument,
                     "Localizer: need inertial.gate_depth_ratio and gate_sigmas in 0..1e3, gate_rotation_deg in "
                     "0..180, max_inertial_s in 0..1e4 and unknown_velocity_depths_per_s in 0..1e3");
  }
  VKLOC_TRY_STATUS(validateInertialOptions(ia.predictor));
  EkfOptions ekf = ia.ekf;
  ekf.gravity_world = ia.predictor.gravity_world;
  ekf.T_body_camera = ia.T_body_camera;
  return validateEkfOptions(ekf);
}

// --- ConstantVelocityPrior ----------------------------------------------------------------------

Status ConstantVelocityPrior::addImu(const ImuSample& sample) {
  if (!sample.gyro_body.allFinite() || !sample.accel_body.allFinite()) {
    return makeError(ErrorCode::kInvalidArgument, "IMU reading: non-finite rate or acceleration");
  }
  if (last_imu_t_ns_ && sample.t_ns <= *last_imu_t_ns_) {
    return makeError(ErrorCode::kInvalidArgument, "IMU reading: time " + std::to_string(sample.t_ns) +
                                                      " ns is not after the previous reading's " +
                                                      std::to_string(*last_imu_t_ns_) + " ns");
  }
  last_imu_t_ns_ = sample.t_ns;
  return Status::success();
}

std::optional<MotionPrediction> ConstantVelocityPrior::predict(int64_t t_ns) const {
  if (!last_pose_) return std::nullopt;
  MotionPrediction p;
  p.t_ns = t_ns;
  p.T_world_camera = *last_pose_;
  if (model_ == MotionModel::kLastPose) return p;
  if (!prev_pose_ && initial_velocity_ && last_pose_timed_) {
    // Only the start pose and the caller's velocity are known: move at that velocity (up to 1 s).
    const double dt = static_cast<double>(t_ns - last_pose_t_ns_) * 1e-9;
    if (dt > 0 && dt <= 1.0) p.T_world_camera.translation() += dt * *initial_velocity_;
    return p;
  }
  if (!prev_pose_) {
    p.velocity_unobserved = !initial_velocity_;
    return p;
  }
  if (last_pose_t_ns_ <= prev_pose_t_ns_) return p;
  // Constant velocity: the last inter-frame motion (camera frame) scaled to the time step.
  const Vector6d xi = logSE3(prev_pose_->inverse() * *last_pose_);
  const double scale =
      static_cast<double>(t_ns - last_pose_t_ns_) / static_cast<double>(last_pose_t_ns_ - prev_pose_t_ns_);
  if (!std::isfinite(scale) || scale <= 0 || scale > 10) return p;
  p.T_world_camera = *last_pose_ * expSE3(scale * xi);
  return p;
}

void ConstantVelocityPrior::push(int64_t t_ns, const Pose& T_world_camera) {
  // The reset pose has no time: it does not make a motion with the first timed pose.
  if (last_pose_timed_) {
    prev_pose_ = last_pose_;
    prev_pose_t_ns_ = last_pose_t_ns_;
  }
  last_pose_timed_ = true;
  last_pose_ = T_world_camera;
  last_pose_t_ns_ = t_ns;
}

void ConstantVelocityPrior::addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d&) {
  push(t_ns, T_world_camera);
}

std::optional<BridgedPose> ConstantVelocityPrior::bridge(int64_t, const std::optional<MotionPrediction>&,
                                                         const Pose& guess) {
  // Keep the last trusted pose and its motion: the next guess extrapolates the last tracked
  // velocity over the time since (up to 10 frame intervals), so a camera that keeps moving
  // through a few untrackable frames is found again.
  if (!last_pose_) last_pose_ = guess;
  return std::nullopt;
}

bool ConstantVelocityPrior::carryOn(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                    const Pose& guess) {
  bridge(t_ns, prediction, guess);
  if (!prediction || !prediction->inertial) return false;
  // The inertial pose carries the motion on: should the prediction expire (max_inertial_s), the
  // constant-velocity guess continues from it, not from the last visual pose.
  push(t_ns, prediction->T_world_camera);
  return true;
}

void ConstantVelocityPrior::reset(const std::optional<Pose>& T_world_camera,
                                  const std::optional<Eigen::Vector3d>& v_world_camera, double /*sigma_velocity_m_s*/) {
  prev_pose_.reset();
  last_pose_.reset();
  last_imu_t_ns_.reset();
  last_pose_timed_ = false;
  initial_velocity_.reset();
  if (T_world_camera && isValidPose(*T_world_camera)) last_pose_ = *T_world_camera;
  if (v_world_camera && v_world_camera->allFinite()) initial_velocity_ = *v_world_camera;
}

// --- InertialPrior --------------------------------------------------------------------------------

InertialPrior::InertialPrior(const InertialAiding& aiding, MotionModel model)
    : aiding_(aiding), motion_(model), predictor_(aiding.predictor) {}

Status InertialPrior::addImu(const ImuSample& sample) { return predictor_.addImu(sample); }

std::optional<MotionPrediction> InertialPrior::predict(int64_t t_ns) const {
  if (aiding_.enabled && predictor_.hasImu()) {
    std::optional<InertialPrediction> inertial = predictor_.predict(t_ns);
    if (inertial && inertial->since_fix_s <= aiding_.max_inertial_s) {
      MotionPrediction p;
      p.t_ns = t_ns;
      p.T_world_camera = inertial->T_world_body * aiding_.T_body_camera;
      p.inertial = true;
      p.sigma_m = inertial->sigma_m;
      p.fit_rms_m = inertial->fit_rms_m;
      return p;
    }
  }
  return motion_.predict(t_ns);
}

bool InertialPrior::consistent(const MotionPrediction& prediction, const Pose& T_world_camera, const Matrix6d&,
                               double scene_depth_m) const {
  if (!prediction.inertial) return true;
  // Consistency gate: the visual pose must agree with the IMU-propagated one.
  const Pose d = prediction.T_world_camera.inverse() * T_world_camera;
  const double depth = scene_depth_m > 0 ? scene_depth_m : 1.0;
  const double gate_m =
      aiding_.gate_depth_ratio * depth + aiding_.gate_sigmas * std::hypot(prediction.sigma_m, prediction.fit_rms_m);
  return !(d.translation().norm() > gate_m || rotationAngleDeg(d.linear()) > aiding_.gate_rotation_deg);
}

void InertialPrior::addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) {
  predictor_.addFix(t_ns, T_world_camera * aiding_.T_body_camera.inverse());
  last_covariance_ = covariance;
  motion_.addVisualPose(t_ns, T_world_camera, covariance);
}

std::optional<BridgedPose> InertialPrior::bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                                 const Pose& guess) {
  if (!motion_.carryOn(t_ns, prediction, guess)) return std::nullopt;
  // The last accepted frame's rotation uncertainty (gyro drift over max_inertial_s is far below
  // it), the prediction's in translation.
  BridgedPose out;
  out.T_world_camera = prediction->T_world_camera;
  out.covariance.bottomRightCorner<3, 3>() = last_covariance_.bottomRightCorner<3, 3>();
  out.covariance.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * (prediction->sigma_m * prediction->sigma_m);
  return out;
}

void InertialPrior::reset(const std::optional<Pose>& T_world_camera,
                          const std::optional<Eigen::Vector3d>& v_world_camera, double /*sigma_velocity_m_s*/) {
  predictor_.reset();  // timestamps may start over
  motion_.reset(T_world_camera, v_world_camera);
}

// --- EkfPrior -----------------------------------------------------------------------------------

namespace {

EkfOptions ekfOptionsOf(const InertialAiding& aiding) {
  EkfOptions o = aiding.ekf;
  o.gravity_world = aiding.predictor.gravity_world;
  o.T_body_camera = aiding.T_body_camera;
  return o;
}

}  // namespace

EkfPrior::EkfPrior(const InertialAiding& aiding, MotionModel model) : aiding_(aiding), motion_(model) {
  // Options are validated by Localizer::create (validateInertialAiding); a failure here leaves
  // the default filter, which behaves the same with default options.
  if (auto created = ErrorStateEkf::create(ekfOptionsOf(aiding)); created.ok()) ekf_ = std::move(created).value();
}

Status EkfPrior::addImu(const ImuSample& sample) {
  if (!aiding_.enabled) return motion_.addImu(sample);
  Status status = ekf_.addImu(sample);
  // A reading the filter took (a gap is reported but used) makes it the prior from now on.
  if (status.ok() || ekf_.newestNs() == sample.t_ns) has_imu_ = true;
  return status;
}

std::optional<MotionPrediction> EkfPrior::filterAt(int64_t t_ns) const {
  Result<EkfPrediction> p = ekf_.predict(t_ns);
  if (!p.ok()) return std::nullopt;
  MotionPrediction out;
  out.t_ns = t_ns;
  out.T_world_camera = p->T_world_camera;
  out.inertial = true;
  out.covariance = p->covariance_camera;
  // Largest position sigma (the translation block is in the camera frame: its trace bounds it).
  out.sigma_m = std::sqrt(std::max(0.0, p->covariance_camera.topLeftCorner<3, 3>().trace()));
  out.velocity_unobserved = velocity_unobserved_;
  out.v_world_body = p->v_world_body;
  out.sigma_velocity_m_s = std::sqrt(std::max(0.0, p->state.P.block<3, 3>(3, 3).diagonal().maxCoeff()));
  return out;
}

std::optional<Eigen::Matrix3d> EkfPrior::attitude(int64_t t_ns) const {
  if (!ekf_.initialized()) return std::nullopt;
  Result<EkfPrediction> p = ekf_.predict(t_ns);
  if (!p.ok()) return std::nullopt;
  return p->T_world_camera.linear();
}

std::optional<MotionPrediction> EkfPrior::predict(int64_t t_ns) const {
  if (aiding_.enabled && ekf_.initialized() &&
      static_cast<double>(t_ns - last_update_t_ns_) * 1e-9 <= aiding_.max_inertial_s) {
    if (std::optional<MotionPrediction> p = filterAt(t_ns)) return p;
  }
  return motion_.predict(t_ns);
}

bool EkfPrior::consistent(const MotionPrediction& prediction, const Pose& T_world_camera, const Matrix6d& covariance,
                          double scene_depth_m) const {
  last_innovation_ = std::numeric_limits<double>::quiet_NaN();
  if (!prediction.inertial || !ekf_.initialized() || ekf_.awaitingFix()) return true;
  // The filter's own test: the same residual, Jacobian, scale, floors and threshold as the
  // update that follows when the pose passes (at the frame's time: the IMU may run ahead of a
  // frame delivered late, and the update is then a delayed one).
  const int64_t t_test = std::min(prediction.t_ns, ekf_.newestNs());
  Result<EkfUpdate> u = ekf_.testCameraPose(t_test, T_world_camera, covariance);
  if (!u.ok()) return true;  // cannot be tested (e.g. no reading yet at the frame's time)
  last_innovation_ = u->mahalanobis_sq;
  if (u->accepted) return true;
  // The chi-square test trusts the filter's covariance, which shrinks with every update although
  // the alignment's errors on real imagery (model-to-image differences) stay alike from frame to
  // frame: a filter that has drifted by a few of its sigmas would then refuse every correct pose
  // and drift further. A pose within the window gate's floor of the prediction (a fraction of the
  // scene depth, and gate_rotation_deg) is no evidence of a wrong alignment and is taken.
  const Pose d = prediction.T_world_camera.inverse() * T_world_camera;
  const double depth = scene_depth_m > 0 ? scene_depth_m : 1.0;
  return d.translation().norm() <= aiding_.gate_depth_ratio * depth &&
         rotationAngleDeg(d.linear()) <= aiding_.gate_rotation_deg;
}

void EkfPrior::addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) {
  motion_.addVisualPose(t_ns, T_world_camera, covariance);
  updated_t_ns_.reset();
  if (!aiding_.enabled || !has_imu_) return;
  last_update_t_ns_ = t_ns;
  if (!ekf_.initialized()) {
    // The first trusted pose starts the filter: with the caller's velocity (tight unless the
    // caller gave its sigma), else an unknown one (initial_sigma_velocity_m_s) that the next
    // poses pin down.
    const EkfOptions& o = ekf_.options();
    double sigma_v = start_velocity_ ? start_sigma_velocity_m_s_ : o.initial_sigma_velocity_m_s;
    if (!start_velocity_ && scene_depth_m_ > 0 && aiding_.unknown_velocity_depths_per_s > 0) {
      sigma_v = std::max(0.5, aiding_.unknown_velocity_depths_per_s * scene_depth_m_);
    }
    Vector15d sigma;
    sigma << Eigen::Vector3d::Constant(o.initial_sigma_position_m), Eigen::Vector3d::Constant(sigma_v),
        Eigen::Vector3d::Constant(o.initial_sigma_attitude_rad),
        Eigen::Vector3d::Constant(o.initial_sigma_gyro_bias_rad_s),
        Eigen::Vector3d::Constant(o.initial_sigma_accel_bias_m_s2);
    const Matrix15d P0 = sigma.cwiseAbs2().asDiagonal();
    const Eigen::Vector3d v_body = start_velocity_ ? *start_velocity_ : Eigen::Vector3d::Zero();
    if (!ekf_.initializeFromCamera(t_ns, T_world_camera, v_body, P0).ok()) return;
    // The start pose is itself a measurement (its covariance tightens the initial sigmas).
    if (ekf_.updateCameraPose(t_ns, T_world_camera, covariance, EkfGate::kForceAccept).ok()) updated_t_ns_ = t_ns;
    velocity_unobserved_ = !start_velocity_;
    return;
  }
  velocity_unobserved_ = false;
  // The pose passed consistent()'s gate (or could not be tested): applied as is. A pose older
  // than the newest reading is a delayed update; one newer than the readings cannot be applied.
  const int64_t t_update = std::min(t_ns, ekf_.newestNs());
  if (ekf_.updateCameraPose(t_update, T_world_camera, covariance, EkfGate::kForceAccept).ok()) updated_t_ns_ = t_ns;
}

std::optional<MotionPrediction> EkfPrior::filtered(int64_t t_ns) const {
  if (!aiding_.enabled || !ekf_.initialized() || !updated_t_ns_ || *updated_t_ns_ != t_ns) return std::nullopt;
  return filterAt(t_ns);
}

std::optional<BridgedPose> EkfPrior::bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                            const Pose& guess) {
  if (!motion_.carryOn(t_ns, prediction, guess)) return std::nullopt;
  BridgedPose out;
  out.T_world_camera = prediction->T_world_camera;
  out.covariance = prediction->covariance;
  return out;
}

void EkfPrior::setSceneDepth(double depth_m) {
  if (std::isfinite(depth_m) && depth_m > 0 && scene_depth_m_ <= 0) scene_depth_m_ = depth_m;
}

void EkfPrior::reset(const std::optional<Pose>& T_world_camera, const std::optional<Eigen::Vector3d>& v_world_camera,
                     double sigma_velocity_m_s) {
  scene_depth_m_ = 0;
  ekf_.reset();
  has_imu_ = false;
  velocity_unobserved_ = false;
  motion_.reset(T_world_camera, v_world_camera);
  last_update_t_ns_ = 0;
  updated_t_ns_.reset();
  last_innovation_ = std::numeric_limits<double>::quiet_NaN();
  start_velocity_.reset();
  start_sigma_velocity_m_s_ = std::isfinite(sigma_velocity_m_s) && sigma_velocity_m_s > 0 ? sigma_velocity_m_s : 0.1;
  if (v_world_camera && v_world_camera->allFinite()) start_velocity_ = *v_world_camera;
}

std::vector<FilterOutput> EkfPrior::takeOutputs() {
  std::vector<FilterOutput> out;
  for (const EkfState& s : ekf_.drainOutputs()) {
    FilterOutput o;
    o.t_ns = s.t_ns;
    o.T_world_camera = ekf_.cameraPose(s);
    o.v_world_body = s.v_world_body;
    o.covariance = ekf_.cameraCovariance(s);
    o.sigma_velocity = s.P.block<3, 3>(3, 3).diagonal().cwiseMax(0.0).cwiseSqrt();
    out.push_back(o);
  }
  return out;
}

// --- ViewPrior ----------------------------------------------------------------------------------

// T_world_camera expSE3(xi_c) T_camera_view = T_world_view expSE3(Ad(T_view_camera) xi_c).
Matrix6d ViewPrior::covarianceToView(const Matrix6d& covariance_camera) const {
  const Matrix6d Ad = adjointSE3(T_camera_view_.inverse());
  return Ad * covariance_camera * Ad.transpose();
}

Matrix6d ViewPrior::covarianceToCamera(const Matrix6d& covariance_view) const {
  const Matrix6d Ad = adjointSE3(T_camera_view_);
  return Ad * covariance_view * Ad.transpose();
}

MotionPrediction ViewPrior::toView(MotionPrediction p) const {
  p.T_world_camera = toView(p.T_world_camera);
  p.covariance = covarianceToView(p.covariance);
  return p;
}

std::optional<MotionPrediction> ViewPrior::predict(int64_t t_ns) const {
  std::optional<MotionPrediction> p = prior_->predict(t_ns);
  if (p) p = toView(*p);
  return p;
}

bool ViewPrior::consistent(const MotionPrediction& prediction, const Pose& T_world_view, const Matrix6d& covariance,
                           double scene_depth_m) const {
  MotionPrediction p = prediction;
  p.T_world_camera = toCamera(p.T_world_camera);
  p.covariance = covarianceToCamera(p.covariance);
  return prior_->consistent(p, toCamera(T_world_view), covarianceToCamera(covariance), scene_depth_m);
}

void ViewPrior::addVisualPose(int64_t t_ns, const Pose& T_world_view, const Matrix6d& covariance) {
  prior_->addVisualPose(t_ns, toCamera(T_world_view), covarianceToCamera(covariance));
}

std::optional<BridgedPose> ViewPrior::bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                             const Pose& guess) {
  std::optional<MotionPrediction> p = prediction;
  if (p) {
    p->T_world_camera = toCamera(p->T_world_camera);
    p->covariance = covarianceToCamera(p->covariance);
  }
  std::optional<BridgedPose> b = prior_->bridge(t_ns, p, toCamera(guess));
  if (b) {
    b->T_world_camera = toView(b->T_world_camera);
    b->covariance = covarianceToView(b->covariance);
  }
  return b;
}

void ViewPrior::reset(const std::optional<Pose>& T_world_view, const std::optional<Eigen::Vector3d>& v_world,
                      double sigma_velocity_m_s) {
  prior_->reset(T_world_view ? std::optional<Pose>(toCamera(*T_world_view)) : std::nullopt, v_world,
                sigma_velocity_m_s);
}

std::optional<MotionPrediction> ViewPrior::filtered(int64_t t_ns) const {
  std::optional<MotionPrediction> p = prior_->filtered(t_ns);
  if (p) p = toView(*p);
  return p;
}

std::optional<Eigen::Matrix3d> ViewPrior::attitude(int64_t t_ns) const {
  std::optional<Eigen::Matrix3d> R = prior_->attitude(t_ns);
  if (R) R = *R * T_camera_view_.linear();
  return R;
}

std::optional<Pose> ViewPrior::lastPose() const {
  std::optional<Pose> p = prior_->lastPose();
  if (p) p = toView(*p);
  return p;
}

bool refusalCountsAgainstPrior(double score, const std::vector<double>& taken_scores, size_t window,
                               double restart_min_score, double min_score) {
  if (score >= restart_min_score) return true;
  if (!(score >= min_score)) return false;  // NaN counts for nothing
  if (window == 0 || taken_scores.size() < window) return false;
  return std::all_of(taken_scores.end() - static_cast<std::ptrdiff_t>(window), taken_scores.end(),
                     [score](double taken) { return score > taken; });
}

bool attitudeFavoursFeaturePose(const MotionPrediction& prediction, const Pose& T_world_feature,
                                const Pose& T_world_aligned, double sigmas) {
  if (!(sigmas > 0) || !prediction.inertial) return false;
  const Eigen::Matrix3d C = prediction.covariance.bottomRightCorner<3, 3>();
  const Eigen::LLT<Eigen::Matrix3d> llt(0.5 * (C + C.transpose()));
  if (!C.allFinite() || llt.info() != Eigen::Success) return false;
  // phi with R_x = R_predicted expSO3(phi) (MotionPrediction::covariance's rotation part).
  const Eigen::Matrix3d R_predicted_world = prediction.T_world_camera.linear().transpose();
  // sqrt(phi^T C^-1 phi); NaN for a pose that is not finite (then false below).
  const auto mahalanobis = [&](const Pose& T) {
    if (!T.matrix().allFinite()) return std::numeric_limits<double>::quiet_NaN();
    const Eigen::Vector3d phi = logSO3(R_predicted_world * T.linear());
    return std::sqrt(phi.dot(llt.solve(phi)));
  };
  return mahalanobis(T_world_aligned) > sigmas && mahalanobis(T_world_feature) <= 0.5 * sigmas;
}

}  // namespace vkloc
