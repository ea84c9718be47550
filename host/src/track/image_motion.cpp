#include "vkloc/track/image_motion.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

namespace vkloc {

Result<std::vector<ImageShift>> estimateImageShifts(const ImageU8& previous, const ImageU8& current,
                                                    const PinholeCamera& camera,
                                                    const Eigen::Matrix3d& R_current_previous, int level,
                                                    int max_peaks) {
  auto sized = [&](const ImageU8& image) {
    return image.channels == 1 && image.width == camera.width && image.height == camera.height &&
           image.data.size() == static_cast<size_t>(image.width) * image.height;
  };
  if (!sized(previous) || !sized(current)) {
    return makeError(ErrorCode::kInvalidArgument, "estimateImageShifts: images must be gray and of the camera's size");
  }
  if (!R_current_previous.allFinite()) {
    return makeError(ErrorCode::kInvalidArgument, "estimateImageShifts: the rotation is not finite");
  }
  const double scale = std::ldexp(1.0, -std::max(0, level));
  const int w = static_cast<int>(camera.width * scale), h = static_cast<int>(camera.height * scale);
  if (level < 0 || w < 16 || h < 16) {
    return makeError(ErrorCode::kInvalidArgument, "estimateImageShifts: the level leaves fewer than 16x16 pixels");
  }
  // Pixel centres: u_level + 0.5 = (u + 0.5) scale.
  Eigen::Matrix3d K;
  K << camera.fx * scale, 0, (camera.cx + 0.5) * scale - 0.5, 0, camera.fy * scale, (camera.cy + 0.5) * scale - 0.5, 0,
      0, 1;
  const Eigen::Matrix3d H = K * R_current_previous * K.inverse();  // previous pixel -> current pixel
  const cv::Mat prev_full(previous.height, previous.width, CV_8UC1, const_cast<uint8_t*>(previous.data.data()));
  const cv::Mat cur_full(current.height, current.width, CV_8UC1, const_cast<uint8_t*>(current.data.data()));
  cv::Mat prev_small, cur_small;
  cv::resize(prev_full, prev_small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  cv::resize(cur_full, cur_small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  cv::Mat Hcv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Hcv.at<double>(r, c) = H(r, c);
  }
  cv::Mat prev_turned, valid;
  cv::warpPerspective(prev_small, prev_turned, Hcv, cv::Size(w, h), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  // Pixels the turned previous view does not cover are filled with the current image's mean, so
  // the border of the warp is not a strong edge of its own.
  cv::warpPerspective(cv::Mat(h, w, CV_8UC1, cv::Scalar(255)), valid, Hcv, cv::Size(w, h), cv::INTER_NEAREST,
                      cv::BORDER_CONSTANT, 0);
  cv::Mat a, b;
  prev_turned.convertTo(a, CV_64F);
  cur_small.convertTo(b, CV_64F);
  const double mean_b = cv::mean(b)[0];
  a.setTo(mean_b, valid == 0);
  // High-pass (minus a Gaussian blur of sigma = 3 pixels of the level): what the camera carries
  // with it (vignetting, shading across the view) would otherwise pull the peak to zero shift.
  auto highPass = [](cv::Mat& m) {
    cv::Mat low;
    cv::GaussianBlur(m, low, cv::Size(0, 0), 3.0);
    m -= low;
  };
  highPass(a);
  highPass(b);
  a.setTo(0.0, valid == 0);
  cv::Mat window;
  cv::createHanningWindow(window, cv::Size(w, h), CV_64F);
  a = a.mul(window);
  b = b.mul(window);
  // Phase correlation by hand (cv::phaseCorrelate gives only the highest peak): the normalized
  // cross-power spectrum's inverse transform peaks at each shift that part of the view moved by
  // (a far facade through a window and the near wall around it move differently).
  const int W = cv::getOptimalDFTSize(w), Hh = cv::getOptimalDFTSize(h);
  cv::Mat pa, pb;
  cv::copyMakeBorder(a, pa, 0, Hh - h, 0, W - w, cv::BORDER_CONSTANT, 0);
  cv::copyMakeBorder(b, pb, 0, Hh - h, 0, W - w, cv::BORDER_CONSTANT, 0);
  cv::Mat Fa, Fb, C;
  cv::dft(pa, Fa, cv::DFT_COMPLEX_OUTPUT);
  cv::dft(pb, Fb, cv::DFT_COMPLEX_OUTPUT);
  cv::mulSpectrums(Fb, Fa, C, 0, true);  // Fb conj(Fa): peak at the shift of b against a
  std::vector<cv::Mat> parts;
  cv::split(C, parts);
  cv::Mat magnitude;
  cv::magnitude(parts[0], parts[1], magnitude);
  magnitude += 1e-12;
  parts[0] /= magnitude;
  parts[1] /= magnitude;
  cv::merge(parts, C);
  cv::Mat surface;
  cv::idft(C, surface, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  // Peaks: local maxima of the (circular) surface, highest first, at least 3 pixels apart; the
  // response is the 5x5 sum around the peak (the sub-pixel energy) and the position its centroid.
  std::vector<ImageShift> peaks;
  cv::Mat work = surface.clone();
  for (int k = 0; k < std::max(1, max_peaks); ++k) {
    cv::Point at;
    double top = 0;
    cv::minMaxLoc(work, nullptr, &top, nullptr, &at);
    if (!(top > 0)) break;
    double sum = 0, sx = 0, sy = 0;
    for (int dy = -2; dy <= 2; ++dy) {
      for (int dx = -2; dx <= 2; ++dx) {
        const int y = (at.y + dy + Hh) % Hh, x = (at.x + dx + W) % W;
        const double value = std::max(0.0, surface.at<double>(y, x));
        sum += value;
        sx += value * dx;
        sy += value * dy;
        work.at<double>(y, x) = -1.0;
      }
    }
    // Clear a wider neighbourhood so the next peak is another one.
    for (int dy = -4; dy <= 4; ++dy) {
      for (int dx = -4; dx <= 4; ++dx) work.at<double>((at.y + dy + Hh) % Hh, (at.x + dx + W) % W) = -1.0;
    }
    double px = at.x + (sum > 0 ? sx / sum : 0.0), py = at.y + (sum > 0 ? sy / sum : 0.0);
    if (px > W / 2.0) px -= W;
    if (py > Hh / 2.0) py -= Hh;
    ImageShift shift;
    shift.dx_px = px / scale;
    shift.dy_px = py / scale;
    shift.response = std::isfinite(sum) ? std::min(1.0, sum) : 0.0;
    if (std::isfinite(shift.dx_px) && std::isfinite(shift.dy_px)) peaks.push_back(shift);
  }
  std::sort(peaks.begin(), peaks.end(),
            [](const ImageShift& x, const ImageShift& y) { return x.response > y.response; });
  return peaks;
}

}  // namespace vkloc
