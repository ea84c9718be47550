// Shared pieces of the libFuzzer targets: a per-process scratch folder for loaders that take a
// path, and property checks that abort on violation.
//
// A violated property prints "vkloc fuzz: property '<id>' violated: <details>" and aborts, so
// libFuzzer records the input as a crash. Properties listed (comma-separated ids) in the
// environment variable VKLOC_FUZZ_KNOWN are known findings: they are reported once per process
// on stderr and do not abort (tests/fuzz/known_findings.txt keeps the list with reasons).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "vkloc/core/status.hpp"
#include "vkloc/io/calibration.hpp"

namespace vkloc::fuzz {

/// Per-process scratch folder (under /dev/shm when writable, else $TMPDIR or /tmp), created on
/// first use and removed at exit. Ends without '/'.
const std::string& scratchDir();

/// scratchDir() + "/" + name.
std::string scratchPath(const std::string& name);

/// Writes `size` bytes to `path` (truncating); aborts when the file cannot be written.
void writeInput(const std::string& path, const uint8_t* data, size_t size);
void writeInput(const std::string& path, std::string_view text);

/// Aborts unless `condition` holds or `id` is a known finding (see above).
void check(bool condition, const char* id, const std::string& details);

/// A failed load's message: exactly one line with no control characters (bytes < 0x20 and
/// 0x7f), and it contains `path` (skipped when `path` is empty). Property ids are
/// "<target>.error_one_line" and "<target>.error_names_file".
void checkErrorMessage(const Error& error, const std::string& path, const char* target);

/// True when `text` has no byte < 0x20 and no 0x7f.
bool noControlCharacters(std::string_view text);

/// `text` with control characters and bytes >= 0x7f shown as \xNN, for reports.
std::string escaped(std::string_view text);

/// |a - b| <= tol * max(1, |a|, |b|).
bool nearRelative(double a, double b, double tol);

/// "" when the cameras are equal field by field (exactly), else the first field that differs.
std::string cameraDifference(const SequenceCamera& a, const SequenceCamera& b);

/// The checks of a loaded camera: lensCamera() accepts it and T_body_camera is rigid (property
/// "<target>.valid"); saveSequenceCamera accepts it ("<target>.save_accepts_loaded") and `reload`
/// of the saved file gives it back exactly ("<target>.roundtrip").
void checkCamera(const SequenceCamera& camera, const char* target,
                 Result<SequenceCamera> (*reload)(const std::string& path));

}  // namespace vkloc::fuzz
