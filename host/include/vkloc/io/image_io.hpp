// vkloc: reading and writing image files (PNG, JPEG, TIFF, PGM through OpenCV's codecs).
// Writers are atomic (core/atomic_file.hpp): an existing file is replaced only by a complete one.
#pragma once

#include <string>

#include "vkloc/core/image.hpp"
#include "vkloc/core/status.hpp"

namespace vkloc {

/// Writes an 8-bit gray/RGB/RGBA image or a 16-bit gray image as PNG. The file is written to a
/// temporary name and renamed, so an existing file is never left half-written.
Status writePng(const std::string& path, const ImageU8& image);
Status writePng(const std::string& path, const ImageU16& image);

/// Writes a single-channel float image as TIFF (32-bit float, lossless; readable by OpenCV,
/// GDAL, Python's tifffile). Same atomic-rename guarantee as writePng.
Status writeFloatTiff(const std::string& path, const ImageF32& image);

/// Reads an image file (PNG, JPEG, TIFF, ...) as 8-bit with `channels` = 1 (gray) or 4 (RGBA).
Result<ImageU8> readImageU8(const std::string& path, int channels);

/// Reads a single-channel 32-bit float TIFF written by writeFloatTiff.
Result<ImageF32> readFloatTiff(const std::string& path);

}  // namespace vkloc
