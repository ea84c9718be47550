// vkloc: the Localizer's motion prior: the pose guess of each frame (the alignment's start),
// whether a frame's visual pose agrees with the motion, and what a frame without a trusted
// visual pose reports. ConstantVelocityPrior extrapolates the last two trusted poses;
// InertialPrior adds IMU readings integrated from the accepted visual poses (the propagation
// half of seed paper 000's filter, sec. IV-D) with a consistency gate. The error-state EKF
// plugs in here as another MotionPrior.
//
// Frames: poses are T_world_camera (camera to world, metres); the IMU and its readings are in
// the body frame, T_body_camera maps camera points into it. Times are int64 nanoseconds.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/se3.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/fusion/error_state_ekf.hpp"
#include "vkloc/fusion/inertial_predictor.hpp"
#include "vkloc/fusion/sensors.hpp"

namespace vkloc {

/// How the pose guess for a frame is predicted when there is no IMU prediction.
enum class MotionModel {
  kConstantVelocity,  ///< Last pose moved by the last inter-frame motion, scaled to the time step.
  kLastPose,          ///< The last pose as it is.
};

/// How IMU readings and visual poses are fused.
enum class InertialFilter {
  /// Error-state EKF (ErrorStateEkf, seed 000 sec. IV-D): IMU propagation from the first frame
  /// on (gyro-predicted rotation at once), visual poses as measurements with their covariance,
  /// chi-square gate; the velocity comes from the caller (reset) or the first visual fixes.
  kEkf,
  /// Velocity fitted over a window of visual fixes (InertialPredictor) with a distance gate.
  kWindowFit,
};

/// Inertial aiding, active once IMU readings are given (Localizer::addImu): the guess for a frame
/// is the IMU-propagated pose (InertialPredictor, fed with the accepted visual poses), a visual
/// result farther from it than the gate is rejected, and a frame whose alignment is lost or
/// rejected reports the inertial pose (state kInertial) for up to max_inertial_s after the last
/// accepted visual pose. Gate: translation <= gate_depth_ratio x scene depth + gate_sigmas x
/// sqrt(sigma_pred^2 + fit_rms^2) (InertialPrediction), rotation <= gate_rotation_deg.
struct InertialAiding {
  bool enabled = true;  ///< Use readings given with addImu.
  InertialFilter filter =
      InertialFilter::kEkf;  ///< Fusion; kEkf uses `ekf` (its gravity and T_body_camera are set from these).
  /// kEkf: noise densities, initial sigmas, gate, buffer. An unknown start velocity is taken as
  /// 0 with a 1-sigma of 15 m/s (a drone in flight) until the scene depth scales it
  /// (unknown_velocity_depths_per_s). The alignment's Gauss-Newton covariance is taken 10 times
  /// larger (measurement_covariance_scale): it counts only the pixel noise of the edge residuals,
  /// taken as independent, not the model-to-image differences that dominate on real imagery
  /// (README, "Filter", for what larger factors do).
  EkfOptions ekf = [] {
    EkfOptions o;
    o.initial_sigma_velocity_m_s = 15.0;
    o.measurement_covariance_scale = 10.0;
    return o;
  }();
  Pose T_body_camera = Pose::Identity();       ///< Camera frame into the body (IMU) frame, metres.
  InertialOptions predictor;                   ///< Gravity, velocity-fit window, uncertainty model.
  double gate_depth_ratio = 0.005;             ///< Translation gate floor, fraction of the median scene depth.
  double gate_sigmas = 4.0;                    ///< Translation gate, prediction sigmas added to the floor.
  double gate_rotation_deg = 1.5;              ///< Rotation gate, degrees.
  double max_inertial_s = 2.0;                 ///< Longest inertial-only stretch before frames are lost, seconds.
  double unknown_velocity_depths_per_s = 2.0;  ///< kEkf: see EkfPrior::setSceneDepth (0 = off).
};

/// kInvalidArgument naming the field for values out of range.
Status validateInertialAiding(const InertialAiding& aiding);

/// A predicted camera pose.
struct MotionPrediction {
  int64_t t_ns = 0;  ///< Time the prediction is for, nanoseconds.
  Pose T_world_camera = Pose::Identity();
  bool inertial = false;  ///< Propagated from IMU readings (else the motion model's extrapolation).
  double sigma_m = 0;     ///< 1-sigma position error of an inertial prediction, metres (0 otherwise).
  double fit_rms_m = 0;   ///< RMS of the visual poses about the fitted motion, metres (inertial only).
  /// Covariance of xi = [rho; phi] in the camera frame (T_true = T_world_camera expSE3(xi)), m^2
  /// and rad^2; zero when the prior has none (only kEkf fills it).
  Matrix6d covariance = Matrix6d::Zero();
  /// kEkf: the filter started at an unknown velocity that no second pose has pinned down yet, so
  /// its gate cannot tell a wrong pose from a right one (the velocity's sigma admits both).
  /// Constant-velocity model (not inertial): a single pose since the reset and no velocity given,
  /// so the prediction holds that pose whatever the camera does.
  bool velocity_unobserved = false;
  /// kEkf: the filter's velocity of the body, world frame, m/s (the camera's up to its lever arm
  /// turning), and its largest 1-sigma over the world axes; nullopt for the other priors.
  std::optional<Eigen::Vector3d> v_world_body;
  double sigma_velocity_m_s = 0;
};

/// The filter's state at one IMU reading (kEkf), for output at the IMU rate.
struct FilterOutput {
  int64_t t_ns = 0;
  Pose T_world_camera = Pose::Identity();
  Eigen::Vector3d v_world_body = Eigen::Vector3d::Zero();    ///< Velocity of the body, world frame, m/s.
  Matrix6d covariance = Matrix6d::Zero();                    ///< Camera pose, as MotionPrediction::covariance.
  Eigen::Vector3d sigma_velocity = Eigen::Vector3d::Zero();  ///< 1-sigma of v per world axis, m/s.
};

/// The pose a frame without a trusted visual pose reports.
struct BridgedPose {
  Pose T_world_camera = Pose::Identity();
  Matrix6d covariance = Matrix6d::Zero();  ///< [rho; phi] in the camera frame, m^2 and rad^2.
};

/// Interface of the motion priors. Not thread-safe.
class MotionPrior {
 public:
  virtual ~MotionPrior() = default;
  /// One IMU reading, body frame, in time order. kInvalidArgument for a non-finite value or a
  /// time not after the previous reading's (the reading is ignored). Priors without an IMU
  /// model check and ignore readings.
  virtual Status addImu(const ImuSample& sample) = 0;
  /// The camera pose at t_ns (after the last frame's time), or nullopt before any pose is known.
  virtual std::optional<MotionPrediction> predict(int64_t t_ns) const = 0;
  /// Whether a trusted visual pose (with its alignment covariance, camera frame) agrees with
  /// `prediction` (the inertial gate); `scene_depth_m` is the keyframe's median depth (0 = unknown).
  virtual bool consistent(const MotionPrediction& prediction, const Pose& T_world_camera, const Matrix6d& covariance,
                          double scene_depth_m) const = 0;
  /// The frame at t_ns has a trusted visual pose with its covariance (camera frame).
  virtual void addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) = 0;
  /// The frame at t_ns has no trusted visual pose; `prediction` was this frame's, `guess` its
  /// alignment's start. Returns the pose to report (bridged by the IMU), or nullopt (lost).
  virtual std::optional<BridgedPose> bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                            const Pose& guess) = 0;
  /// Forgets the motion (and IMU readings: timestamps may start over) and restarts from
  /// T_world_camera, or from nothing when it is nullopt or invalid, moving at v_world_camera
  /// (the camera's velocity in the world frame, m/s) when it is given and finite, else at an
  /// unknown velocity. `sigma_velocity_m_s` > 0 is the given velocity's 1-sigma (m/s; 0: known
  /// well, 0.1 m/s); priors without a velocity covariance ignore it.
  virtual void reset(const std::optional<Pose>& T_world_camera,
                     const std::optional<Eigen::Vector3d>& v_world_camera = std::nullopt,
                     double sigma_velocity_m_s = 0) = 0;
  /// The last trusted (or bridged, or reset) camera pose.
  virtual std::optional<Pose> lastPose() const = 0;
  /// The prior's estimate of the camera at t_ns when it fuses the visual poses with other
  /// measurements and took one at t_ns (addVisualPose): the filter's posterior, pose and
  /// covariance (camera frame). nullopt for priors that do not fuse (constant velocity, the
  /// window fit: their pose at t_ns is the visual one) and when no pose at t_ns was taken.
  virtual std::optional<MotionPrediction> filtered(int64_t /*t_ns*/) const { return std::nullopt; }
  /// Squared Mahalanobis distance of the last visual pose checked by consistent() (NaN when the
  /// prior has no covariance to test it with).
  virtual double lastInnovation() const { return std::numeric_limits<double>::quiet_NaN(); }
  /// The filter states since the last call, oldest first (IMU rate; empty for priors without one).
  virtual std::vector<FilterOutput> takeOutputs() { return {}; }
  /// R_world_camera at t_ns from the IMU while a filter runs, however long since its last visual
  /// pose (predict() has then fallen back to the motion model): the gyro carries the attitude on
  /// when nothing carries the position, and a stabilised view needs no more. nullopt for priors
  /// without a filter, and before the filter starts.
  virtual std::optional<Eigen::Matrix3d> attitude(int64_t /*t_ns*/) const { return std::nullopt; }
  /// The median depth of the scene in view (metres; the first keyframe's), which scales what an
  /// unknown start velocity may be. Priors without a velocity prior ignore it.
  virtual void setSceneDepth(double /*depth_m*/) {}
};

/// A prior over the physical camera seen through a view that turns with each frame (the camera
/// front's T_camera_view, a rotation about the optical centre): poses and covariances in and out
/// are the view's, the wrapped prior works on the camera's. setView() before each frame's calls.
class ViewPrior final : public MotionPrior {
 public:
  explicit ViewPrior(std::unique_ptr<MotionPrior> camera_prior) : prior_(std::move(camera_prior)) {}
  /// The view of the frames to come: T_camera_view (camera frame into the view's parent).
  void setView(const Pose& T_camera_view) { T_camera_view_ = T_camera_view; }
  const Pose& view() const { return T_camera_view_; }
  /// The wrapped prior (camera frame).
  const MotionPrior& cameraPrior() const { return *prior_; }

  Status addImu(const ImuSample& sample) override { return prior_->addImu(sample); }
  std::optional<MotionPrediction> predict(int64_t t_ns) const override;
  bool consistent(const MotionPrediction& prediction, const Pose& T_world_view, const Matrix6d& covariance,
                  double scene_depth_m) const override;
  void addVisualPose(int64_t t_ns, const Pose& T_world_view, const Matrix6d& covariance) override;
  std::optional<BridgedPose> bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                    const Pose& guess) override;
  void reset(const std::optional<Pose>& T_world_view, const std::optional<Eigen::Vector3d>& v_world = std::nullopt,
             double sigma_velocity_m_s = 0) override;
  std::optional<Pose> lastPose() const override;
  std::optional<MotionPrediction> filtered(int64_t t_ns) const override;
  double lastInnovation() const override { return prior_->lastInnovation(); }
  std::vector<FilterOutput> takeOutputs() override { return prior_->takeOutputs(); }
  std::optional<Eigen::Matrix3d> attitude(int64_t t_ns) const override;
  void setSceneDepth(double depth_m) override { prior_->setSceneDepth(depth_m); }

  /// Pose and covariance (right perturbation) of the camera from the view's, and back.
  Pose toCamera(const Pose& T_world_view) const { return T_world_view * T_camera_view_.inverse(); }
  Pose toView(const Pose& T_world_camera) const { return T_world_camera * T_camera_view_; }
  Matrix6d covarianceToCamera(const Matrix6d& covariance_view) const;
  Matrix6d covarianceToView(const Matrix6d& covariance_camera) const;

 private:
  MotionPrediction toView(MotionPrediction p) const;
  std::unique_ptr<MotionPrior> prior_;
  Pose T_camera_view_ = Pose::Identity();
};

/// Constant velocity (or last pose) from the last two poses.
class ConstantVelocityPrior final : public MotionPrior {
 public:
  explicit ConstantVelocityPrior(MotionModel model = MotionModel::kConstantVelocity) : model_(model) {}
  Status addImu(const ImuSample& sample) override;
  /// kConstantVelocity: the last inter-frame motion (camera frame) scaled to the time since the
  /// last pose (up to 10 frame intervals; beyond, the last pose).
  std::optional<MotionPrediction> predict(int64_t t_ns) const override;
  bool consistent(const MotionPrediction&, const Pose&, const Matrix6d&, double) const override { return true; }
  void addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) override;
  /// Keeps the last pose and its motion (the next guess extrapolates over the time since);
  /// reports nothing.
  std::optional<BridgedPose> bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                    const Pose& guess) override;
  void reset(const std::optional<Pose>& T_world_camera,
             const std::optional<Eigen::Vector3d>& v_world_camera = std::nullopt,
             double sigma_velocity_m_s = 0) override;
  std::optional<Pose> lastPose() const override { return last_pose_; }

  /// Moves the motion on by one pose at t_ns (the last one becomes the one before).
  void push(int64_t t_ns, const Pose& T_world_camera);
  /// For the inertial priors' bridge: bridge(), then, when `prediction` is inertial, push() its
  /// pose (the motion goes on from it should the inertial prediction expire); returns whether it was.
  bool carryOn(int64_t t_ns, const std::optional<MotionPrediction>& prediction, const Pose& guess);

 private:
  MotionModel model_;
  std::optional<Pose> last_pose_;
  std::optional<Pose> prev_pose_;
  int64_t last_pose_t_ns_ = 0;
  int64_t prev_pose_t_ns_ = 0;
  bool last_pose_timed_ = false;  ///< last_pose_ came with a time (not only from reset).
  std::optional<Eigen::Vector3d> initial_velocity_;
  std::optional<int64_t> last_imu_t_ns_;
};

/// InertialAiding over a constant-velocity prior (which predicts when the IMU cannot).
class InertialPrior final : public MotionPrior {
 public:
  InertialPrior(const InertialAiding& aiding, MotionModel model);
  Status addImu(const ImuSample& sample) override;
  /// The IMU-propagated pose while aiding is enabled, readings were given, enough visual poses
  /// were accepted and the last one is at most max_inertial_s old; else the motion model's.
  std::optional<MotionPrediction> predict(int64_t t_ns) const override;
  bool consistent(const MotionPrediction& prediction, const Pose& T_world_camera, const Matrix6d& covariance,
                  double scene_depth_m) const override;
  void addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) override;
  /// With an inertial prediction: that pose (rotation covariance of the last accepted visual
  /// pose, translation the prediction's), which also carries the motion model on.
  std::optional<BridgedPose> bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                    const Pose& guess) override;
  void reset(const std::optional<Pose>& T_world_camera,
             const std::optional<Eigen::Vector3d>& v_world_camera = std::nullopt,
             double sigma_velocity_m_s = 0) override;
  std::optional<Pose> lastPose() const override { return motion_.lastPose(); }

 private:
  InertialAiding aiding_;
  ConstantVelocityPrior motion_;
  InertialPredictor predictor_;
  Matrix6d last_covariance_ = Matrix6d::Zero();  ///< Of the last accepted visual pose.
};

/// InertialAiding with kEkf: the error-state EKF over a constant-velocity prior (which predicts
/// before the filter has a pose, and without IMU readings). The filter starts at the first frame
/// with a trusted pose (the reset pose's velocity, or unknown: initial_sigma_velocity_m_s), and
/// from then on predicts every frame from the IMU, gyro rotation included.
class EkfPrior final : public MotionPrior {
 public:
  EkfPrior(const InertialAiding& aiding, MotionModel model);
  /// The filter's addImu (readings before the first pose are kept for its start); a reading
  /// after a gap re-anchors the filter and returns its message.
  Status addImu(const ImuSample& sample) override;
  /// The filter's pose and covariance at t_ns (inertial) while it runs and the last accepted
  /// visual pose is at most max_inertial_s old; else the constant-velocity prior's.
  std::optional<MotionPrediction> predict(int64_t t_ns) const override;
  /// Chi-square gate of the filter (EkfOptions::gate_probability) on the pose with the frame's
  /// alignment covariance: the pose is tested as the filter's update would be (lastInnovation()).
  /// A pose the chi-square test refuses is still taken when it lies within the window gate's
  /// floor of the prediction: gate_depth_ratio x scene_depth_m (1 m when unknown) and
  /// gate_rotation_deg; the filter's covariance alone would let a drifted filter refuse correct
  /// poses frame after frame.
  bool consistent(const MotionPrediction& prediction, const Pose& T_world_camera, const Matrix6d& covariance,
                  double scene_depth_m) const override;
  /// Starts the filter at the first pose, else updates it with the pose (gate already passed).
  void addVisualPose(int64_t t_ns, const Pose& T_world_camera, const Matrix6d& covariance) override;
  /// The filter's prediction (state kInertial) up to max_inertial_s after the last accepted pose.
  std::optional<BridgedPose> bridge(int64_t t_ns, const std::optional<MotionPrediction>& prediction,
                                    const Pose& guess) override;
  void reset(const std::optional<Pose>& T_world_camera,
             const std::optional<Eigen::Vector3d>& v_world_camera = std::nullopt,
             double sigma_velocity_m_s = 0) override;
  std::optional<Pose> lastPose() const override { return motion_.lastPose(); }
  /// The filter's state at t_ns after the update with the pose taken at t_ns (its posterior:
  /// the visual pose weighed against the IMU propagation by their covariances).
  std::optional<MotionPrediction> filtered(int64_t t_ns) const override;
  double lastInnovation() const override { return last_innovation_; }
  std::vector<FilterOutput> takeOutputs() override;
  std::optional<Eigen::Matrix3d> attitude(int64_t t_ns) const override;
  /// An unknown start velocity gets 1-sigma unknown_velocity_depths_per_s x depth (m/s) instead
  /// of the fixed EkfOptions::initial_sigma_velocity_m_s, when the depth is known before the
  /// filter starts: cameras move at most a few scene depths per second (a drone 25 m/s over a
  /// 12-58 m deep city, a hand 2.5 m/s in a 1.4-3.4 m deep room).
  void setSceneDepth(double depth_m) override;

  /// The filter (for inspection; not initialized before the first trusted pose).
  const ErrorStateEkf& filter() const { return ekf_; }

 private:
  std::optional<MotionPrediction> filterAt(int64_t t_ns) const;  ///< The filter's state at t_ns, camera frame.
  InertialAiding aiding_;
  ConstantVelocityPrior motion_;
  ErrorStateEkf ekf_;
  std::optional<Eigen::Vector3d> start_velocity_;
  double start_sigma_velocity_m_s_ = 0.1;  ///< 1-sigma of start_velocity_, m/s.
  double scene_depth_m_ = 0;
  bool has_imu_ = false;  ///< The filter took a reading since reset (without, the constant-velocity prior runs).
  bool velocity_unobserved_ = false;  ///< Started at an unknown velocity, no update since.
  int64_t last_update_t_ns_ = 0;
  std::optional<int64_t> updated_t_ns_;  ///< Time of the last pose the filter was updated with (filtered()).
  mutable double last_innovation_ = std::numeric_limits<double>::quiet_NaN();
};

/// Whether a pose the motion prior's gate refused counts against the prior
/// (LocalizerOptions::restart_after_refusals): it verifies with `restart_min_score`, or, on
/// imagery whose true poses never verify that well, it verifies (>= `min_score`) above every one
/// of the last `window` poses the prior took (`taken_scores`, oldest first; fewer than `window`:
/// this part does not apply): a prior that took poorly verified poses drifted with them and now
/// refuses better ones. Scores are verificationScore values (0..1).
bool refusalCountsAgainstPrior(double score, const std::vector<double>& taken_scores, size_t window,
                               double restart_min_score, double min_score);

/// Whether the prediction's attitude (an inertial prediction's: the gyro's) sides with a feature
/// pose against an alignment (LocalizerOptions::motion_search_feature_attitude_sigmas): with phi
/// = logSO3(R_predicted^T R_x) (MotionPrediction::covariance's rotation part, camera frame) and C
/// the prediction's rotation covariance, sqrt(phi^T C^-1 phi) is above `sigmas` for the
/// alignment and at most `sigmas` / 2 for the feature pose. False for a prediction that is not
/// inertial, a rotation covariance that is not finite and positive definite, `sigmas` <= 0 or a
/// pose that is not finite.
bool attitudeFavoursFeaturePose(const MotionPrediction& prediction, const Pose& T_world_feature,
                                const Pose& T_world_aligned, double sigmas);

}  // namespace vkloc
