// Draco (.drc) loading and the decoding of Draco-compressed glTF primitives. Every count read
// from the stream is checked against the bytes that back it before the decoder allocates.
#include <draco/compression/decode.h>
#include <draco/compression/entropy/symbol_decoding.h>
#include <draco/compression/mesh/mesh_edgebreaker_decoder.h>
#include <draco/compression/mesh/mesh_sequential_decoder.h>
#include <draco/core/varint_decoding.h>
#include <draco/mesh/mesh.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include "model/model_internal.hpp"

namespace vkloc::model_detail {
namespace {

// Little-endian reads that fail instead of running past the end.
class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : p_(data), left_(size) {}
  bool u8(uint8_t& v) { return read(&v, 1); }
  bool u16(uint16_t& v) {
    uint8_t b[2];
    if (!read(b, 2)) return false;
    v = static_cast<uint16_t>(b[0] | (b[1] << 8));
    return true;
  }
  bool u32(uint32_t& v) {
    uint8_t b[4];
    if (!read(b, 4)) return false;
    v = uint32_t{b[0]} | (uint32_t{b[1]} << 8) | (uint32_t{b[2]} << 16) | (uint32_t{b[3]} << 24);
    return true;
  }
  // LEB128 as Draco writes it (least significant group first), at most 32 bits.
  bool varint(uint32_t& v) {
    v = 0;
    for (int shift = 0; shift < 35; shift += 7) {
      uint8_t b;
      if (!u8(b) || (shift == 28 && (b & 0x70))) return false;
      v |= uint32_t{b & 0x7fu} << shift;
      if (!(b & 0x80)) return true;
    }
    return false;
  }
  bool skip(uint64_t n) {
    if (n > left_) return false;
    p_ += n;
    left_ -= n;
    return true;
  }

 private:
  bool read(uint8_t* out, size_t n) {
    if (n > left_) return false;
    std::memcpy(out, p_, n);
    return skip(n);
  }
  const uint8_t* p_;
  size_t left_;
};

// Skips a Draco metadata block (entries and nested sub-metadata), refusing deep nesting.
bool skipDracoMetadata(ByteReader& r, int depth) {
  uint32_t entries = 0, children = 0;
  uint8_t name = 0;
  if (depth > 32 || !r.varint(entries)) return false;
  for (uint32_t i = 0; i < entries; ++i) {
    uint32_t size = 0;
    if (!r.u8(name) || !r.skip(name) || !r.varint(size) || size == 0 || !r.skip(size)) return false;
  }
  if (!r.varint(children)) return false;
  for (uint32_t i = 0; i < children; ++i) {
    if (!r.u8(name) || !r.skip(name) || !skipDracoMetadata(r, depth + 1)) return false;
  }
  return true;
}

// Draco's decoders size their arrays from the face and vertex counts at the start of the
// connectivity data, before reading the data behind them. Real meshes need well over a bit per
// face and per vertex, so counts above this many per stream byte (plus a floor for tiny
// streams) come from a corrupt or hostile header and are refused before decoding.
constexpr uint64_t kDracoElementsPerByte = 16;
constexpr uint64_t kDracoElementsFloor = uint64_t{1} << 16;

bool checkDracoCounts(const uint8_t* data, size_t size, std::string& error) {
  ByteReader r(data, size);
  uint8_t major = 0, minor = 0, type = 0, method = 0;
  uint16_t flags = 0;
  if (!r.skip(5) || !r.u8(major) || !r.u8(minor) || !r.u8(type) || !r.u8(method) || !r.u16(flags)) {
    error = "truncated Draco header";
    return false;
  }
  const int version = major * 256 + minor;
  bool ok = true;
  if (version >= 0x0103 && (flags & 0x8000)) {
    uint32_t attribute_metadata = 0, unique_id = 0;
    ok = r.varint(attribute_metadata);
    for (uint32_t i = 0; ok && i < attribute_metadata; ++i) {
      ok = r.varint(unique_id) && skipDracoMetadata(r, 0);
    }
    ok = ok && skipDracoMetadata(r, 0);
  }
  const bool fixed = version < 0x0200;  // counts were plain uint32 before 2.0
  const auto count = [&](bool fixed32, uint32_t& v) { return fixed32 ? r.u32(v) : r.varint(v); };
  uint32_t counts[4] = {0, 0, 0, 0};
  if (method == 0) {  // sequential: faces, points
    ok = ok && count(version < 0x0202, counts[0]) && count(version < 0x0202, counts[1]);
  } else if (method == 1) {  // edgebreaker: vertices, faces, symbols, split symbols
    uint8_t traversal = 0, attribute_data = 0;
    uint32_t new_vertices = 0;
    ok = ok && r.u8(traversal) && (version >= 0x0202 || count(fixed, new_vertices)) && count(fixed, counts[0]) &&
         count(fixed, counts[1]) && r.u8(attribute_data) && count(fixed, counts[2]) && count(fixed, counts[3]);
  } else {
    error = fmt::format("unknown Draco encoding method {}", method);
    return false;
  }
  if (!ok) {
    error = "truncated or corrupt Draco header";
    return false;
  }
  const uint64_t limit = kDracoElementsFloor + kDracoElementsPerByte * size;
  for (uint32_t c : counts) {
    if (c > limit) {
      error = fmt::format("Draco header claims {} elements in a {}-byte stream", c, size);
      return false;
    }
  }
  return true;
}

// Draco's Edgebreaker decoder with one check Draco lacks. The texture-coordinate predictors
// (portable and deprecated) read an orientation count from the stream and decode that many bits
// whatever the mesh holds: a 226-byte file can ask for 2^31 (seconds of work before the decode
// fails). A valid stream has at most one orientation per attribute entry. Draco asks the decoder
// for the attribute's encoding data when it creates the predictor, right after reading the
// predictor's method and transform bytes and before the values; at that point this decoder reads
// ahead on a copy of the stream, past the values (decoded as Draco will decode them), to the
// count, and refuses the stream when the count exceeds the entries. Refusing makes Draco fall
// back to a delta predictor (linear work); the caller reports the refusal.
class BoundedEdgebreakerDecoder : public draco::MeshEdgebreakerDecoder {
 public:
  // `buffer` is the stream Decode() is given; it must outlive the decoder.
  explicit BoundedEdgebreakerDecoder(const draco::DecoderBuffer* buffer) : stream_(buffer) {}

  const std::string& refusal() const { return refusal_; }
  /// Whether the refusal is of a valid stream this check cannot judge (not a corrupt one).
  bool refusalUnsupported() const { return unsupported_; }

  const draco::MeshAttributeIndicesEncodingData* GetAttributeEncodingData(int att_id) const override {
    const draco::MeshAttributeIndicesEncodingData* data = MeshEdgebreakerDecoder::GetAttributeEncodingData(att_id);
    if (data && refusal_.empty()) refusal_ = checkOrientationCount(att_id, *data);
    return refusal_.empty() ? data : nullptr;
  }

 private:
  // Empty when the stream is fine at this attribute or when it is broken in a way Draco's own
  // decode reports (the read-ahead then stops without judging).
  std::string checkOrientationCount(int att_id, const draco::MeshAttributeIndicesEncodingData& data) const {
    if (stream_->decoded_size() < 2) return {};
    const char* head = stream_->data_head();
    const auto method = static_cast<int8_t>(head[-2]);
    const auto transform = static_cast<int8_t>(head[-1]);
    const bool portable = method == draco::MESH_PREDICTION_TEX_COORDS_PORTABLE;
    // Only integer and quantized attributes (wrap transform) get the texture-coordinate predictors.
    if (transform != draco::PREDICTION_TRANSFORM_WRAP ||
        (!portable && method != draco::MESH_PREDICTION_TEX_COORDS_DEPRECATED)) {
      return {};
    }
    const uint16_t version = bitstream_version();
    if (version < DRACO_BITSTREAM_VERSION(2, 0)) {
      // Quantization data sat between the method and the values then; the count cannot be
      // located without knowing the attribute's decoder.
      unsupported_ = true;
      return fmt::format("texture-coordinate prediction in a version {}.{} Draco stream is not supported", version >> 8,
                         version & 0xff);
    }
    const draco::PointAttribute* att = point_cloud()->attribute(att_id);
    if (!att || att->num_components() < 1) return {};
    const uint64_t entries = data.num_values;
    const uint64_t values = entries * static_cast<uint64_t>(att->num_components());
    if (values > UINT32_MAX) return {};
    draco::DecoderBuffer ahead(*stream_);
    uint8_t compressed = 0;
    if (!ahead.Decode(&compressed)) return {};
    if (compressed) {
      std::vector<uint32_t> symbols(values);
      if (!draco::DecodeSymbols(static_cast<uint32_t>(values), att->num_components(), &ahead, symbols.data())) {
        return {};
      }
    } else {
      uint8_t value_bytes = 0;
      if (!ahead.Decode(&value_bytes) || static_cast<int64_t>(value_bytes * values) > ahead.remaining_size()) return {};
      ahead.Advance(static_cast<int64_t>(value_bytes * values));
    }
    uint32_t count = 0;
    if (portable) {
      int32_t signed_count = 0;
      if (!ahead.Decode(&signed_count) || signed_count < 0) return {};
      count = static_cast<uint32_t>(signed_count);
    } else if (version < DRACO_BITSTREAM_VERSION(2, 2) ? !ahead.Decode(&count) : !draco::DecodeVarint(&count, &ahead)) {
      return {};
    }
    if (count <= entries) return {};
    return fmt::format("texture-coordinate predictor of attribute {} claims {} orientations for {} entries", att_id,
                       count, entries);
  }

  const draco::DecoderBuffer* stream_;
  mutable std::string refusal_;
  mutable bool unsupported_ = false;
};

}  // namespace

// Decodes a Draco triangle mesh. On failure returns null with `error` set; `unsupported` is set
// when the stream is valid but holds a point cloud.

std::unique_ptr<draco::Mesh> decodeDracoMesh(const uint8_t* data, size_t size, std::string& error, bool& unsupported) {
  unsupported = false;
  if (size < 5 || std::memcmp(data, "DRACO", 5) != 0) {
    error = "not a Draco stream (no DRACO magic)";
    return nullptr;
  }
  draco::DecoderBuffer buffer;
  buffer.Init(reinterpret_cast<const char*>(data), size);
  auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok()) {
    error = "cannot decode Draco: " + type.status().error_msg_string();
    return nullptr;
  }
  if (type.value() == draco::POINT_CLOUD) {
    error = "Draco point cloud, not a triangle mesh";
    unsupported = true;
    return nullptr;
  }
  if (type.value() != draco::TRIANGULAR_MESH) {
    error = "unknown Draco geometry type";
    return nullptr;
  }
  if (!checkDracoCounts(data, size, error)) return nullptr;
  draco::DecoderBuffer header_buffer(buffer);
  draco::DracoHeader header;
  if (!draco::PointCloudDecoder::DecodeHeader(&header_buffer, &header).ok()) {
    error = "truncated or corrupt Draco header";
    return nullptr;
  }
  // Sequential meshes have no connectivity for the texture-coordinate predictors: Draco's own
  // decoder; Edgebreaker ones get the orientation-count check.
  std::unique_ptr<draco::MeshDecoder> decoder;
  BoundedEdgebreakerDecoder* bounded = nullptr;
  if (header.encoder_method == draco::MESH_EDGEBREAKER_ENCODING) {
    auto edgebreaker = std::make_unique<BoundedEdgebreakerDecoder>(&buffer);
    bounded = edgebreaker.get();
    decoder = std::move(edgebreaker);
  } else if (header.encoder_method == draco::MESH_SEQUENTIAL_ENCODING) {
    decoder = std::make_unique<draco::MeshSequentialDecoder>();
  } else {
    error = "cannot decode Draco: unknown encoding method";
    return nullptr;
  }
  auto mesh = std::make_unique<draco::Mesh>();
  const draco::DecoderOptions options;
  const draco::Status status = decoder->Decode(options, &buffer, mesh.get());
  if (bounded && !bounded->refusal().empty()) {
    unsupported = bounded->refusalUnsupported();
    error = (unsupported ? "Draco stream: " : "corrupt Draco stream: ") + bounded->refusal();
    return nullptr;
  }
  if (!status.ok()) {
    error = "cannot decode Draco: " + status.error_msg_string();
    return nullptr;
  }
  return mesh;
}

// Reads `comps` components per point as floats (normalized integers as 0..1).
namespace {

bool readDracoAttribute(const draco::PointAttribute& att, uint32_t points, int comps, std::vector<float>& out) {
  if (att.num_components() < 1 || (!att.is_mapping_identity() && att.indices_map_size() < points)) {
    return false;
  }
  out.assign(size_t{points} * comps, 0.0f);
  for (uint32_t i = 0; i < points; ++i) {
    const draco::AttributeValueIndex value = att.mapped_index(draco::PointIndex(i));
    if (value.value() >= att.size() ||
        !att.ConvertValue<float>(value, static_cast<int8_t>(comps), &out[size_t{i} * comps])) {
      return false;
    }
  }
  return true;
}

}  // namespace

// Converts a decoded Draco mesh to a primitive. `flip_v` turns a bottom-left uv origin into the
// top-left one. Returns false with `error` set when an attribute cannot be read.
bool dracoPrimitive(const draco::Mesh& mesh, const draco::PointAttribute* position, const draco::PointAttribute* uv,
                    const draco::PointAttribute* color, bool flip_v, Primitive& prim, std::string& error) {
  const uint32_t points = mesh.num_points();
  if (!position || position->num_components() < 3 || !readDracoAttribute(*position, points, 3, prim.positions)) {
    error = "Draco mesh has no readable 3-component POSITION attribute";
    return false;
  }
  if (uv) {
    if (uv->num_components() < 2 || !readDracoAttribute(*uv, points, 2, prim.uvs)) {
      error = "Draco texture coordinates cannot be read";
      return false;
    }
    if (flip_v) {
      for (size_t i = 1; i < prim.uvs.size(); i += 2) prim.uvs[i] = 1.0f - prim.uvs[i];
    }
  }
  if (color) {
    std::vector<float> values;
    if (color->num_components() < 3 || !readDracoAttribute(*color, points, 4, values)) {
      error = "Draco colours cannot be read";
      return false;
    }
    // Floats and normalized integers are 0..1; other 8-bit values are 0..255, 16-bit 0..65535.
    const bool integral = color->data_type() != draco::DT_FLOAT32 && color->data_type() != draco::DT_FLOAT64;
    const float scale = !integral || color->normalized()         ? 255.0f
                        : color->data_type() == draco::DT_UINT16 ? 1.0f / 257.0f
                                                                 : 1.0f;
    prim.colors.resize(values.size());
    for (size_t i = 0; i < values.size(); ++i) {
      const bool alpha = i % 4 == 3;
      prim.colors[i] = alpha && color->num_components() < 4 ? 255 : toByte(values[i] * scale);
    }
  }
  prim.indices.resize(size_t{3} * mesh.num_faces());
  for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f) {
    const auto& face = mesh.face(f);
    for (int j = 0; j < 3; ++j) prim.indices[3 * size_t{f.value()} + j] = face[j].value();
  }
  return true;
}

Result<Model> loadDrc(const std::string& path) {
  auto bytes = readFileBytes(path);
  if (!bytes.ok()) return bytes.error();
  std::string error;
  bool unsupported = false;
  const auto mesh = decodeDracoMesh(bytes->data(), bytes->size(), error, unsupported);
  if (!mesh) {
    return fileError(unsupported ? ErrorCode::kUnsupported : ErrorCode::kMalformedInput, path, error);
  }
  // Standalone .drc files usually come from OBJ or PLY (draco_encoder), whose uv origin is the
  // bottom-left of the image: flip v.
  Primitive prim;
  if (!dracoPrimitive(*mesh, mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION),
                      mesh->GetNamedAttribute(draco::GeometryAttribute::TEX_COORD),
                      mesh->GetNamedAttribute(draco::GeometryAttribute::COLOR), true, prim, error)) {
    return fileError(ErrorCode::kMalformedInput, path, error);
  }
  Model model;
  model.materials.push_back(Material{"default"});
  if (!prim.colors.empty()) model.materials[0].base_color = {1.0f, 1.0f, 1.0f, 1.0f};
  VKLOC_TRY_STATUS(appendPrimitive(model, prim, path, "Draco mesh"));
  return model;
}

}  // namespace vkloc::model_detail
