// vkloc: ViSP .cao CAD models (vpMbTracker::loadCAOModel); importing whole ViSP image folders
// is io/import.hpp.
//
// The .cao format (ViSP vpMbTracker::loadCAOModel), '#' starts a comment anywhere on a line:
//   V1                                        optional version header (V1 or V2)
//   load("part.cao", t=[x; y; z], tu=[a; b; c])   zero or more includes; the path is relative
//                                             to the including file; t is a translation in
//                                             metres and tu an axis-angle rotation (radians, or
//                                             with a "deg" suffix) placing the part in the
//                                             including file's frame; () and ',' also accepted
//   N  then N lines "x y z" (V2: "x y z i j")    3D points, metres
//   N  then N lines "p0 p1 [name=...]"            3D lines (point indices)
//   N  then N lines "n l0 .. l(n-1) [name=...]"   faces from lines (line indices, chained)
//   N  then N lines "n p0 .. p(n-1) [name=...]"   faces from points
//   N  then N lines "p0 p1 radius"                cylinders (optional section)
//   N  then N lines "radius centre p1 p2"         circles (optional section)
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vkloc/core/pose.hpp"
#include "vkloc/core/status.hpp"
#include "vkloc/model/model.hpp"

namespace vkloc {

/// The geometry of a .cao file with every load() include resolved, in the top file's frame.
struct CaoModel {
  std::vector<Eigen::Vector3d> points;             ///< Object frame, metres.
  std::vector<std::array<uint32_t, 2>> segments;   ///< 3D lines and face edges, point indices.
  std::vector<std::vector<uint32_t>> faces;        ///< Polygons as closed point loops (>= 3 points).
  std::vector<std::string> face_names;             ///< name= of each face, "" when unnamed.
  std::vector<std::vector<uint32_t>> extra_faces;  ///< Cylinder / circle tessellation (triangles).
};

/// Most points (or lines) in one .cao face. Ear clipping is O(n^2) at worst; a face of this
/// many points triangulates in well under a second.
constexpr uint64_t kMaxCaoFacePoints = 4096;

/// Parses a .cao file and its includes. Cylinders become 32-sided open tubes and circles
/// 32-sided discs (both listed in `extra_faces`, with a warning). An include that would load a
/// file already being loaded is skipped with a warning. Returns kNotFound for a missing file and
/// kMalformedInput "file:line: what" for bad content (missing or non-numeric fields, indices out
/// of range, counts above 1e6, faces above kMaxCaoFacePoints points, more than 8e6 non-blank
/// lines, files above 256 MiB, non-finite values, faces with fewer than 3 points or lines that
/// do not form a closed loop).
Result<CaoModel> parseCaoFile(const std::string& path, std::vector<std::string>* warnings = nullptr);

/// Appends `part` to `model`, mapping its points with p_model = T_model_part * p_part.
void appendCaoModel(CaoModel& model, const CaoModel& part, const Pose& T_model_part);

/// Ear-clipping triangulation of a planar (or nearly planar) simple polygon, concave allowed.
/// Time O(n r) for n corners of which r are reflex, O(n^2) at worst, also for loops that touch
/// or cross themselves (triangulated as well as may be).
/// The loop is projected onto its best-fit plane (Newell normal); the triangles keep the loop's
/// winding, so a loop that is counter-clockwise seen from outside gives triangles that are too.
/// Returns 3 indices into `loop` per triangle (n - 2 triangles for n distinct vertices), or an
/// empty vector when the loop has fewer than 3 distinct vertices or zero area.
std::vector<uint32_t> triangulatePolygon(const std::vector<Eigen::Vector3d>& loop);

/// Builds a vkloc Model (one mid-gray material, blocks built) from parsed .cao geometry.
/// Faces keep the file's vertex order: ViSP models are usually counter-clockwise seen from
/// outside, but nothing enforces it, so render them with back-face culling off (the default).
/// kMalformedInput when no face yields a triangle; `source` names the model in messages.
Result<Model> caoToModel(const CaoModel& cao, const std::string& source);

/// parseCaoFile + caoToModel.
Result<Model> loadCaoModel(const std::string& path, std::vector<std::string>* warnings = nullptr);

}  // namespace vkloc
