// The keyframe database (see keyframe_database.hpp): descriptors, query, file format, build.
#include "vkloc/localize/keyframe_database.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <unordered_set>

#include "vkloc/core/atomic_file.hpp"
#include "vkloc/core/clock.hpp"
#include "vkloc/core/numeric.hpp"
#include "vkloc/core/text.hpp"

namespace vkloc {
namespace {

constexpr char kMagic[8] = {'V', 'K', 'L', 'O', 'C', 'K', 'D', 'B'};
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 4 + 4 + 4 * 8 + 8;

uint64_t fnv1a(const void* data, size_t size, uint64_t hash = 14695981039346656037ull) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <typename T>
T get(const std::string& in, size_t& at) {
  T value;
  std::memcpy(&value, in.data() + at, sizeof(T));
  at += sizeof(T);
  return value;
}

}  // namespace

Result<ImageU8> descriptorThumbnail(const ImageU8& gray) {
  if (gray.channels != 1 || gray.width < kThumbnailWidth || gray.height < kThumbnailHeight ||
      gray.data.size() != static_cast<size_t>(gray.width) * gray.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("descriptor: need an 8-bit gray image of at least {}x{}, got {}x{} with {} channel(s)",
                                 kThumbnailWidth, kThumbnailHeight, gray.width, gray.height, gray.channels));
  }
  const cv::Mat in(gray.height, gray.width, CV_8UC1, const_cast<uint8_t*>(gray.data.data()));
  ImageU8 out(kThumbnailWidth, kThumbnailHeight, 1);
  cv::Mat dst(kThumbnailHeight, kThumbnailWidth, CV_8UC1, out.data.data());
  cv::resize(in, dst, dst.size(), 0, 0, cv::INTER_AREA);
  return out;
}

Result<GlobalDescriptor> globalDescriptor(const ImageU8& gray) {
  Result<ImageU8> thumbnail = descriptorThumbnail(gray);  // checks the input
  if (!thumbnail.ok()) return thumbnail.error();
  // Gradient magnitude rather than gray levels: a model's textures and a camera's image differ
  // in light, shadows and tone, their edges much less (measured: README, "Relocalization").
  // Computed at twice the thumbnail's size, smoothed (sigma 2 px there) against sensor noise
  // and aliasing, then area-averaged to 80x64 and scaled so that its 99th percentile is 255.
  const cv::Mat in(gray.height, gray.width, CV_8UC1, const_cast<uint8_t*>(gray.data.data()));
  cv::Mat half;
  cv::resize(in, half, cv::Size(2 * kThumbnailWidth, 2 * kThumbnailHeight), 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(half, half, cv::Size(0, 0), 2.0);
  cv::Mat gx, gy, magnitude;
  cv::Sobel(half, gx, CV_32F, 1, 0);
  cv::Sobel(half, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, magnitude);
  cv::Mat small;
  cv::resize(magnitude, small, cv::Size(kThumbnailWidth, kThumbnailHeight), 0, 0, cv::INTER_AREA);
  std::vector<float> values(small.begin<float>(), small.end<float>());
  auto p99 = values.begin() + static_cast<std::ptrdiff_t>(values.size() * 99 / 100);
  std::nth_element(values.begin(), p99, values.end());
  cv::Mat image;
  small.convertTo(image, CV_8U, 255.0 / std::max(static_cast<double>(*p99), 1e-6));
  // One keypoint at the centre; a 63-pixel patch covers the 64 rows (seed 001 sec. II-D). The
  // border is 31 so that the keypoint is kept; ORB smooths the patch itself (7x7 Gaussian).
  constexpr int kPatch = 63;
  cv::Ptr<cv::ORB> orb = cv::ORB::create(1, 1.2f, 1, kPatch / 2, 0, 2, cv::ORB::HARRIS_SCORE, kPatch);
  std::vector<cv::KeyPoint> keypoints{
      cv::KeyPoint(cv::Point2f(kThumbnailWidth / 2.0f, kThumbnailHeight / 2.0f), kPatch, 0.0f)};
  cv::Mat descriptors;
  orb->compute(image, keypoints, descriptors);
  if (keypoints.size() != 1 || descriptors.rows != 1 || descriptors.cols != 32 || descriptors.type() != CV_8U) {
    return makeError(ErrorCode::kInvalidArgument, "descriptor: ORB gave no descriptor for the thumbnail");
  }
  GlobalDescriptor d;
  std::memcpy(d.data(), descriptors.ptr<uint8_t>(0), sizeof(d));
  return d;
}

double thumbnailContrast(const ImageU8& thumbnail) {
  if (thumbnail.data.empty()) return 0.0;
  double sum = 0, sum2 = 0;
  for (uint8_t v : thumbnail.data) {
    sum += v;
    sum2 += static_cast<double>(v) * v;
  }
  const double n = static_cast<double>(thumbnail.data.size());
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

int hammingDistance(const GlobalDescriptor& a, const GlobalDescriptor& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

uint64_t modelFingerprint(const Model& model) {
  uint64_t hash = fnv1a(model.positions.data(), model.positions.size() * sizeof(float));
  return fnv1a(model.indices.data(), model.indices.size() * sizeof(uint32_t), hash);
}

void KeyframeDatabase::add(const DatabaseKeyframe& keyframe) {
  keyframes_.push_back(keyframe);
  const Eigen::Vector3d& t = keyframe.T_world_camera.translation();
  positions_.insert(positions_.end(), {t.x(), t.y(), t.z()});
}

std::vector<KeyframeCandidate> KeyframeDatabase::query(const GlobalDescriptor& descriptor, size_t k,
                                                       const std::optional<SearchRegion>& region) const {
  std::vector<KeyframeCandidate> out;
  if (k == 0) return out;
  out.reserve(std::min(keyframes_.size(), 4 * k + 16));
  const bool everywhere = !region || !std::isfinite(region->radius_m);
  const double cx = region ? region->center_world.x() : 0.0;
  const double cy = region ? region->center_world.y() : 0.0;
  const double cz = region ? region->center_world.z() : 0.0;
  const double r2 = region && !everywhere ? region->radius_m * region->radius_m : 0.0;
  // Keeps the k best seen so far in a max-heap on (distance, index): one pass, no sort of all.
  auto worse = [](const KeyframeCandidate& a, const KeyframeCandidate& b) {
    return a.distance != b.distance ? a.distance < b.distance : a.index < b.index;
  };
  for (size_t i = 0; i < keyframes_.size(); ++i) {
    if (!everywhere) {
      const double dx = positions_[3 * i] - cx, dy = positions_[3 * i + 1] - cy, dz = positions_[3 * i + 2] - cz;
      if (dx * dx + dy * dy + dz * dz > r2) continue;
    }
    const KeyframeCandidate c{i, hammingDistance(descriptor, keyframes_[i].descriptor)};
    if (out.size() < k) {
      out.push_back(c);
      std::push_heap(out.begin(), out.end(), worse);
    } else if (worse(c, out.front())) {
      std::pop_heap(out.begin(), out.end(), worse);
      out.back() = c;
      std::push_heap(out.begin(), out.end(), worse);
    }
  }
  std::sort_heap(out.begin(), out.end(), worse);
  return out;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> KeyframeDatabase::positionBounds() const {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (size_t i = 0; i + 2 < positions_.size(); i += 3) {
    const Eigen::Vector3d p(positions_[i], positions_[i + 1], positions_[i + 2]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

double KeyframeDatabase::positionReach() const {
  // Distinct positions (a position's views share it exactly).
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(keyframes_.size());
  for (size_t i = 0; i < keyframes_.size(); ++i) {
    positions.emplace_back(positions_[3 * i], positions_[3 * i + 1], positions_[3 * i + 2]);
  }
  std::sort(positions.begin(), positions.end(), [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  positions.erase(std::unique(positions.begin(), positions.end()), positions.end());
  if (positions.size() < 2) return 0.0;
  const size_t samples = std::min<size_t>(256, positions.size());
  std::vector<double> nearest;
  nearest.reserve(samples);
  for (size_t s = 0; s < samples; ++s) {
    const Eigen::Vector3d& p = positions[s * positions.size() / samples];
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector3d& q : positions) {
      const double d = (q - p).squaredNorm();
      if (d > 0 && d < best) best = d;
    }
    nearest.push_back(std::sqrt(best));
  }
  std::nth_element(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(nearest.size() / 2), nearest.end());
  return 0.5 * std::sqrt(3.0) * nearest[nearest.size() / 2];
}

Status KeyframeDatabase::save(const std::string& path) const {
  std::string bytes;
  bytes.reserve(kHeaderBytes + keyframes_.size() * kRecordBytes + 8);
  bytes.append(kMagic, sizeof(kMagic));
  put<uint32_t>(bytes, kVersion);
  put<uint32_t>(bytes, 0);
  put<uint64_t>(bytes, fingerprint_);
  put<uint32_t>(bytes, static_cast<uint32_t>(camera_.width));
  put<uint32_t>(bytes, static_cast<uint32_t>(camera_.height));
  for (double v : {camera_.fx, camera_.fy, camera_.cx, camera_.cy}) put<double>(bytes, v);
  put<uint64_t>(bytes, keyframes_.size());
  for (const DatabaseKeyframe& k : keyframes_) {
    const Eigen::Vector3d& t = k.T_world_camera.translation();
    for (int a = 0; a < 3; ++a) put<double>(bytes, t[a]);
    const Eigen::Quaterniond q(k.T_world_camera.linear());
    for (double v : {q.x(), q.y(), q.z(), q.w()}) put<float>(bytes, static_cast<float>(v));
    put<float>(bytes, k.scene_depth_m);
    for (uint64_t word : k.descriptor) put<uint64_t>(bytes, word);
  }
  put<uint64_t>(bytes, fnv1a(bytes.data(), bytes.size()));
  return writeFileAtomically(path, bytes);
}

Result<KeyframeDatabase> KeyframeDatabase::load(const std::string& path, std::optional<uint64_t> expected_fingerprint) {
  Result<std::string> read = text::readFile(path, "keyframe database");
  if (!read.ok()) return read.error();
  const std::string& bytes = *read;
  auto malformed = [&](const std::string& what) {
    return makeError(ErrorCode::kMalformedInput, fmt::format("{}: {}", path, what));
  };
  if (bytes.size() < kHeaderBytes + 8 || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return malformed("not a vkloc keyframe database (no VKLOCKDB header)");
  }
  size_t at = sizeof(kMagic);
  const uint32_t version = get<uint32_t>(bytes, at);
  if (version != kVersion) {
    return makeError(
        ErrorCode::kUnsupported,
        fmt::format("{}: keyframe database version {}; this build reads version {}", path, version, kVersion));
  }
  get<uint32_t>(bytes, at);  // flags
  const uint64_t fingerprint = get<uint64_t>(bytes, at);
  PinholeCamera camera;
  camera.width = static_cast<int>(get<uint32_t>(bytes, at));
  camera.height = static_cast<int>(get<uint32_t>(bytes, at));
  camera.fx = get<double>(bytes, at);
  camera.fy = get<double>(bytes, at);
  camera.cx = get<double>(bytes, at);
  camera.cy = get<double>(bytes, at);
  const uint64_t count = get<uint64_t>(bytes, at);
  const uint64_t records = (bytes.size() - kHeaderBytes - 8) / kRecordBytes;
  if (count > records || bytes.size() != kHeaderBytes + count * kRecordBytes + 8) {
    return malformed(fmt::format("truncated or damaged: {} bytes for {} keyframes (expected {})", bytes.size(), count,
                                 kHeaderBytes + std::min(count, records + 1) * kRecordBytes + 8));
  }
  {
    size_t end = bytes.size() - 8;
    const uint64_t stored = get<uint64_t>(bytes, end);
    if (stored != fnv1a(bytes.data(), bytes.size() - 8)) return malformed("damaged (checksum mismatch)");
  }
  if (Status s = validateCamera(camera); !s.ok()) return malformed(s.error().message);
  if (expected_fingerprint && *expected_fingerprint != fingerprint) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("{}: keyframe database built for another model (fingerprint {:016x}, this model's "
                                 "{:016x}); build it again with vkloc keyframes build",
                                 path, fingerprint, *expected_fingerprint));
  }
  KeyframeDatabase db(fingerprint, camera);
  db.keyframes_.reserve(count);
  db.positions_.reserve(3 * count);
  for (uint64_t i = 0; i < count; ++i) {
    DatabaseKeyframe k;
    Eigen::Vector3d t;
    for (int a = 0; a < 3; ++a) t[a] = get<double>(bytes, at);
    float q[4];
    for (float& v : q) v = get<float>(bytes, at);
    k.scene_depth_m = get<float>(bytes, at);
    for (uint64_t& word : k.descriptor) word = get<uint64_t>(bytes, at);
    Eigen::Quaterniond quat(q[3], q[0], q[1], q[2]);
    const double norm = quat.norm();
    if (!t.allFinite() || !std::isfinite(norm) || std::abs(norm - 1.0) > 1e-3 || !std::isfinite(k.scene_depth_m)) {
      return malformed(fmt::format("keyframe {}: pose is not a finite rigid transform", i));
    }
    k.T_world_camera = Pose::Identity();
    k.T_world_camera.linear() = quat.normalized().toRotationMatrix();
    k.T_world_camera.translation() = t;
    db.add(k);
  }
  return db;
}

Pose placementPose(const Eigen::Vector3d& position, const Eigen::Vector3d& up_world, double heading_deg,
                   double tilt_deg) {
  const Eigen::Vector3d up = up_world.normalized();
  // First horizontal axis: the world axis least aligned with up, made horizontal.
  Eigen::Index axis = 0;
  up.cwiseAbs().minCoeff(&axis);
  const Eigen::Vector3d e1 = (Eigen::Vector3d::Unit(axis) - up * up[axis]).normalized();
  const Eigen::Vector3d e2 = up.cross(e1);
  const double h = heading_deg * M_PI / 180.0, t = tilt_deg * M_PI / 180.0;
  const Eigen::Vector3d horizontal = std::cos(h) * e1 + std::sin(h) * e2;
  const Eigen::Vector3d z = std::cos(t) * horizontal - std::sin(t) * up;  // optical axis
  // No roll: image up as close to up as can be; straight up or down, image up is the heading.
  const bool vertical = std::abs(std::cos(t)) < 1e-9;
  Result<Pose> T = lookAt(position, position + z, vertical ? horizontal * (t > 0 ? 1.0 : -1.0) : up);
  return T.ok() ? *T : Pose::Identity();
}

namespace {

/// The placement's grid: n points per axis, the first at start, centred in the box.
struct PlacementGrid {
  std::array<int64_t, 3> n{};
  std::array<double, 3> start{};
  double spacing = 1;
  Eigen::Vector3d at(int64_t i, int64_t j, int64_t k) const {
    return {start[0] + static_cast<double>(i) * spacing, start[1] + static_cast<double>(j) * spacing,
            start[2] + static_cast<double>(k) * spacing};
  }
};

PlacementGrid placementGrid(const KeyframePlacement& p) {
  PlacementGrid g;
  g.spacing = p.spacing_m;
  for (int a = 0; a < 3; ++a) {
    const double extent = static_cast<double>(p.volume.max[a]) - static_cast<double>(p.volume.min[a]);
    g.n[a] = static_cast<int64_t>(std::floor(extent / p.spacing_m)) + 1;
    g.start[a] = p.volume.min[a] + 0.5 * (extent - static_cast<double>(g.n[a] - 1) * p.spacing_m);
  }
  return g;
}

/// Distance of x from the segment a-b, metres.
double segmentDistance(const Eigen::Vector3d& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (x - (a + t * ab)).norm();
}

/// The grid indices (x slowest) of the positions within the corridor, sorted; stops with an
/// error once they would exceed max_views. The corridor's points nearer than a quarter spacing to
/// the last one kept are skipped (each segment's cells are visited once; a dense ground truth
/// would visit them hundreds of times).
Result<std::vector<int64_t>> corridorCells(const KeyframePlacement& p) {
  const PlacementGrid g = placementGrid(p);
  std::vector<Eigen::Vector3d> path;
  for (const Eigen::Vector3d& c : p.corridor) {
    if (path.empty() || (c - path.back()).norm() >= 0.25 * p.spacing_m) path.push_back(c);
  }
  if (p.corridor.size() > 1 && (p.corridor.back() - path.back()).norm() > 0) path.push_back(p.corridor.back());
  const double r = p.corridor_radius_m;
  const size_t per_position = static_cast<size_t>(p.headings) * p.tilts_deg.size();
  const size_t max_positions = p.max_views / std::max<size_t>(1, per_position);
  std::unordered_set<int64_t> cells;
  for (size_t s = 0; s < path.size(); ++s) {
    const Eigen::Vector3d& a = path[s];
    const Eigen::Vector3d& b = path[std::min(s + 1, path.size() - 1)];
    std::array<int64_t, 3> lo{}, hi{};
    for (int d = 0; d < 3; ++d) {
      lo[d] =
          std::max<int64_t>(0, static_cast<int64_t>(std::ceil((std::min(a[d], b[d]) - r - g.start[d]) / g.spacing)));
      hi[d] = std::min<int64_t>(g.n[d] - 1,
                                static_cast<int64_t>(std::floor((std::max(a[d], b[d]) + r - g.start[d]) / g.spacing)));
    }
    for (int64_t i = lo[0]; i <= hi[0]; ++i) {
      for (int64_t j = lo[1]; j <= hi[1]; ++j) {
        for (int64_t k = lo[2]; k <= hi[2]; ++k) {
          if (segmentDistance(g.at(i, j, k), a, b) > r) continue;
          cells.insert((i * g.n[1] + j) * g.n[2] + k);
          if (cells.size() > max_positions) {
            return makeError(ErrorCode::kInvalidArgument,
                             fmt::format("keyframe placement: the corridor holds more than {} views, the limit (a "
                                         "coarser spacing, a narrower corridor, fewer headings or tilts)",
                                         p.max_views));
          }
        }
      }
    }
  }
  std::vector<int64_t> sorted(cells.begin(), cells.end());
  std::sort(sorted.begin(), sorted.end());
  return sorted;
}

}  // namespace

Status validateKeyframePlacement(const KeyframePlacement& p) {
  auto bad = [](const std::string& what) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("keyframe placement: {}", what));
  };
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(p.volume.min[a]) || !std::isfinite(p.volume.max[a]) || p.volume.min[a] > p.volume.max[a]) {
      return bad("the volume must be a finite box with min <= max");
    }
  }
  if (!finiteIn(p.spacing_m, 1e-3, 1e6)) return bad("spacing must be in 0.001..1e6 m");
  if (!p.up_world.allFinite() || p.up_world.norm() < 1e-9) return bad("up must be a finite non-zero vector");
  if (p.headings < 1 || p.headings > 360) return bad("headings must be in 1..360");
  if (p.tilts_deg.empty()) return bad("at least one tilt is needed");
  for (double t : p.tilts_deg) {
    if (!finiteIn(t, -90.0, 90.0)) return bad("tilts must be in -90..90 degrees");
  }
  if (!finiteIn(p.min_clearance_m, 0.0, 1e6) || !finiteIn(p.max_back_face_fraction, 0.0, 1.0) ||
      !finiteIn(p.min_model_fraction, 0.0, 1.0) || !finiteIn(p.min_contrast, 0.0, 255.0)) {
    return bad("min_clearance_m >= 0, fractions in 0..1 and min_contrast in 0..255 needed");
  }
  if (!p.corridor.empty()) {
    if (!finiteIn(p.corridor_radius_m, 1e-6, 1e6)) return bad("the corridor's radius must be in 1e-6..1e6 m");
    for (const Eigen::Vector3d& c : p.corridor) {
      if (!c.allFinite()) return bad("the corridor's points must be finite");
    }
    // The view count: the corridor's positions, counted up to the limit.
    Result<std::vector<int64_t>> cells = corridorCells(p);
    if (!cells.ok()) return cells.error();
    return Status::success();
  }
  const double views = placementBoxViews(p);
  if (views > static_cast<double>(p.max_views)) {
    return bad(fmt::format("{:.3g} views exceed the limit of {} (a coarser spacing, fewer headings or tilts)", views,
                           p.max_views));
  }
  return Status::success();
}

double placementBoxViews(const KeyframePlacement& p) {
  double views = static_cast<double>(p.headings) * static_cast<double>(p.tilts_deg.size());
  for (int a = 0; a < 3; ++a) views *= std::floor((p.volume.max[a] - p.volume.min[a]) / p.spacing_m) + 1;
  return views;
}

Result<std::vector<Eigen::Vector3d>> placementPositions(const KeyframePlacement& placement) {
  VKLOC_TRY_STATUS(validateKeyframePlacement(placement));
  const PlacementGrid g = placementGrid(placement);
  std::vector<Eigen::Vector3d> positions;
  if (!placement.corridor.empty()) {
    Result<std::vector<int64_t>> cells = corridorCells(placement);
    if (!cells.ok()) return cells.error();
    positions.reserve(cells->size());
    for (int64_t c : *cells) positions.push_back(g.at(c / (g.n[1] * g.n[2]), (c / g.n[2]) % g.n[1], c % g.n[2]));
    return positions;
  }
  positions.reserve(static_cast<size_t>(g.n[0] * g.n[1] * g.n[2]));
  for (int64_t i = 0; i < g.n[0]; ++i) {
    for (int64_t j = 0; j < g.n[1]; ++j) {
      for (int64_t k = 0; k < g.n[2]; ++k) positions.push_back(g.at(i, j, k));
    }
  }
  return positions;
}

PinholeCamera keyframeViewCamera(const PinholeCamera& camera) {
  const int width =
      std::max(2 * kThumbnailWidth,
               static_cast<int>(std::ceil(2.0 * kThumbnailHeight * camera.width / std::max(1, camera.height))));
  return scaledCamera(camera, width);
}

float surfaceDepths(const ImageF32& depth, std::vector<float>& depths) {
  depths.clear();
  float nearest = std::numeric_limits<float>::infinity();
  for (float d : depth.data) {
    if (d > 0.0f) {
      depths.push_back(d);
      nearest = std::min(nearest, d);
    }
  }
  return nearest;
}

Result<double> typicalSceneDepth(Renderer& renderer, const PinholeCamera& camera, const std::vector<Pose>& views,
                                 double min_model_fraction, double min_clearance_m) {
  VKLOC_TRY_STATUS(validateCamera(camera));
  if (!(min_model_fraction >= 0.0 && min_model_fraction <= 1.0)) {
    return makeError(ErrorCode::kInvalidArgument, "typical scene depth: min_model_fraction must be in 0..1");
  }
  if (!(min_clearance_m >= 0.0) || !std::isfinite(min_clearance_m)) {
    return makeError(ErrorCode::kInvalidArgument, "typical scene depth: min_clearance_m must be finite and >= 0");
  }
  const PinholeCamera small = keyframeViewCamera(camera);
  RenderSettings look;
  look.outputs = kRenderDepth;
  look.cull_back_faces = false;
  const size_t pixels = static_cast<size_t>(small.width) * small.height;
  const auto median = [](auto& values) {  // of a non-empty vector, reordered
    auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), mid, values.end());
    return static_cast<double>(*mid);
  };
  std::vector<double> medians;
  std::vector<float> depths;
  for (const Pose& T_world_camera : views) {
    Result<RenderOutput> out = renderer.render(small, T_world_camera, look);
    if (!out.ok()) return out.error();
    const float nearest = surfaceDepths(out->depth, depths);
    if (depths.empty() || static_cast<double>(depths.size()) < min_model_fraction * static_cast<double>(pixels) ||
        nearest < min_clearance_m) {
      continue;
    }
    medians.push_back(median(depths));
  }
  return medians.empty() ? 0.0 : median(medians);
}

Result<KeyframeDatabase> buildKeyframeDatabase(const Model& model, const std::vector<Renderer*>& renderers,
                                               const PinholeCamera& camera, const KeyframePlacement& placement,
                                               const RenderSettings& render,
                                               const std::function<void(size_t, size_t)>& progress,
                                               KeyframeBuildStats* stats) {
  const auto t0 = SteadyClock::now();
  VKLOC_TRY_STATUS(validateCamera(camera));
  VKLOC_TRY_STATUS(validateKeyframePlacement(placement));
  VKLOC_TRY_STATUS(validateRenderSettings(render));
  if (renderers.empty() || std::find(renderers.begin(), renderers.end(), nullptr) != renderers.end()) {
    return makeError(ErrorCode::kInvalidArgument, "keyframe database: need at least one renderer (and no null one)");
  }
  const PinholeCamera small = keyframeViewCamera(camera);
  RenderSettings look = render;
  // One thread per renderer already: a CPU renderer's bands would only nest threads.
  if (renderers.size() > 1) look.threads = 1;
  look.outputs = kRenderColor | kRenderDepth;
  // The back-face mask comes with the normals (RenderOutput::back_faces).
  if (placement.max_back_face_fraction < 1.0) look.outputs |= kRenderNormals;
  look.cull_back_faces = false;

  Result<std::vector<Eigen::Vector3d>> positions = placementPositions(placement);
  if (!positions.ok()) return positions.error();
  std::vector<Pose> poses;
  poses.reserve(positions->size() * placement.tilts_deg.size() * static_cast<size_t>(placement.headings));
  for (const Eigen::Vector3d& position : *positions) {
    for (double tilt : placement.tilts_deg) {
      for (int h = 0; h < placement.headings; ++h) {
        poses.push_back(placementPose(position, placement.up_world, 360.0 * h / placement.headings, tilt));
      }
    }
  }
  enum class Verdict : uint8_t { kKept, kTooClose, kInside, kEmpty };
  struct View {
    Verdict verdict = Verdict::kEmpty;
    DatabaseKeyframe keyframe;
  };
  std::vector<View> views(poses.size());
  const size_t pixels = static_cast<size_t>(small.width) * small.height;
  // One thread per renderer takes the next view; results land at the view's index, so the
  // database is the same whatever the number of threads.
  std::atomic<size_t> next{0};
  std::atomic<size_t> done{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;
  std::optional<Error> error;
  auto work = [&](Renderer& renderer, bool reports) {
    std::vector<float> depths;
    depths.reserve(pixels);
    for (size_t v = next++; v < poses.size() && !failed; v = next++) {
      auto fail = [&](const Error& e) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = e;
        failed = true;
      };
      const size_t finished = ++done;
      if (reports && progress && (finished % 256 == 0 || finished == poses.size())) progress(finished, poses.size());
      View& view = views[v];
      Result<RenderOutput> out = renderer.render(small, poses[v], look);
      if (!out.ok()) return fail(out.error());
      const float nearest = surfaceDepths(out->depth, depths);
      if (nearest < placement.min_clearance_m) {
        view.verdict = Verdict::kTooClose;
        continue;
      }
      if (static_cast<double>(depths.size()) < placement.min_model_fraction * static_cast<double>(pixels)) continue;
      if (placement.max_back_face_fraction < 1.0) {
        // Pixels whose nearest surface is seen from behind.
        const std::vector<uint8_t>& mask = out->back_faces.data;
        const size_t back = mask.size() - static_cast<size_t>(std::count(mask.begin(), mask.end(), uint8_t{0}));
        if (static_cast<double>(back) > placement.max_back_face_fraction * static_cast<double>(pixels)) {
          view.verdict = Verdict::kInside;
          continue;
        }
      }
      Result<ImageU8> thumbnail = descriptorThumbnail(out->gray);
      if (!thumbnail.ok()) return fail(thumbnail.error());
      if (thumbnailContrast(*thumbnail) < placement.min_contrast) continue;
      Result<GlobalDescriptor> descriptor = globalDescriptor(out->gray);
      if (!descriptor.ok()) return fail(descriptor.error());
      view.keyframe.T_world_camera = poses[v];
      view.keyframe.descriptor = *descriptor;
      auto mid = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
      std::nth_element(depths.begin(), mid, depths.end());
      view.keyframe.scene_depth_m = *mid;
      view.verdict = Verdict::kKept;
    }
  };
  std::vector<std::thread> threads;
  for (size_t t = 1; t < renderers.size(); ++t) threads.emplace_back(work, std::ref(*renderers[t]), false);
  work(*renderers[0], true);
  for (std::thread& t : threads) t.join();
  if (error) return *error;

  KeyframeBuildStats s;
  s.positions = positions->size();
  s.views = poses.size();
  KeyframeDatabase db(modelFingerprint(model), camera);
  for (const View& view : views) {
    switch (view.verdict) {
      case Verdict::kKept:
        db.add(view.keyframe);
        break;
      case Verdict::kTooClose:
        ++s.too_close;
        break;
      case Verdict::kInside:
        ++s.inside;
        break;
      case Verdict::kEmpty:
        ++s.empty;
        break;
    }
  }
  s.kept = db.size();
  s.seconds = msSince(t0) * 1e-3;
  if (stats) *stats = s;
  return db;
}

}  // namespace vkloc
