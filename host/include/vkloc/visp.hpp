// vkloc: reading ViSP model-based tracking data (.cao CAD models, cMo pose files, camera XML)
// and converting a ViSP image folder (e.g. visp-images-data's mbt-depth/Castle-simu) into a
// vkloc sequence.
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

#include "vkloc/camera.hpp"
#include "vkloc/model.hpp"
#include "vkloc/pose.hpp"
#include "vkloc/sequence.hpp"
#include "vkloc/status.hpp"

namespace vkloc {

/// The geometry of a .cao file with every load() include resolved, in the top file's frame.
struct CaoModel {
  std::vector<Eigen::Vector3d> points;             ///< Object frame, metres.
  std::vector<std::array<uint32_t, 2>> segments;   ///< 3D lines and face edges, point indices.
  std::vector<std::vector<uint32_t>> faces;        ///< Polygons as closed point loops (>= 3 points).
  std::vector<std::string> face_names;             ///< name= of each face, "" when unnamed.
  std::vector<std::vector<uint32_t>> extra_faces;  ///< Cylinder / circle tessellation (triangles).
};

/// Parses a .cao file and its includes. Cylinders become 32-sided open tubes and circles
/// 32-sided discs (both listed in `extra_faces`, with a warning). An include that would load a
/// file already being loaded is skipped with a warning. Returns kNotFound for a missing file and
/// kMalformedInput "file:line: what" for bad content (missing or non-numeric fields, indices out
/// of range, counts above 1e6, non-finite values, faces with fewer than 3 points or lines that
/// do not form a closed loop).
Result<CaoModel> parseCaoFile(const std::string& path, std::vector<std::string>* warnings = nullptr);

/// Appends `part` to `model`, mapping its points with p_model = T_model_part * p_part.
void appendCaoModel(CaoModel& model, const CaoModel& part, const Pose& T_model_part);

/// Ear-clipping triangulation of a planar (or nearly planar) simple polygon, concave allowed.
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

/// Reads a ViSP pose file: a 4x4 homogeneous matrix as 16 numbers (row-major, e.g. the
/// Camera_NNN.txt files holding cMo = T_camera_object, metres). The rotation must be orthonormal
/// to 1e-4 (it is then re-orthonormalised) and the last row 0 0 0 1. kNotFound / kMalformedInput
/// with the file name otherwise.
Result<Pose> loadVispPose(const std::string& path);

/// Reads pinhole intrinsics px, py, u0, v0 from a ViSP camera XML (vpXmlParserCamera, preferring
/// the model of type perspectiveProjWithoutDistortion) or a model-based tracker config XML
/// (<camera><px>..). u = u0 + px x/z, v = v0 + py y/z. `width` / `height` (pixels) give the
/// image size; when <= 0 they are read from <image_width> / <image_height>. Errors name the file
/// and the missing or bad tag.
Result<PinholeCamera> loadVispCameraXml(const std::string& path, int width = 0, int height = 0);

/// How a ViSP image folder is converted.
struct VispImportOptions {
  /// Add Models/cube.cao to the model, placed with T_object_cube (visp-images-data's
  /// Castle-simu scene contains this cube; ViSP's depth-tracker test loads it with this pose).
  bool include_cube = true;
  /// Cube frame into the object (world) frame, metres.
  Pose T_object_cube = defaultCastleCubePose();
  /// Timestamp of image number n (Image_NNNN): (n - first) / frame_rate_hz seconds.
  double frame_rate_hz = 30.0;
  /// Name of the written model file inside the output folder (.obj keeps the gray material).
  std::string model_file = "model.obj";

  /// [[-1,0,0,-0.2],[0,0,1,0.12],[0,1,0,-0.15]]: the cube's pose in the castle scene.
  static Pose defaultCastleCubePose();
};

/// What importVispSequence wrote.
struct VispImportReport {
  size_t frames = 0;          ///< Images written.
  size_t poses = 0;           ///< Ground-truth poses written.
  size_t triangles = 0;       ///< Model triangles.
  size_t cube_triangles = 0;  ///< Of which from the cube.
  std::string model_path;     ///< Model file written.
  std::vector<std::string> warnings;
};

/// Converts a ViSP mbt folder laid out as Castle-simu (Images/Image_NNNN.pgm or .png,
/// CameraPose/Camera_NNN.txt, Config/<one>.xml with the intrinsics, Models/<one>.cao other than
/// cube.cao, optional Models/cube.cao) into a vkloc sequence in `out_dir`: the images are
/// converted to PNG under images/, the model (castle plus cube) is written as
/// options.model_file, and ground truth T_world_camera = inverse(cMo) with world = the model's
/// object frame. Gravity is -y in that frame (the castle's up axis is +y). Errors (one line,
/// naming the file): kNotFound for a missing folder/file, kMalformedInput for bad content.
Result<Sequence> importVispSequence(const std::string& folder, const std::string& out_dir,
                                    const VispImportOptions& options = {}, VispImportReport* report = nullptr);

}  // namespace vkloc
