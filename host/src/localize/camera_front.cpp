#include "vkloc/localize/camera_front.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace vkloc {

namespace {

/// Written for view pixels without a source: far outside every image (remap gives 0).
constexpr float kNoSource = -1.0e5f;

}  // namespace

struct CameraFront::Maps {
  cv::Mat xy;        ///< CV_16SC2 integer positions.
  cv::Mat fraction;  ///< CV_16UC1 interpolation table indices.
};

CameraFront::~CameraFront() = default;

const char* viewKindName(ViewKind kind) { return kind == ViewKind::kStabilised ? "stabilised" : "undistorted"; }

Result<ViewKind> parseViewKind(const std::string& name) {
  if (name == "undistorted") return ViewKind::kUndistorted;
  if (name == "stabilised" || name == "stabilized") return ViewKind::kStabilised;
  return makeError(ErrorCode::kInvalidArgument, fmt::format("unknown view '{}' (undistorted, stabilised)", name));
}

Result<std::unique_ptr<CameraFront>> CameraFront::create(const LensCamera& lens, const ViewOptions& options) {
  VKLOC_TRY_STATUS(validateLensCamera(lens));
  auto bad = [](const std::string& what) {
    return makeError(ErrorCode::kInvalidArgument, fmt::format("camera front: {}", what));
  };
  if (options.width < 0 || options.height < 0 || options.width > 16384 || options.height > 16384 ||
      (options.width == 0) != (options.height == 0)) {
    return bad(fmt::format("view size {}x{} is invalid (both 1..16384, or both 0 for the lens's)", options.width,
                           options.height));
  }
  if (!(options.hfov_deg == 0 || (options.hfov_deg >= 1 && options.hfov_deg <= 170))) {
    return bad(fmt::format("hfov {} deg is outside 1..170 (0: default)", options.hfov_deg));
  }
  if (!(options.flat_field_sigma_px >= 0 && options.flat_field_sigma_px <= 1e4)) {
    return bad(fmt::format("flat field sigma {} px is outside 0..1e4", options.flat_field_sigma_px));
  }
  if (!(options.dead_band_deg >= 0 && options.dead_band_deg <= 90)) {
    return bad(fmt::format("dead band {} deg is outside 0..90", options.dead_band_deg));
  }
  if (!(options.pitch_deg >= -89 && options.pitch_deg <= 90)) {
    return bad(fmt::format("pitch {} deg is outside -89..90", options.pitch_deg));
  }
  if (!options.up_world.allFinite() || options.up_world.norm() < 1e-9) return bad("up_world is not a direction");
  if (options.grid_step_px < 1 || options.grid_step_px > 32) {
    return bad(fmt::format("grid step {} px is outside 1..32", options.grid_step_px));
  }
  std::unique_ptr<CameraFront> front(new CameraFront());
  front->lens_ = lens;
  front->options_ = options;
  front->up_world_ = options.up_world.normalized();
  const int w = options.width > 0 ? options.width : lens.intrinsics.width;
  const int h = options.height > 0 ? options.height : lens.intrinsics.height;
  const PinholeCamera& K = lens.intrinsics;
  const bool pinhole_focal = lens.model == LensModel::kPinhole && options.hfov_deg == 0;
  // An undistorted view of a pinhole lens no larger than it: the central crop at the lens's own
  // scale (its own intrinsics at its size; a wider field would magnify the lens image and reach
  // past it, --view-hfov asks for one).
  const bool crop = pinhole_focal && options.kind == ViewKind::kUndistorted && w <= K.width && h <= K.height;
  const bool keep_intrinsics = crop && w == K.width && h == K.height;
  if (crop) {
    front->view_ = PinholeCamera{K.fx, K.fy, K.cx - 0.5 * (K.width - w), K.cy - 0.5 * (K.height - h), w, h};
  } else if (pinhole_focal) {
    front->view_ = PinholeCamera{K.fx, K.fy, 0.5 * (w - 1), 0.5 * (h - 1), w, h};
  } else {
    const double hfov = options.hfov_deg > 0 ? options.hfov_deg : 90.0;
    const double f = 0.5 * w / std::tan(0.5 * hfov * M_PI / 180.0);
    front->view_ = PinholeCamera{f, f, 0.5 * (w - 1), 0.5 * (h - 1), w, h};
  }
  front->same_pixels_ = keep_intrinsics && lens.isIdealPinhole();
  if (front->same_pixels_) {
    front->slots_[kFixedSlot].valid_fraction = 1.0;
    return front;
  }
  // The view must mostly see through the lens, when their axes are aligned (a stabilised view
  // turns away from that as the camera does).
  (void)front->table(Eigen::Matrix3d::Identity());
  if (front->validFraction() < 0.5) {
    return bad(fmt::format("only {:.0f} % of the {}x{} view (hfov {:.1f} deg) lies in the lens's field of view",
                           100.0 * front->validFraction(), w, h,
                           2.0 * std::atan(0.5 * w / front->view_.fx) * 180.0 / M_PI));
  }
  return front;
}

Eigen::Matrix3d CameraFront::viewRotation(const Eigen::Matrix3d& R_world_camera) const {
  if (options_.kind != ViewKind::kStabilised) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d& up = up_world_;
  // Heading: the horizontal part of forward - (forward . up) image-up: forward's own for a level
  // camera, image-up's for one looking straight down (image-down's straight up), and positive
  // along the camera's heading at every pitch in between (no flip past 45 deg).
  const Eigen::Vector3d forward = R_world_camera.col(2);
  const Eigen::Vector3d image_up = -R_world_camera.col(1);
  Eigen::Vector3d heading = forward - forward.dot(up) * image_up;
  heading -= heading.dot(up) * up;
  if (heading.norm() < 1e-6) heading = R_world_camera.col(0).cross(up);
  heading.normalize();
  const double p = options_.pitch_deg * M_PI / 180.0;
  Eigen::Matrix3d R_world_view;
  const Eigen::Vector3d z = std::cos(p) * heading - std::sin(p) * up;
  const Eigen::Vector3d x = heading.cross(up).normalized();
  R_world_view.col(0) = x;
  R_world_view.col(1) = z.cross(x);
  R_world_view.col(2) = z;
  const Eigen::Matrix3d R_camera_view = R_world_camera.transpose() * R_world_view;
  if (!(options_.dead_band_deg > 0)) return R_camera_view;
  const Eigen::AngleAxisd turn(R_camera_view);
  const double band = options_.dead_band_deg * M_PI / 180.0;
  if (turn.angle() <= band) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(turn.angle() - band, turn.axis()).toRotationMatrix();
}

Pose CameraFront::viewExtrinsic(const Pose& T_world_camera) const {
  Pose T = Pose::Identity();
  T.linear() = viewRotation(T_world_camera.linear());
  return T;
}

bool CameraFront::sourceOf(const Eigen::Matrix3d& R_camera_view, double u, double v, float& su, float& sv) const {
  const Eigen::Vector3d ray_view((u - view_.cx) / view_.fx, (v - view_.cy) / view_.fy, 1.0);
  Eigen::Vector2d uv;
  if (!projectLens(lens_, R_camera_view * ray_view, uv)) return false;
  if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() <= lens_.intrinsics.width - 1 && uv.y() <= lens_.intrinsics.height - 1)) {
    return false;
  }
  su = static_cast<float>(uv.x());
  sv = static_cast<float>(uv.y());
  return true;
}

RemapTable CameraFront::exactTable(const Eigen::Matrix3d& R_camera_view) const {
  RemapTable t;
  fillGrid(R_camera_view, 1, t);
  return t;
}

void CameraFront::fillGrid(const Eigen::Matrix3d& R_camera_view, int step, RemapTable& t) const {
  const int w = view_.width, h = view_.height;
  t.width = w;
  t.height = h;
  t.source_width = lens_.intrinsics.width;
  t.source_height = lens_.intrinsics.height;
  t.uv.assign(static_cast<size_t>(w) * h * 2, kNoSource);
  auto exact = [&](int x, int y) {
    float su = kNoSource, sv = kNoSource;
    if (!sourceOf(R_camera_view, x, y, su, sv)) su = sv = kNoSource;
    float* p = &t.uv[(static_cast<size_t>(y) * w + x) * 2];
    p[0] = su;
    p[1] = sv;
  };
  if (step <= 1) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) exact(x, y);
    }
    return;
  }
  // Grid nodes every `step` pixels plus the last row and column; cells with four valid corners
  // are interpolated bilinearly, the others (the edge of the lens's field) projected exactly.
  std::vector<int> xs, ys;
  for (int x = 0; x < w; x += step) xs.push_back(x);
  if (xs.back() != w - 1) xs.push_back(w - 1);
  for (int y = 0; y < h; y += step) ys.push_back(y);
  if (ys.back() != h - 1) ys.push_back(h - 1);
  for (int y : ys) {
    for (int x : xs) exact(x, y);
  }
  auto node = [&](int x, int y) { return &t.uv[(static_cast<size_t>(y) * w + x) * 2]; };
  for (size_t j = 0; j + 1 < ys.size(); ++j) {
    const int y0 = ys[j], y1 = ys[j + 1];
    for (size_t i = 0; i + 1 < xs.size(); ++i) {
      const int x0 = xs[i], x1 = xs[i + 1];
      const float* a = node(x0, y0);
      const float* b = node(x1, y0);
      const float* c = node(x0, y1);
      const float* d = node(x1, y1);
      const bool all_valid = a[0] != kNoSource && b[0] != kNoSource && c[0] != kNoSource && d[0] != kNoSource;
      const int y_end = j + 2 == ys.size() ? y1 : y1 - 1;
      const int x_end = i + 2 == xs.size() ? x1 : x1 - 1;
      for (int y = y0; y <= y_end; ++y) {
        const float fy = static_cast<float>(y - y0) / static_cast<float>(y1 - y0);
        for (int x = x0; x <= x_end; ++x) {
          if ((x == x0 || x == x1) && (y == y0 || y == y1)) continue;  // a node
          if (!all_valid) {
            exact(x, y);
            continue;
          }
          const float fx = static_cast<float>(x - x0) / static_cast<float>(x1 - x0);
          float* p = node(x, y);
          for (int k = 0; k < 2; ++k) {
            p[k] = (1 - fy) * ((1 - fx) * a[k] + fx * b[k]) + fy * ((1 - fx) * c[k] + fx * d[k]);
          }
        }
      }
    }
  }
}

const RemapTable& CameraFront::table(const Eigen::Matrix3d& R_camera_view) {
  const bool fixed = options_.kind != ViewKind::kStabilised || R_camera_view == Eigen::Matrix3d::Identity();
  const int index = fixed ? kFixedSlot : kTurnedSlot;
  Slot& slot = slots_[index];
  if (index != current_) {
    current_ = index;
    remapper_stale_ = true;
  }
  if (!slot.table.uv.empty() && (fixed || R_camera_view == slot.R_camera_view)) return slot.table;
  RemapTable& table = slot.table;
  fillGrid(R_camera_view, fixed ? 1 : options_.grid_step_px, table);
  slot.R_camera_view = R_camera_view;
  // Pixels without a source: 0 in the view (OpenCV replicates the border for taps that fall
  // outside the lens image, as the reference clamps them; a pixel with no source is zeroed).
  slot.no_source.clear();
  for (size_t i = 0; i < table.uv.size(); i += 2) {
    const float u = table.uv[i], v = table.uv[i + 1];
    if (!(u >= 0 && v >= 0 && u <= static_cast<float>(table.source_width - 1) &&
          v <= static_cast<float>(table.source_height - 1))) {
      slot.no_source.push_back(static_cast<uint32_t>(i / 2));
    }
  }
  const size_t valid = table.uv.size() / 2 - slot.no_source.size();
  slot.valid_fraction = table.uv.empty() ? 0.0 : static_cast<double>(valid) / static_cast<double>(table.uv.size() / 2);
  slot.maps.reset();
  remapper_stale_ = true;
  if (fixed && !remapper_ && options_.interpolation == RemapInterpolation::kBilinear) buildMaps(slot);
  return table;
}

Status CameraFront::remap(const ImageU8& lens_image, const Eigen::Matrix3d& R_camera_view, ImageU8& view_image) {
  const PinholeCamera& k = lens_.intrinsics;
  if (lens_image.channels != 1 || lens_image.width != k.width || lens_image.height != k.height ||
      lens_image.data.size() != static_cast<size_t>(k.width) * k.height) {
    return makeError(ErrorCode::kInvalidArgument,
                     fmt::format("camera front: image is {}x{} with {} channel(s); the calibration is {}x{} gray",
                                 lens_image.width, lens_image.height, lens_image.channels, k.width, k.height));
  }
  VKLOC_TRY_STATUS(resample(lens_image, R_camera_view, view_image));
  if (options_.flat_field_sigma_px > 0) flatten(view_image);
  return Status::success();
}

Status CameraFront::resample(const ImageU8& lens_image, const Eigen::Matrix3d& R_camera_view, ImageU8& view_image) {
  const PinholeCamera& k = lens_.intrinsics;
  if (same_pixels_) {  // no remap
    view_image = lens_image;
    return Status::success();
  }
  const RemapTable& t = table(R_camera_view);
  if (view_image.width != t.width || view_image.height != t.height || view_image.channels != 1) {
    view_image = ImageU8(t.width, t.height, 1);
  }
  if (remapper_) {
    if (remapper_stale_) {
      VKLOC_TRY_STATUS(remapper_->setTable(t));
      remapper_stale_ = false;
    }
    Result<ImageU8> out = remapper_->remap(lens_image);
    if (!out.ok()) return out.error();
    view_image = std::move(out).value();
    return Status::success();
  }
  const Slot& slot = current();
  if (options_.interpolation == RemapInterpolation::kBicubic) {
    // The fixed-point bicubic path (remapBicubicFixedRows) on OpenCV's threads, in stripes of
    // rows; it reads the float table itself (no maps to build for a table made this frame) and
    // zeroes the pixels without a source.
    const int stripes = std::max(1, std::min(t.height / 16, 4 * cv::getNumThreads()));
    cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& r) {
      const int begin = static_cast<int>(static_cast<int64_t>(t.height) * r.start / stripes);
      const int end = static_cast<int>(static_cast<int64_t>(t.height) * r.end / stripes);
      remapBicubicFixedRows(lens_image.data.data(), t, view_image.data.data(), begin, end);
    });
    return Status::success();
  }
  const cv::Mat src(k.height, k.width, CV_8UC1, const_cast<uint8_t*>(lens_image.data.data()));
  cv::Mat dst(t.height, t.width, CV_8UC1, view_image.data.data());
  if (slot.maps) {
    cv::remap(src, dst, slot.maps->xy, slot.maps->fraction, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  } else {
    const cv::Mat uv(t.height, t.width, CV_32FC2, const_cast<float*>(t.uv.data()));
    cv::remap(src, dst, uv, cv::Mat(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  }
  for (uint32_t i : slot.no_source) view_image.data[i] = 0;
  return Status::success();
}

void CameraFront::flatten(ImageU8& view_image) const {
  const int w = view_image.width, h = view_image.height;
  cv::Mat image(h, w, CV_8UC1, view_image.data.data());
  cv::Mat value;
  image.convertTo(value, CV_32F);
  cv::Mat weight(h, w, CV_32F, cv::Scalar(1.0f));
  float* weights = weight.ptr<float>();
  const std::vector<uint32_t>& no_source = current().no_source;
  for (uint32_t i : no_source) weights[i] = 0.0f;
  // The local mean: a normalized convolution (sum of w I over sum of w, Gaussian weights) at
  // 1/k scale, k a power of two up to 8 that leaves sigma >= 2 of its pixels, then bilinear back.
  const double sigma = options_.flat_field_sigma_px;
  int k = 1;
  while (k < 8 && sigma / (2 * k) >= 2.0) k *= 2;
  const cv::Size small_size((w + k - 1) / k, (h + k - 1) / k);
  cv::Mat weighted = value.mul(weight), small_value, small_weight;
  cv::resize(weighted, small_value, small_size, 0, 0, cv::INTER_AREA);
  cv::resize(weight, small_weight, small_size, 0, 0, cv::INTER_AREA);
  cv::GaussianBlur(small_value, small_value, cv::Size(0, 0), sigma / k, sigma / k, cv::BORDER_REFLECT);
  cv::GaussianBlur(small_weight, small_weight, cv::Size(0, 0), sigma / k, sigma / k, cv::BORDER_REFLECT);
  cv::Mat local = small_value / cv::max(small_weight, 1e-3);
  cv::Mat local_full;
  cv::resize(local, local_full, cv::Size(w, h), 0, 0, cv::INTER_LINEAR);
  const double total_weight = cv::sum(weight)[0];
  if (!(total_weight > 0)) return;
  const double mean = cv::sum(weighted)[0] / total_weight;
  // A floor on the local mean (5 % of the image's, one gray level) keeps near-black regions from
  // being lifted into noise.
  const float floor_value = static_cast<float>(std::max(1.0, 0.05 * mean));
  cv::Mat flat = value.mul(static_cast<float>(mean) / cv::max(local_full, floor_value));
  flat.convertTo(image, CV_8U);  // rounds and saturates into the view's own buffer
  for (uint32_t i : no_source) view_image.data[i] = 0;
}

void CameraFront::setRemapper(std::unique_ptr<ImageRemapper> remapper) {
  remapper_ = std::move(remapper);
  remapper_stale_ = true;
  // Without a device the kept table needs its OpenCV maps again.
  if (!remapper_ && options_.interpolation == RemapInterpolation::kBilinear && !slots_[kFixedSlot].table.uv.empty() &&
      !slots_[kFixedSlot].maps) {
    buildMaps(slots_[kFixedSlot]);
  }
}

void CameraFront::buildMaps(Slot& slot) {
  slot.maps = std::make_unique<Maps>();
  const cv::Mat uv(slot.table.height, slot.table.width, CV_32FC2, slot.table.uv.data());
  cv::convertMaps(uv, cv::Mat(), slot.maps->xy, slot.maps->fraction, CV_16SC2);
}

std::string CameraFront::remapDescription() const {
  if (remapper_) return remapper_->describe();
  return options_.interpolation == RemapInterpolation::kBicubic ? std::string("fixed-point bicubic remap (CPU)")
                                                                : std::string("OpenCV remap (CPU)");
}

}  // namespace vkloc
