// vkloc: simulated sequences with ground truth. Camera images are rendered from the intact model
// with appearance changes that real photos have (sun and cast shadows, exposure, white balance,
// gamma, colour differences, vignetting, sensor noise, motion blur, JPEG), while the model
// written into the sequence is damaged the way reconstructions are (holes, simplification,
// quantization). Deterministic in a seed: the same options give bit-identical output files.
//
// Image pipeline per frame (linear RGB in 0..1 between the steps):
//   renders (sub-frames over the exposure time) -> sRGB decode -> lighting with shadows ->
//   average of sub-frames (motion blur) -> exposure * white balance -> vignetting ->
//   sensor noise -> clamp -> tone curve (sRGB encode, then gamma) -> 8-bit RGB -> PNG / JPEG.
// With every effect off the pipeline is the identity on the renderer's RGB output.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vkloc/core/image.hpp"
#include "vkloc/core/lens_camera.hpp"
#include "vkloc/io/sequence.hpp"
#include "vkloc/model/model.hpp"
#include "vkloc/model/model_write.hpp"
#include "vkloc/render/renderer.hpp"
#include "vkloc/sim/trajectory.hpp"

namespace vkloc {

// ------------------------------------------------------------------------------------------
// Appearance

/// Directional sun (or a spot lamp) with cast shadows from a shadow map.
struct LightingOptions {
  bool enabled = false;  ///< Off: surfaces keep their albedo (shade 1).
  /// true: a spot lamp at `spot_position` pointing down (indoor scenes); false: the sun.
  bool spot = false;
  double sun_azimuth_deg = 135.0;                  ///< Sun direction, degrees counter-clockwise from world +x about +z.
  double sun_elevation_deg = 45.0;                 ///< Sun height above the world xy plane, degrees (0..90].
  std::array<double, 3> spot_position{0, 0, 2.8};  ///< Lamp position, world frame, metres.
  double spot_fov_deg = 140.0;                     ///< Full opening angle of the lamp's cone (and shadow map), degrees.
  double ambient = 0.45;                           ///< Light on every surface (sky, bounces), fraction of albedo.
  double direct = 0.8;                             ///< Sun/lamp strength on a surface facing it, fraction of albedo.
  int shadow_map_size = 2048;                      ///< Side of the square shadow map, pixels.
  double shadow_bias_texels = 1.5;                 ///< Constant depth bias in shadow-map texel footprints.
  double shadow_slope_bias = 2.0;                  ///< Extra bias per tan(angle between normal and light), texels.
  bool pcf = true;                                 ///< 3x3 percentage-closer filtering (soft edges); false: 1 tap.
};

/// Photometric changes of the camera images. Each effect is off at its default value.
struct AppearanceOptions {
  LightingOptions lighting;
  double exposure_ev = 0.0;                      ///< Exposure change, stops (gain 2^ev), whole sequence.
  double exposure_drift_ev = 0.0;                ///< Amplitude of a slow sinusoidal exposure change, stops.
  double exposure_drift_period_s = 12.0;         ///< Period of that change, seconds.
  std::array<double, 3> white_balance{1, 1, 1};  ///< Linear gains on R, G, B.
  double white_balance_drift = 0.0;              ///< Amplitude of a slow change of the R and B gains (relative).
  double gamma = 1.0;                            ///< Tone curve exponent after sRGB encoding: out = srgb(x)^(1/gamma).
  double color_jitter_gain = 0.0;                ///< Per texture/material colour gain: 1 +- uniform(this) per channel.
  double color_jitter_offset = 0.0;              ///< Per texture colour offset: +- uniform(this) in 0..1 units.
  double vignetting = 0.0;                       ///< 0..1: factor = 1 - v (1 - cos^4 theta), theta the ray angle.
  double shot_noise = 0.0;                       ///< Shot noise sigma at linear intensity 1 (sigma^2 = s^2 I + r^2).
  double read_noise = 0.0;                       ///< Read noise sigma, linear 0..1 units.
  int motion_blur_subframes = 1;                 ///< Renders averaged per image (1 = no blur).
  double exposure_time_s = 0.0;                  ///< Shutter time centred on the image time, seconds.
  /// Samples per pixel along each axis: every render (each sub-frame, each cube face of a lens) is
  /// made at this many times the resolution and box-averaged in linear light, so a pixel
  /// integrates its footprint as a sensor does (1..4; 1 = one sample at the pixel centre: hard,
  /// aliased edges, and the same rasterizer the tracker renders its references with).
  int supersampling = 1;
  std::optional<std::array<double, 3>> sky;  ///< Linear RGB painted where no surface is seen (none: black).
};

/// sRGB transfer function (IEC 61966-2-1): encoded 0..1 -> linear 0..1, and back.
double srgbToLinear(double encoded);
double linearToSrgb(double linear);

/// RGBA8 render -> linear RGB float image (3 channels).
ImageF32 decodeRender(const ImageU8& rgba);
/// Linear RGB -> 8-bit RGB: clamp to 0..1, sRGB encode, apply `gamma` (out = s^(1/gamma)), round.
ImageU8 encodeImage(const ImageF32& linear_rgb, double gamma);

/// Multiplies channel c by gain * white_balance[c].
void applyExposure(ImageF32& linear_rgb, double gain, const std::array<double, 3>& white_balance);
/// Multiplies by 1 - strength (1 - cos^4 theta), tan^2 theta = ((u-cx)/fx)^2 + ((v-cy)/fy)^2.
void applyVignetting(ImageF32& linear_rgb, const PinholeCamera& camera, double strength);
/// Adds N(0, shot^2 max(I, 0) + read^2) per value. Deterministic in `seed`.
void addSensorNoise(ImageF32& linear_rgb, double shot, double read, uint64_t seed);

/// Depth map seen from the light and the camera that took it, for shadow tests.
struct ShadowMap {
  PinholeCamera camera;                       ///< Light camera (long focal length for the sun).
  Pose T_world_light = Pose::Identity();      ///< Light camera pose.
  ImageF32 depth;                             ///< Light-camera z of the nearest surface, metres; 0 = none.
  Eigen::Vector3d direction_to_sun{0, 0, 1};  ///< Unit, world frame (sun only).
  bool spot = false;
};

/// Unit world vector pointing at the sun for azimuth/elevation in degrees.
Eigen::Vector3d sunDirection(double azimuth_deg, double elevation_deg);

/// Renders the shadow map of `lighting` for a scene inside `scene_bounds` with `renderer`
/// (which renders the model that casts the shadows). kInvalidArgument for empty bounds or an
/// elevation outside (0, 90].
Result<ShadowMap> renderShadowMap(Renderer& renderer, const Aabb& scene_bounds, const LightingOptions& lighting);

/// Fraction (0..1) of the 3x3 (or 1) shadow-map taps around the projection of `p_world` that
/// see it lit; `normal_world` (unit) sets the slope-scaled bias. Points outside the map are lit
/// (sun) or unlit (spot: outside the lamp's cone).
double shadowLitFraction(const ShadowMap& map, const LightingOptions& lighting, const Eigen::Vector3d& p_world,
                         const Eigen::Vector3d& normal_world);

/// Shades linear albedo in place: albedo * (ambient + direct * max(0, n.l) * lit), using the
/// render's metric depth (back-projected to world) and camera-frame normals. Background pixels
/// (depth 0) are left as they are.
void applyLighting(ImageF32& linear_rgb, const RenderOutput& render, const PinholeCamera& camera,
                   const Pose& T_world_camera, const ShadowMap& map, const LightingOptions& lighting);

/// Copy of `model` with per-texture and per-material colour changes (gain 1 +- gain_range and
/// offset +- offset_range per channel; textures in their stored encoding). Deterministic in seed.
Model jitterModelColors(const Model& model, double gain_range, double offset_range, uint64_t seed);

/// Appearance options of the "hard" scenarios: every effect on, values drawn from `seed`
/// (sun azimuth, elevation, exposure, white balance, gamma). `indoor` uses a spot lamp.
AppearanceOptions hardAppearance(uint64_t seed, bool indoor, const Aabb& scene_bounds);

// ------------------------------------------------------------------------------------------
// Model damage

/// How the localization model differs from the model the images come from.
struct DamageOptions {
  double hole_fraction = 0.0;    ///< Fraction of surface area to remove in patches, 0..0.9.
  double hole_radius_m = 0.0;    ///< Mean patch radius, metres; 0: 2 % of the bounds' diagonal.
  double simplify_ratio = 1.0;   ///< Target triangle count / count after holes, (0, 1]; 1 = off.
  bool draco = false;            ///< Write the model with Draco compression (quantization).
  int draco_position_bits = 14;  ///< Draco position quantization, bits.
  int draco_uv_bits = 12;        ///< Draco texture-coordinate quantization, bits.
};

/// What damageModel did.
struct DamageReport {
  size_t triangles_before = 0;
  size_t triangles_after = 0;
  double removed_area_fraction = 0.0;  ///< Area removed by holes / total area.
  size_t hole_patches = 0;
};

/// Removes about `fraction` of the surface area in spatially clustered patches: seed triangles
/// are drawn area-weighted, each patch takes the nearest remaining triangles (by centroid
/// distance to the seed) up to a random radius around `radius_m`; the last patch stops at the
/// requested area (a triangle is taken only when that brings the total closer). Returns the
/// removed triangle indices (into the input's triangle order) via `removed` when given.
/// kInvalidArgument for a fraction outside [0, 0.9] or an invalid model.
Result<Model> punchHoles(const Model& model, double fraction, double radius_m, uint64_t seed,
                         DamageReport* report = nullptr, std::vector<uint32_t>* removed = nullptr);

/// Simplifies each material's triangles with meshoptimizer to about `ratio` of the triangles
/// (meshopt_simplify, falling back to meshopt_simplifySloppy when that keeps > 110 % of the
/// target). Rebuilds blocks with `max_block_triangles`. kInvalidArgument for ratio outside (0, 1].
Result<Model> simplifyModel(const Model& model, double ratio, uint32_t max_block_triangles = 32768);

/// Holes, then simplification. (Quantization happens when the model is written.)
Result<Model> damageModel(const Model& model, const DamageOptions& options, uint64_t seed,
                          DamageReport* report = nullptr);

// ------------------------------------------------------------------------------------------
// Sequences

/// Everything a simulated sequence is made from.
struct SimulationOptions {
  std::string name = "simulated";  ///< Sequence name in sequence.yaml.
  TrajectoryKind trajectory = TrajectoryKind::kDroneFlight;
  double duration_s = 15.0;  ///< Trajectory length, seconds.
  double rate_hz = 20.0;     ///< Camera frame rate, Hz.
  size_t max_frames = 0;     ///< Stop after this many images; 0 = all.
  SequenceCamera camera;     ///< Intrinsics and T_body_camera.
  AppearanceOptions appearance;
  DamageOptions damage;
  std::optional<ImuNoise> imu_noise = ImuNoise{};  ///< nullopt: exact IMU readings.
  bool write_imu = true;
  bool write_priors = true;
  PriorOptions priors;
  bool jpeg = false;      ///< Write images as JPEG (OpenCV) instead of PNG.
  int jpeg_quality = 90;  ///< JPEG quality 1..100.
  double near_m = 0.05;   ///< Render near plane, metres.
  double far_m = 5000.0;  ///< Render far plane, metres.
  /// Threads of the CPU rasterizer per frame (RenderSettings::threads; 0 = every core this
  /// process may use, availableCores; at most 64). The files do not depend on it.
  int render_threads = 0;
  uint64_t seed = 1;  ///< Every random choice derives from this.
};

/// Built-in scenarios: scene "city" (demo city, drone trajectory) or "room" (demo room,
/// handheld trajectory), difficulty "easy" (no appearance change, intact model) or "hard"
/// (all appearance changes, 20 % holes, simplification to 60 %, Draco 14-bit positions).
/// 640x480, fx = fy = 500, 20 Hz, 15 s. kNotFound for an unknown scene or difficulty.
Result<SimulationOptions> scenarioOptions(const std::string& scene, const std::string& difficulty, uint64_t seed,
                                          const Aabb& scene_bounds);

/// The model of a built-in scenario: the demo city split to about 200k triangles or the demo
/// room to about 50k (fine enough for hole patches and simplification to act like on a
/// reconstruction; renders look the same as the natural-size demos). kNotFound otherwise.
Result<Model> scenarioModel(const std::string& scene);

/// Lenses of the built-in scenarios, mounted by defaultBodyCamera(kind): "pinhole" (640x480,
/// fx = fy = 500), "radtan" (the same with a EuRoC-like barrel distortion: k1 -0.28, k2 0.074,
/// p1 2e-4, p2 1.8e-5) or "fisheye" (800x800 equidistant, 210 deg field of view, fx = fy = 200).
/// kNotFound for another name.
Result<SequenceCamera> scenarioCamera(const std::string& lens, TrajectoryKind kind);

/// Default camera mounting for a trajectory kind: the drone's camera is pitched 45 degrees down
/// from the body's forward axis (body x forward, y left, z up), the handheld ones look forward.
Pose defaultBodyCamera(TrajectoryKind kind);

/// The trajectory simulateSequence uses for `options` in `model` (seed derived from
/// options.seed): inside the model's bounds, drones 10 m above any geometry within 5 m.
Result<SplineTrajectory> simulationTrajectory(const SimulationOptions& options, const Model& model);
/// The same trajectory in an empty box `scene_bounds` (nothing to fly over but its floor).
Result<SplineTrajectory> simulationTrajectory(const SimulationOptions& options, const Aabb& scene_bounds);

/// Progress callback: images written so far and the total.
using SimulationProgress = std::function<void(size_t done, size_t total)>;

/// What simulateSequence produced.
struct SimulationReport {
  size_t frames = 0;
  double seconds = 0.0;  ///< Wall time of the image loop.
  std::string directory;
  std::string model_file;  ///< Damaged model, inside `directory`.
  DamageReport damage;
};

/// Writes a sequence folder: images/NNNNNN.png|jpg as they are rendered, the damaged model
/// (model.glb, Draco-compressed when damage.draco), then sequence.yaml, camera.yaml, images.txt,
/// groundtruth.txt (T_world_camera = T_world_body T_body_camera at each image time), imu.csv
/// and prior.csv. On a failure after some images, the text files are written for the images
/// done so the folder stays loadable, and the error says how many were written.
Result<SimulationReport> simulateSequence(const Model& model, const SimulationOptions& options,
                                          const RendererFactory& renderers, const std::string& directory,
                                          const SimulationProgress& progress = {});

/// Pinhole renders that together see a lens's whole field (one render for a lens of up to 60 deg
/// from the axis, else the faces of a cube map), and where each lens pixel samples them.
struct LensRig {
  LensCamera lens;
  std::vector<PinholeCamera> faces;    ///< Intrinsics of each render.
  std::vector<Pose> T_camera_face;     ///< Rotation of each render from the lens (same centre).
  std::vector<int16_t> face_of_pixel;  ///< Per lens pixel: the render it samples, -1: outside the lens's field.
  std::vector<float> uv;               ///< Per lens pixel: position in that render, pixels.
  std::vector<float> cos_angle;        ///< Per lens pixel: cosine of its ray's angle from the axis.
};
/// The rig of `lens`: renders at 1.25 x the lens's focal length, only those some pixel needs.
/// kInvalidArgument for an invalid lens or a single render over 8192 px wide.
Result<LensRig> makeLensRig(const LensCamera& lens);
/// The lens image (3-channel linear RGB, the lens's size) from the rig's renders (linear RGB, one
/// per face, in rig order), bilinear; pixels outside the field are 0.
ImageF32 resampleLens(const LensRig& rig, const std::vector<ImageF32>& faces);

/// Renders one simulated camera image (linear pipeline of the file comment) at time t_ns
/// (exposure centred on it) from `renderer` (rendering the jittered model). `map` may be null
/// when lighting is off. Exposure at time t uses exposure_ev and the drift. With a `rig`, the
/// image is the rig's lens's (`camera` is then unused): each render of the pipeline becomes the
/// rig's renders resampled through the lens, and vignetting follows the ray angle.
Result<ImageU8> simulateFrame(Renderer& renderer, const SplineTrajectory& trajectory, const Pose& T_body_camera,
                              const PinholeCamera& camera, int64_t t_ns, const AppearanceOptions& appearance,
                              const ShadowMap* map, const RenderSettings& settings, uint64_t noise_seed,
                              const LensRig* rig = nullptr);

}  // namespace vkloc
