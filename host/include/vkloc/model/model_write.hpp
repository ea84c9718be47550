// vkloc: writing models to mesh files (for tests and for exporting the demo models).
#pragma once

#include <string>

#include "vkloc/core/status.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {

/// How saveModel encodes a model.
struct ModelWriteOptions {
  /// .gltf / .glb: compress every primitive with KHR_draco_mesh_compression (listed in
  /// extensionsUsed and extensionsRequired). Ignored by the other formats.
  bool draco = false;
  int draco_position_bits = 14;  ///< Draco position quantization, bits per coordinate (1..24).
  int draco_uv_bits = 12;        ///< Draco texture-coordinate quantization, bits (1..24).
  int draco_speed = 5;           ///< Draco encoder and decoder speed, 0 (smallest) .. 10 (fastest).
};

/// Writes `model` (world-frame positions as stored, no axis change) to `path`. The format
/// follows the extension (case-insensitive):
///  - .obj: text OBJ plus `<stem>.mtl` and one `<stem>_tex<i>.png` per texture next to it;
///    vertex colours as "v x y z r g b" (alpha is lost).
///  - .ply: binary little-endian PLY: positions, texture coordinates as s, t, RGBA vertex
///    colours; no materials or textures.
///  - .gltf: glTF 2.0 JSON plus `<stem>.bin` and `<stem>_tex<i>.png`; .glb: one binary glTF
///    file with the PNG textures embedded. One mesh with one primitive per used material,
///    uint32 indices, POSITION with min/max, TEXCOORD_0, COLOR_0 as normalized unsigned bytes
///    (the stored sRGB bytes), materials with baseColorFactor and baseColorTexture, samplers
///    with REPEAT wrapping. options.draco compresses the primitives.
///  - .drc: one Draco mesh with positions, texture coordinates and colours; no materials.
/// OBJ, PLY and Draco texture coordinates are stored with a bottom-left origin (v' = 1 - v), as
/// the tools that produce those formats do; glTF keeps (0, 0) at the top-left.
/// Every file is first written under a temporary name in the same folder and then renamed, so
/// an existing file is never left half-overwritten. Returns kInvalidArgument for a model that
/// breaks its invariants (out-of-range index, attribute sizes, no triangles) or bad options,
/// kUnsupported for an unknown extension, kIoError when a file cannot be written; messages
/// name the file.
Status saveModel(const Model& model, const std::string& path, const ModelWriteOptions& options = {});

}  // namespace vkloc
