// ViSP .cao models: parsing with includes, polygon triangulation, conversion to a Model.
#include "vkloc/model/cao.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "model/model_internal.hpp"
#include "vkloc/core/text.hpp"

namespace vkloc {

namespace fs = std::filesystem;
using model_detail::fileError;

namespace {

/// Most points, lines or faces one .cao section may declare (ViSP allows 1e5).
constexpr uint64_t kMaxCaoCount = 1000000;
/// Most corners in one face (ear clipping is O(n^2) at worst: ~0.25 s at this limit).
constexpr uint64_t kMaxFaceVertices = kMaxCaoFacePoints;
/// Most non-blank lines in one file (6 sections of kMaxCaoCount records, includes aside).
constexpr size_t kMaxCaoLines = 8 * kMaxCaoCount;
/// Deepest chain of load() includes.
constexpr int kMaxIncludeDepth = 32;
/// Sides of the tessellated cylinders and circles.
constexpr int kRoundSides = 32;
/// Largest .cao / pose / XML text read, bytes.
constexpr uint64_t kMaxTextBytes = uint64_t{256} << 20;

std::vector<std::string> splitWhitespace(std::string_view s) {
  std::vector<std::string> out;
  for (std::string_view field : text::splitFields(s)) out.emplace_back(field);
  return out;
}

bool parseDouble(std::string_view token, double& value) { return text::parseDouble(token, value).empty(); }

bool parseIndex(std::string_view token, uint64_t& value) { return text::parseUint64(token, value).empty(); }

Result<std::string> readText(const std::string& path) {
  auto bytes = model_detail::readFileBytes(path, kMaxTextBytes);
  if (!bytes.ok()) return bytes.error();
  return std::string(bytes->begin(), bytes->end());
}

/// One meaningful line of a .cao file: comments removed, trimmed, non-empty.
struct CaoLine {
  int number = 0;         ///< 1-based line number in the file.
  std::string_view text;  ///< Content without comments (a view into the file's text).
};

/// The non-blank lines of `text`; false when there are more than kMaxCaoLines.
bool caoLines(std::string_view text, std::vector<CaoLine>& lines) {
  text::LineCursor cursor(text);
  for (std::string_view raw; cursor.next(raw);) {
    // '#' starts a comment anywhere; "//" too when it starts a word (ViSP's examples use it).
    size_t cut = raw.find('#');
    size_t quotes = 0, counted = 0;  // '"' before `counted`.
    for (size_t p = raw.find("//"); p != std::string_view::npos && p < cut; p = raw.find("//", p + 1)) {
      if (p == 0 || std::isspace(static_cast<unsigned char>(raw[p - 1]))) {
        // Keep "//" inside a quoted load() path.
        quotes += static_cast<size_t>(std::count(raw.begin() + static_cast<std::ptrdiff_t>(counted),
                                                 raw.begin() + static_cast<std::ptrdiff_t>(p), '"'));
        counted = p;
        if (quotes % 2 == 0) {
          cut = p;
          break;
        }
      }
    }
    const std::string_view content = text::trim(raw.substr(0, std::min(cut, raw.size())));
    if (content.empty()) continue;
    if (lines.size() >= kMaxCaoLines) return false;
    lines.push_back(CaoLine{static_cast<int>(cursor.number()), content});
  }
  return true;
}

Pose poseFromTranslationAxisAngle(const Eigen::Vector3d& t, const Eigen::Vector3d& tu) {
  Pose T = Pose::Identity();
  const double angle = tu.norm();
  if (angle > 0.0) T.linear() = Eigen::AngleAxisd(angle, tu / angle).toRotationMatrix();
  T.translation() = t;
  return T;
}

/// Value list of `key=[a; b; c]` (or `key=(a, b, c)`) in a load() line; nullopt when absent.
std::optional<std::string> loadParameter(const std::string& line, const std::string& key) {
  for (size_t p = line.find(key); p != std::string::npos; p = line.find(key, p + 1)) {
    if (p > 0 && (std::isalnum(static_cast<unsigned char>(line[p - 1])) || line[p - 1] == '_')) continue;
    size_t q = p + key.size();
    while (q < line.size() && line[q] == ' ') ++q;
    if (q >= line.size() || line[q] != '=') continue;
    ++q;
    while (q < line.size() && line[q] == ' ') ++q;
    if (q >= line.size() || (line[q] != '[' && line[q] != '(')) return std::string();
    const char close = line[q] == '[' ? ']' : ')';
    const size_t e = line.find(close, q + 1);
    if (e == std::string::npos) return std::string();
    return line.substr(q + 1, e - q - 1);
  }
  return std::nullopt;
}

/// Parses "a; b; c" (';' or ',' separated); angles may end in "deg" or "rad".
bool parseVector3(const std::string& text, bool angles, Eigen::Vector3d& out) {
  std::string s = text;
  std::replace(s.begin(), s.end(), ';', ' ');
  std::replace(s.begin(), s.end(), ',', ' ');
  const std::vector<std::string> tokens = splitWhitespace(s);
  if (tokens.size() != 3) return false;
  for (int i = 0; i < 3; ++i) {
    std::string token = tokens[static_cast<size_t>(i)];
    double scale = 1.0;
    if (angles && token.size() > 3 && token.compare(token.size() - 3, 3, "deg") == 0) {
      token.resize(token.size() - 3);
      scale = M_PI / 180.0;
    } else if (angles && token.size() > 3 && token.compare(token.size() - 3, 3, "rad") == 0) {
      token.resize(token.size() - 3);
    }
    double v = 0.0;
    if (!parseDouble(token, v)) return false;
    out[i] = v * scale;
  }
  return true;
}

/// "name=value" from the trailing tokens of a record, or "".
std::string recordName(const std::vector<std::string>& tokens, size_t first) {
  for (size_t i = first; i < tokens.size(); ++i) {
    if (tokens[i].rfind("name=", 0) == 0) {
      std::string name = tokens[i].substr(5);
      name.erase(std::remove(name.begin(), name.end(), '"'), name.end());
      return name;
    }
  }
  return {};
}

/// Orders the endpoints of a face's lines into one closed loop (at each point the first unused
/// line in the face's order). Empty when they do not close. Linear in the number of lines.
std::vector<uint32_t> chainLines(const std::vector<std::array<uint32_t, 2>>& edges) {
  std::vector<uint32_t> loop;
  if (edges.size() < 3) return loop;
  // The lines at each point, in the face's order, and how many of the first are used.
  std::unordered_map<uint32_t, std::pair<size_t, std::vector<uint32_t>>> at;
  for (uint32_t k = 0; k < edges.size(); ++k) {
    at[edges[k][0]].second.push_back(k);
    if (edges[k][1] != edges[k][0]) at[edges[k][1]].second.push_back(k);
  }
  std::vector<bool> used(edges.size(), false);
  used[0] = true;
  loop.push_back(edges[0][0]);
  uint32_t current = edges[0][1];
  for (size_t step = 1; step < edges.size(); ++step) {
    loop.push_back(current);
    auto& [first_unused, lines] = at[current];
    while (first_unused < lines.size() && used[lines[first_unused]]) ++first_unused;
    if (first_unused == lines.size()) return {};
    const uint32_t k = lines[first_unused];
    used[k] = true;
    current = edges[k][0] == current ? edges[k][1] : edges[k][0];
  }
  if (current != loop.front()) return {};
  return loop;
}

struct CaoParser {
  std::vector<std::string>& warnings;
  std::vector<std::string> stack;  ///< Canonical paths of the files being loaded.

  Status parse(const std::string& path, const Pose& T_top_file, CaoModel& out) {
    const std::string display = path;
    if (static_cast<int>(stack.size()) >= kMaxIncludeDepth) {
      return fileError(ErrorCode::kMalformedInput, path, fmt::format("load() nested deeper than {}", kMaxIncludeDepth));
    }
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(path, ec);
    const std::string key = ec ? path : canonical.string();
    auto text = readText(path);
    if (!text.ok()) return text.error();
    stack.push_back(key);
    Status status = parseText(path, *text, T_top_file, out);
    stack.pop_back();
    return status;
  }

  Status parseText(const std::string& path, const std::string& text, const Pose& T, CaoModel& out) {
    std::vector<CaoLine> lines;
    if (!caoLines(text, lines)) {
      return fileError(ErrorCode::kMalformedInput, path, fmt::format("more than {} non-blank lines", kMaxCaoLines));
    }
    size_t li = 0;
    auto lineError = [&](int number, const std::string& what) -> Error {
      return makeError(ErrorCode::kMalformedInput, model_detail::oneLine(fmt::format("{}:{}: {}", path, number, what)));
    };
    auto endError = [&](const std::string& what) -> Error {
      return makeError(ErrorCode::kMalformedInput,
                       model_detail::oneLine(fmt::format("{}: unexpected end of file: {}", path, what)));
    };

    // Version header.
    if (li < lines.size() && (lines[li].text[0] == 'V' || lines[li].text[0] == 'v')) {
      uint64_t version = 0;
      const std::string v = splitWhitespace(lines[li].text)[0].substr(1);
      if (!parseIndex(v, version) || version > 2) {
        return lineError(lines[li].number,
                         fmt::format("unknown version header '{}' (expected V1 or V2)", lines[li].text));
      }
      versionTwo_ = version == 2;
      ++li;
    } else {
      versionTwo_ = false;
    }

    // Includes.
    while (li < lines.size() && (lines[li].text.rfind("load", 0) == 0 || lines[li].text.rfind("LOAD", 0) == 0)) {
      const CaoLine& line = lines[li++];
      const size_t q0 = line.text.find('"');
      const size_t q1 = q0 == std::string::npos ? q0 : line.text.find('"', q0 + 1);
      if (q1 == std::string::npos) return lineError(line.number, "load() needs a quoted file name");
      const std::string rel(line.text.substr(q0 + 1, q1 - q0 - 1));
      const std::string params(line.text.substr(q1 + 1));
      if (rel.empty()) return lineError(line.number, "load() needs a file name");
      if (std::any_of(rel.begin(), rel.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20; })) {
        // A NUL would cut the path short and open the including folder.
        return lineError(line.number, fmt::format("load(): file name {} holds a control character", text::shown(rel)));
      }
      Eigen::Vector3d t = Eigen::Vector3d::Zero(), tu = Eigen::Vector3d::Zero();
      if (auto p = loadParameter(params, "t"); p && !parseVector3(*p, false, t)) {
        return lineError(line.number, "load(): t= needs three numbers, e.g. t=[0.1; 0; 0]");
      }
      if (auto p = loadParameter(params, "tu"); p && !parseVector3(*p, true, tu)) {
        return lineError(line.number, "load(): tu= needs three angles, e.g. tu=[0; 0; 90deg]");
      }
      fs::path child = rel;
      if (child.is_relative()) child = fs::path(path).parent_path() / child;
      std::error_code ec;
      const fs::path canonical = fs::weakly_canonical(child, ec);
      const std::string key = ec ? child.string() : canonical.string();
      if (std::find(stack.begin(), stack.end(), key) != stack.end()) {
        warnings.push_back(text::oneLine(
            fmt::format("{}:{}: load({}) skipped: it includes itself", path, line.number, text::shown(rel))));
        continue;
      }
      if (!fs::exists(child, ec)) {
        return lineError(line.number, fmt::format("load(): file {} not found", child.string()));
      }
      const bool saved = versionTwo_;
      // The include's error names the including file and line too.
      if (const Status included = parse(child.string(), T * poseFromTranslationAxisAngle(t, tu), out); !included.ok()) {
        return lineError(line.number, fmt::format("load({}): {}", text::shown(rel), included.error().message));
      }
      versionTwo_ = saved;
    }

    // A section count: one non-negative integer at the start of a line.
    auto readCount = [&](const char* what, bool optional, uint64_t& count) -> Status {
      if (li >= lines.size()) {
        if (optional) {
          count = 0;
          return Status::success();
        }
        return endError(fmt::format("expected the number of {}", what));
      }
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      if (!parseIndex(tokens[0], count)) {
        return lineError(line.number, fmt::format("expected the number of {}, found {}", what, text::shown(tokens[0])));
      }
      if (count > kMaxCaoCount) {
        return lineError(line.number, fmt::format("{} {} is more than the {} allowed", count, what, kMaxCaoCount));
      }
      return Status::success();
    };

    const uint32_t base = static_cast<uint32_t>(out.points.size());
    uint64_t point_count = 0;
    VKLOC_TRY_STATUS(readCount("points", false, point_count));
    for (uint64_t k = 0; k < point_count; ++k) {
      if (li >= lines.size()) return endError(fmt::format("expected {} points, found {}", point_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      Eigen::Vector3d p;
      for (int c = 0; c < 3; ++c) {
        if (static_cast<size_t>(c) >= tokens.size() || !parseDouble(tokens[static_cast<size_t>(c)], p[c])) {
          return lineError(line.number, fmt::format("point {} needs three finite numbers x y z", k));
        }
      }
      if (out.points.size() >= model_detail::kMaxModelElements) {
        return lineError(line.number, "too many points");
      }
      out.points.push_back(T * p);
    }
    const uint64_t local_points = point_count;
    auto pointIndex = [&](const std::string& token, int number, const char* what, uint32_t& index) -> Status {
      uint64_t v = 0;
      if (!parseIndex(token, v)) return lineError(number, fmt::format("{}: '{}' is not a point index", what, token));
      if (v >= local_points) {
        return lineError(number, fmt::format("{}: point index {} but the file has {} points", what, v, local_points));
      }
      index = base + static_cast<uint32_t>(v);
      return Status::success();
    };

    std::set<std::array<uint32_t, 2>> segment_set;
    auto addSegment = [&](uint32_t a, uint32_t b) {
      if (a == b) return;
      const std::array<uint32_t, 2> s{std::min(a, b), std::max(a, b)};
      if (segment_set.insert(s).second) out.segments.push_back(s);
    };

    uint64_t line_count = 0;
    VKLOC_TRY_STATUS(readCount("lines", false, line_count));
    std::vector<std::array<uint32_t, 2>> file_lines;
    for (uint64_t k = 0; k < line_count; ++k) {
      if (li >= lines.size()) return endError(fmt::format("expected {} lines, found {}", line_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      if (tokens.size() < 2) return lineError(line.number, fmt::format("line {} needs two point indices", k));
      std::array<uint32_t, 2> seg{};
      VKLOC_TRY_STATUS(pointIndex(tokens[0], line.number, "line", seg[0]));
      VKLOC_TRY_STATUS(pointIndex(tokens[1], line.number, "line", seg[1]));
      file_lines.push_back(seg);
      addSegment(seg[0], seg[1]);
    }

    uint64_t line_face_count = 0;
    VKLOC_TRY_STATUS(readCount("faces from lines", false, line_face_count));
    for (uint64_t k = 0; k < line_face_count; ++k) {
      if (li >= lines.size())
        return endError(fmt::format("expected {} faces from lines, found {}", line_face_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      uint64_t n = 0;
      if (!parseIndex(tokens[0], n)) {
        return lineError(line.number, fmt::format("face {}: '{}' is not a line count", k, tokens[0]));
      }
      if (n > kMaxFaceVertices) {
        return lineError(line.number, fmt::format("face {} has {} lines, more than the {} allowed in one face", k, n,
                                                  kMaxFaceVertices));
      }
      if (tokens.size() < n + 1) return lineError(line.number, fmt::format("face {}: expected {} line indices", k, n));
      std::vector<std::array<uint32_t, 2>> edges;
      for (uint64_t i = 0; i < n; ++i) {
        uint64_t v = 0;
        if (!parseIndex(tokens[i + 1], v) || v >= file_lines.size()) {
          return lineError(line.number, fmt::format("face {}: '{}' is not a line index below {}", k, tokens[i + 1],
                                                    file_lines.size()));
        }
        edges.push_back(file_lines[v]);
      }
      std::vector<uint32_t> loop = chainLines(edges);
      if (loop.empty()) {
        // As ViSP does: the line endpoints in the order they are listed.
        std::unordered_set<uint32_t> seen;
        for (const auto& e : edges) {
          for (uint32_t p : e) {
            if (seen.insert(p).second) loop.push_back(p);
          }
        }
        if (loop.size() < 3) {
          return lineError(line.number, fmt::format("face {}: its {} lines touch fewer than 3 points", k, n));
        }
        warnings.push_back(
            fmt::format("{}:{}: face {}: its lines do not form one closed loop; using their "
                        "endpoints in order",
                        path, line.number, k));
      }
      out.faces.push_back(std::move(loop));
      out.face_names.push_back(recordName(tokens, n + 1));
    }

    uint64_t point_face_count = 0;
    VKLOC_TRY_STATUS(readCount("faces from points", false, point_face_count));
    for (uint64_t k = 0; k < point_face_count; ++k) {
      if (li >= lines.size())
        return endError(fmt::format("expected {} faces from points, found {}", point_face_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      uint64_t n = 0;
      if (!parseIndex(tokens[0], n)) {
        return lineError(line.number, fmt::format("face {}: '{}' is not a point count", k, tokens[0]));
      }
      if (n > kMaxFaceVertices) {
        return lineError(line.number, fmt::format("face {} has {} points, more than the {} allowed in one face", k, n,
                                                  kMaxFaceVertices));
      }
      if (n < 3) return lineError(line.number, fmt::format("face {} has {} points; a face needs at least 3", k, n));
      if (tokens.size() < n + 1) return lineError(line.number, fmt::format("face {}: expected {} point indices", k, n));
      std::vector<uint32_t> loop(n);
      for (uint64_t i = 0; i < n; ++i) VKLOC_TRY_STATUS(pointIndex(tokens[i + 1], line.number, "face", loop[i]));
      for (uint64_t i = 0; i < n; ++i) addSegment(loop[i], loop[(i + 1) % n]);
      out.faces.push_back(std::move(loop));
      out.face_names.push_back(recordName(tokens, n + 1));
    }

    uint64_t cylinder_count = 0;
    VKLOC_TRY_STATUS(readCount("cylinders", true, cylinder_count));
    for (uint64_t k = 0; k < cylinder_count; ++k) {
      if (li >= lines.size()) return endError(fmt::format("expected {} cylinders, found {}", cylinder_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      uint32_t a = 0, b = 0;
      double radius = 0.0;
      if (tokens.size() < 3) return lineError(line.number, "cylinder needs: point index, point index, radius");
      VKLOC_TRY_STATUS(pointIndex(tokens[0], line.number, "cylinder", a));
      VKLOC_TRY_STATUS(pointIndex(tokens[1], line.number, "cylinder", b));
      if (!parseDouble(tokens[2], radius) || radius <= 0.0) {
        return lineError(line.number, fmt::format("cylinder radius '{}' is not a positive number", tokens[2]));
      }
      addCylinder(out, out.points[a], out.points[b], radius * scaleOf(T));
    }
    if (cylinder_count > 0) {
      warnings.push_back(
          fmt::format("{}: {} cylinders tessellated as {}-sided open tubes", path, cylinder_count, kRoundSides));
    }

    uint64_t circle_count = 0;
    VKLOC_TRY_STATUS(readCount("circles", true, circle_count));
    for (uint64_t k = 0; k < circle_count; ++k) {
      if (li >= lines.size()) return endError(fmt::format("expected {} circles, found {}", circle_count, k));
      const CaoLine& line = lines[li++];
      const std::vector<std::string> tokens = splitWhitespace(line.text);
      double radius = 0.0;
      uint32_t c = 0, p1 = 0, p2 = 0;
      if (tokens.size() < 4) return lineError(line.number, "circle needs: radius, centre, two points on its plane");
      if (!parseDouble(tokens[0], radius) || radius <= 0.0) {
        return lineError(line.number, fmt::format("circle radius '{}' is not a positive number", tokens[0]));
      }
      VKLOC_TRY_STATUS(pointIndex(tokens[1], line.number, "circle", c));
      VKLOC_TRY_STATUS(pointIndex(tokens[2], line.number, "circle", p1));
      VKLOC_TRY_STATUS(pointIndex(tokens[3], line.number, "circle", p2));
      if (!addCircle(out, out.points[c], out.points[p1], out.points[p2], radius * scaleOf(T))) {
        return lineError(line.number, "circle: the centre and the two points do not span a plane");
      }
    }
    if (circle_count > 0) {
      warnings.push_back(fmt::format("{}: {} circles tessellated as {}-sided discs", path, circle_count, kRoundSides));
    }
    if (li < lines.size()) {
      warnings.push_back(fmt::format("{}:{}: ignored content after the circles section", path, lines[li].number));
    }
    return Status::success();
  }

  static double scaleOf(const Pose& T) { return std::cbrt(std::abs(T.linear().determinant())); }

  static void perpendicularBasis(const Eigen::Vector3d& n, Eigen::Vector3d& u, Eigen::Vector3d& v) {
    const Eigen::Vector3d seed = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    u = n.cross(seed).normalized();
    v = n.cross(u);  // (u, v, n) right-handed.
  }

  /// Open tube between a and b; triangles counter-clockwise seen from outside.
  /// Points are taken by value: callers pass elements of out.points, which push_back moves.
  static void addCylinder(CaoModel& out, const Eigen::Vector3d a, const Eigen::Vector3d b, double r) {
    const Eigen::Vector3d axis = b - a;
    if (axis.norm() <= 0.0) return;
    Eigen::Vector3d u, v;
    perpendicularBasis(axis.normalized(), u, v);
    const uint32_t first = static_cast<uint32_t>(out.points.size());
    for (int k = 0; k < kRoundSides; ++k) {
      const double angle = 2.0 * M_PI * k / kRoundSides;
      const Eigen::Vector3d offset = r * (std::cos(angle) * u + std::sin(angle) * v);
      out.points.push_back(a + offset);
      out.points.push_back(b + offset);
    }
    for (uint32_t k = 0; k < static_cast<uint32_t>(kRoundSides); ++k) {
      const uint32_t k1 = (k + 1) % kRoundSides;
      const uint32_t a0 = first + 2 * k, b0 = a0 + 1, a1 = first + 2 * k1, b1 = a1 + 1;
      out.extra_faces.push_back({a0, a1, b1});
      out.extra_faces.push_back({a0, b1, b0});
    }
  }

  /// Disc of radius r around c in the plane through c, p1, p2. False when they are collinear.
  static bool addCircle(CaoModel& out, const Eigen::Vector3d c, const Eigen::Vector3d p1, const Eigen::Vector3d p2,
                        double r) {
    const Eigen::Vector3d n = (p1 - c).cross(p2 - c);
    if (!(n.norm() > 1e-12)) return false;
    Eigen::Vector3d u, v;
    perpendicularBasis(n.normalized(), u, v);
    const uint32_t centre = static_cast<uint32_t>(out.points.size());
    out.points.push_back(c);
    for (int k = 0; k < kRoundSides; ++k) {
      const double angle = 2.0 * M_PI * k / kRoundSides;
      out.points.push_back(c + r * (std::cos(angle) * u + std::sin(angle) * v));
    }
    for (uint32_t k = 0; k < static_cast<uint32_t>(kRoundSides); ++k) {
      const uint32_t a = centre + 1 + k, b = centre + 1 + (k + 1) % kRoundSides;
      out.extra_faces.push_back({centre, a, b});
      out.segments.push_back({std::min(a, b), std::max(a, b)});
    }
    return true;
  }

  bool versionTwo_ = false;
};

/// Adds every face's edges to the segment list (once per undirected edge).
void addFaceEdges(CaoModel& cao) {
  std::set<std::array<uint32_t, 2>> seen(cao.segments.begin(), cao.segments.end());
  for (const auto& face : cao.faces) {
    for (size_t i = 0; i < face.size(); ++i) {
      const uint32_t a = face[i], b = face[(i + 1) % face.size()];
      if (a == b) continue;
      const std::array<uint32_t, 2> s{std::min(a, b), std::max(a, b)};
      if (seen.insert(s).second) cao.segments.push_back(s);
    }
  }
}

}  // namespace

Result<CaoModel> parseCaoFile(const std::string& path, std::vector<std::string>* warnings) {
  std::vector<std::string> ignored;
  CaoParser parser{warnings ? *warnings : ignored, {}};
  CaoModel out;
  try {
    VKLOC_TRY_STATUS(parser.parse(path, Pose::Identity(), out));
  } catch (const std::bad_alloc&) {
    return fileError(ErrorCode::kMalformedInput, path, "out of memory while parsing");
  } catch (const std::exception& e) {
    return fileError(ErrorCode::kMalformedInput, path, std::string("cannot parse: ") + e.what());
  }
  addFaceEdges(out);
  return out;
}

void appendCaoModel(CaoModel& model, const CaoModel& part, const Pose& T_model_part) {
  const uint32_t base = static_cast<uint32_t>(model.points.size());
  for (const auto& p : part.points) model.points.push_back(T_model_part * p);
  for (const auto& s : part.segments) model.segments.push_back({s[0] + base, s[1] + base});
  for (const auto& f : part.faces) {
    model.faces.emplace_back(f);
    for (auto& i : model.faces.back()) i += base;
  }
  model.face_names.insert(model.face_names.end(), part.face_names.begin(), part.face_names.end());
  for (const auto& f : part.extra_faces) {
    model.extra_faces.emplace_back(f);
    for (auto& i : model.extra_faces.back()) i += base;
  }
}

std::vector<uint32_t> triangulatePolygon(const std::vector<Eigen::Vector3d>& loop) {
  std::vector<uint32_t> out;
  // Distinct consecutive vertices (a closing duplicate of the first is dropped too).
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < loop.size(); ++i) {
    if (!loop[i].allFinite()) return out;
    if (!ids.empty() && loop[i] == loop[ids.back()]) continue;
    ids.push_back(i);
  }
  while (ids.size() > 1 && loop[ids.front()] == loop[ids.back()]) ids.pop_back();
  if (ids.size() < 3) return out;

  // Newell normal: its length is twice the area, its direction the loop's orientation.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < ids.size(); ++i) {
    const Eigen::Vector3d& a = loop[ids[i]];
    const Eigen::Vector3d& b = loop[ids[(i + 1) % ids.size()]];
    normal += Eigen::Vector3d((a.y() - b.y()) * (a.z() + b.z()), (a.z() - b.z()) * (a.x() + b.x()),
                              (a.x() - b.x()) * (a.y() + b.y()));
  }
  double extent = 0.0;
  for (uint32_t i : ids) extent = std::max(extent, (loop[i] - loop[ids[0]]).norm());
  if (!(normal.norm() > 1e-12 * extent * extent) || extent == 0.0) return out;
  const Eigen::Vector3d n = normal.normalized();
  const Eigen::Vector3d seed = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = n.cross(seed).normalized();
  const Eigen::Vector3d v = n.cross(u);  // (u, v, n) right-handed: the loop is counter-clockwise in (u, v).
  std::vector<Eigen::Vector2d> p2(loop.size());
  for (uint32_t i : ids) {
    const Eigen::Vector3d d = loop[i] - loop[ids[0]];
    p2[i] = Eigen::Vector2d(d.dot(u), d.dot(v)) / extent;
  }
  const double eps = 1e-12;
  auto inside = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t q) {
    // q inside or on the boundary of the counter-clockwise triangle abc.
    auto side = [&](uint32_t s, uint32_t e) {
      const Eigen::Vector2d se = p2[e] - p2[s], sq = p2[q] - p2[s];
      return se.x() * sq.y() - se.y() * sq.x();
    };
    return side(a, b) >= -eps && side(b, c) >= -eps && side(c, a) >= -eps;
  };

  // Ear clipping over a linked list of the m corners, with each corner's ear status kept and
  // re-tested only when its neighbours change; an ear test looks at reflex (or flat) corners
  // only, since in a simple polygon a triangle with a vertex inside also has a reflex one
  // inside. Work O(m r) for r reflex corners, O(m^2) at worst.
  const auto m = static_cast<uint32_t>(ids.size());
  std::vector<Eigen::Vector2d> q(m);
  for (uint32_t k = 0; k < m; ++k) q[k] = p2[ids[k]];
  std::vector<uint32_t> prev(m), next(m);
  for (uint32_t k = 0; k < m; ++k) {
    prev[k] = (k + m - 1) % m;
    next[k] = (k + 1) % m;
  }
  std::vector<char> removed(m, 0), ear(m, 0), listed(m, 0);
  uint32_t remaining = m;
  auto turn = [&](uint32_t k) {
    const Eigen::Vector2d ab = q[k] - q[prev[k]], bc = q[next[k]] - q[k];
    return ab.x() * bc.y() - ab.y() * bc.x();
  };
  auto straight = [&](uint32_t k) {
    return std::abs(turn(k)) <= eps && (q[k] - q[prev[k]]).dot(q[next[k]] - q[k]) >= 0.0;
  };
  auto unlink = [&](uint32_t k) {
    next[prev[k]] = next[k];
    prev[next[k]] = prev[k];
    removed[k] = 1;
    --remaining;
  };
  std::vector<uint32_t> reflex;  // Corners that may lie inside an ear (lazily pruned).
  auto noteReflex = [&](uint32_t k) {
    if (!listed[k] && turn(k) <= eps) {
      listed[k] = 1;
      reflex.push_back(k);
    }
  };
  uint64_t work = 0;  // Corner-in-triangle tests, bounded by `budget` for full re-tests.
  const uint64_t budget = 2 * uint64_t{m} * m + 1024;
  auto isEar = [&](uint32_t k) {
    if (turn(k) <= eps) return false;  // Reflex or degenerate corner.
    const uint32_t a = prev[k], c = next[k];
    for (const uint32_t r : reflex) {
      ++work;
      if (removed[r] || r == a || r == k || r == c) continue;
      if (q[r] == q[a] || q[r] == q[k] || q[r] == q[c]) continue;
      if (inside(ids[a], ids[k], ids[c], ids[r])) return false;
    }
    return true;
  };
  std::vector<uint32_t> ears;     // Stack of corners that were ears when pushed.
  std::vector<uint32_t> touched;  // Corners whose neighbours changed.
  // Drops flat corners among `touched` (and the corners next to each one dropped), then
  // re-tests the ear status of those that stay.
  auto settle = [&]() {
    for (size_t i = 0; i < touched.size() && remaining > 3; ++i) {
      const uint32_t k = touched[i];
      if (removed[k] || !straight(k)) continue;
      touched.push_back(prev[k]);
      touched.push_back(next[k]);
      unlink(k);
    }
    for (const uint32_t k : touched) {
      if (removed[k]) continue;
      noteReflex(k);
      ear[k] = isEar(k) ? 1 : 0;
      if (ear[k]) ears.push_back(k);
    }
    touched.clear();
    if (reflex.size() > 2 * size_t{remaining} + 64) {
      reflex.erase(std::remove_if(reflex.begin(), reflex.end(), [&](uint32_t r) { return removed[r] != 0; }),
                   reflex.end());
    }
  };
  auto clip = [&](uint32_t k, bool emit) {
    if (emit) out.insert(out.end(), {ids[prev[k]], ids[k], ids[next[k]]});
    touched.push_back(prev[k]);
    touched.push_back(next[k]);
    unlink(k);
    settle();
  };

  for (uint32_t k = 0; k < m; ++k) touched.push_back(k);
  for (uint32_t k = 0; k < m; ++k) noteReflex(k);
  settle();
  uint32_t any = 0;  // A corner still in the list.
  while (remaining > 3) {
    uint32_t k = m;
    while (!ears.empty() && k == m) {
      const uint32_t candidate = ears.back();
      ears.pop_back();
      if (!removed[candidate] && ear[candidate]) k = candidate;
    }
    if (k != m) {
      clip(k, true);
      continue;
    }
    while (removed[any]) ++any;
    if (work < budget) {
      // No known ear (the loop touches or crosses itself): re-test every corner once.
      uint32_t j = any;
      do {
        ear[j] = isEar(j) ? 1 : 0;
        if (ear[j]) ears.push_back(j);
        j = next[j];
      } while (j != any);
      if (!ears.empty()) continue;
    }
    // Self-intersecting or otherwise degenerate loop: clip the most convex corner.
    uint32_t best = any;
    double best_turn = -1e300;
    uint32_t j = any;
    do {
      const double t = turn(j);
      if (t > best_turn) {
        best_turn = t;
        best = j;
      }
      j = next[j];
    } while (j != any);
    clip(best, best_turn > eps);
  }
  while (removed[any]) ++any;
  if (remaining == 3 && turn(next[any]) > eps) out.insert(out.end(), {ids[any], ids[next[any]], ids[next[next[any]]]});
  return out;
}

Result<Model> caoToModel(const CaoModel& cao, const std::string& source) {
  std::vector<uint32_t> triangles;  // Indices into cao.points.
  for (const auto& face : cao.faces) {
    std::vector<Eigen::Vector3d> loop;
    for (uint32_t i : face) {
      if (i >= cao.points.size()) return fileError(ErrorCode::kMalformedInput, source, "face index out of range");
      loop.push_back(cao.points[i]);
    }
    for (uint32_t local : triangulatePolygon(loop)) triangles.push_back(face[local]);
  }
  for (const auto& tri : cao.extra_faces) {
    for (uint32_t i : tri) {
      if (i >= cao.points.size()) return fileError(ErrorCode::kMalformedInput, source, "face index out of range");
    }
    if (tri.size() == 3) triangles.insert(triangles.end(), tri.begin(), tri.end());
  }
  if (triangles.empty()) {
    return fileError(ErrorCode::kMalformedInput, source, "the model has no faces with a non-zero area");
  }
  // Only the points used by triangles become vertices.
  std::vector<uint32_t> remap(cao.points.size(), UINT32_MAX);
  model_detail::Primitive prim;
  for (uint32_t& i : triangles) {
    if (remap[i] == UINT32_MAX) {
      remap[i] = static_cast<uint32_t>(prim.positions.size() / 3);
      for (int c = 0; c < 3; ++c) prim.positions.push_back(static_cast<float>(cao.points[i][c]));
    }
    prim.indices.push_back(remap[i]);
  }
  Model model;
  model.source = source;
  Material gray;
  gray.name = "cao_gray";
  gray.base_color = {0.5f, 0.5f, 0.5f, 1.0f};
  model.materials.push_back(gray);
  VKLOC_TRY_STATUS(model_detail::appendPrimitive(model, prim, source, "faces"));
  buildBlocks(model, ModelLoadOptions{}.max_block_triangles);
  VKLOC_TRY_STATUS(validateModel(model));
  return model;
}

Result<Model> loadCaoModel(const std::string& path, std::vector<std::string>* warnings) {
  auto cao = parseCaoFile(path, warnings);
  if (!cao.ok()) return cao.error();
  return caoToModel(*cao, path);
}

}  // namespace vkloc
