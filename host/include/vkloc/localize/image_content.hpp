// vkloc: whether a frame holds anything to align with. A black, saturated or uniform frame (lens
// cap, a lamp filling the view, a blank test frame) has no edges: aligning it, searching for it
// or relocalizing it only spends time on noise. The check runs on the frame's block-averaged
// thumbnail (80x64, the keyframe database's): averaging over blocks of about 60 pixels (640x480)
// lowers per-pixel sensor noise about 8 times, while the structure a tracker aligns with (edges
// between surfaces and textures) survives it.
#pragma once

#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// What a frame holds for the alignment.
enum class ImageContent {
  kOk,         ///< Structure to align with.
  kBlack,      ///< Nothing above the noise, and dark (mean below ImageContentOptions::dark_level).
  kSaturated,  ///< Nothing above the noise, and bright (mean above saturated_level).
  kUniform,    ///< Nothing above the noise, at any other gray level.
};

/// "ok" | "black" | "saturated" | "uniform" (the frames log's image_content column).
const char* imageContentName(ImageContent content);

/// Thresholds of checkImageContent. Plain data; validateImageContentOptions checks them.
struct ImageContentOptions {
  /// A frame whose contrast above the noise (ImageContentCheck::contrast) is below this has
  /// nothing to align with, gray levels (0 = check off). Real frames measured 16 and more (a
  /// plain painted wall of a rendered room), a uniform frame with noise of sigma 30 below 1.
  double min_contrast = 2.0;
  double dark_level = 32.0;        ///< Mean gray level below which such a frame is kBlack.
  double saturated_level = 224.0;  ///< Mean gray level above which it is kSaturated.
};

/// kInvalidArgument naming the field for values out of range (0..255, dark below saturated).
Status validateImageContentOptions(const ImageContentOptions& options);

/// The check's outcome and the statistics it decided on.
struct ImageContentCheck {
  ImageContent content = ImageContent::kOk;
  /// Standard deviation of the thumbnail's gray levels with the part that per-pixel noise
  /// leaves in it taken off: sqrt(max(0, var(thumbnail) - s^2 / n)), s the noise sigma estimated
  /// from the median absolute difference of horizontal neighbours (s = median / (0.6745 sqrt 2)),
  /// n the pixels per thumbnail block. Gray levels.
  double contrast = 0;
  double mean = 0;  ///< Mean gray level.
};

/// Checks an 8-bit gray image (1 channel, at least 1x1; images smaller than the thumbnail are
/// taken as they are). One pass over the image (0.4-0.7 ms at 640x480 on a busy 2-core machine).
/// kInvalidArgument for an empty or multi-channel image.
Result<ImageContentCheck> checkImageContent(const ImageU8& gray, const ImageContentOptions& options = {});

}  // namespace vkloc
