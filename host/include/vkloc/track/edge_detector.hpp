// vkloc: the Canny-like edge detector shared by live images and reference renders (seed paper
// 000, sec. IV-C). Pixel convention of core/camera.hpp: pixel (i, j)'s centre is (u, v) = (i, j).
#pragma once

#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

// --- edge detection ------------------------------------------------------------------------

/// Canny-like edge detector whose thresholds follow the image's contrast.
///
/// Gradient: 3x3 Sobel divided by 8 (gray levels per pixel), magnitude sqrt(gx^2 + gy^2).
/// Thresholds: s = the `contrast_percentile` quantile of the magnitude over all pixels;
/// high = max(high_factor * s, min_high_gradient), low = low_ratio * high. Multiplying the image
/// by a constant multiplies s and every magnitude alike, so the same edges survive (only the
/// absolute floor, which acts on nearly flat images, is not scale-free).
/// Non-maximum suppression along the gradient direction quantised to 4 directions keeps a pixel
/// whose magnitude is >= both neighbours and > at least one: on an ideal step both pixels next
/// to it are kept (a symmetric 2-pixel edge centred on the step, no half-pixel bias).
/// Hysteresis: 8-connected growth from pixels >= high through pixels >= low.
struct EdgeDetectorOptions {
  double contrast_percentile = 0.9;  ///< Quantile (0..1) of the gradient magnitude taken as contrast s.
  double high_factor = 1.0;          ///< High threshold = high_factor * s.
  double low_ratio = 0.4;            ///< Low threshold = low_ratio * high (0..1).
  double min_high_gradient = 2.0;    ///< Floor of the high threshold, gray levels per pixel.
};

/// Edge map of a gray image (any value range, typically 0..255): 255 on edge pixels, 0 elsewhere.
/// kInvalidArgument for an empty or multi-channel image or options out of range.
Result<ImageU8> detectEdges(const ImageF32& gray, const EdgeDetectorOptions& options = {});

/// Checks ranges of EdgeDetectorOptions; kInvalidArgument naming the field otherwise.
Status validateEdgeDetectorOptions(const EdgeDetectorOptions& options);

}  // namespace vkloc
