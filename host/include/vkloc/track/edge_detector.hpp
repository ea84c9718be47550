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
/// high = max(high_factor * s, min_high_gradient, noise_sigmas * sigma_g), low = low_ratio * high,
/// where sigma_g is the noise of the gradient estimated from the flattest pixels: the
/// `noise_quantile` quantile q of the magnitude taken as a quantile of the Rayleigh distribution
/// that the magnitude of pure Gaussian noise follows, sigma_g = q / sqrt(-2 ln(1 - noise_quantile)).
/// On a plain, noisy wall the contrast quantile lies inside the noise and would turn sensor noise
/// and compression blocks into edges; the noise floor keeps only what stands out of the noise
/// (with 4.5 sigma, a pure-noise pixel passes the high threshold with probability exp(-10)).
/// Multiplying the image by a constant multiplies s, sigma_g and every magnitude alike, so the same
/// edges survive (only the absolute floor, which acts on nearly flat images, is not scale-free).
/// Non-maximum suppression along the gradient direction quantised to 4 directions keeps a pixel
/// whose magnitude is >= both neighbours and > at least one: on an ideal step both pixels next
/// to it are kept (a symmetric 2-pixel edge centred on the step, no half-pixel bias).
/// Hysteresis: 8-connected growth from pixels >= high through pixels >= low.
struct EdgeDetectorOptions {
  double contrast_percentile = 0.9;  ///< Quantile (0..1) of the gradient magnitude taken as contrast s.
  double high_factor = 1.0;          ///< High threshold = high_factor * s.
  double low_ratio = 0.4;            ///< Low threshold = low_ratio * high (0..1).
  double min_high_gradient = 2.0;    ///< Floor of the high threshold, gray levels per pixel.
  /// Quantile (0.01..0.9) of the magnitude that estimates the noise; taken at most one sample
  /// below the contrast quantile (no floor when that is the lowest sample).
  double noise_quantile = 0.25;
  double noise_sigmas = 4.5;  ///< High threshold floor in noise sigmas (0 = no noise floor).
};

/// Rayleigh factor of the noise estimate: the `noise_quantile` quantile of the magnitude of
/// Gaussian gradient noise of scale sigma_g is sigma_g * rayleighQuantileFactor(noise_quantile).
double rayleighQuantileFactor(double quantile);

/// Edge map of a gray image (any value range, typically 0..255): 255 on edge pixels, 0 elsewhere.
/// kInvalidArgument for an empty or multi-channel image or options out of range.
Result<ImageU8> detectEdges(const ImageF32& gray, const EdgeDetectorOptions& options = {});

/// Checks ranges of EdgeDetectorOptions; kInvalidArgument naming the field otherwise.
Status validateEdgeDetectorOptions(const EdgeDetectorOptions& options);

}  // namespace vkloc
