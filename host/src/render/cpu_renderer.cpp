// CPU reference renderer: the test oracle for the GPU renderer.
//
// Conventions, shared with the GPU renderer (see render.hpp and camera.hpp):
//  - Camera frame x right, y down, z forward. Pixel (i, j) is sampled at its centre, which has
//    pinhole coordinates (u, v) = (i, j), u = fx x / z + cx, v = fy y / z + cy. In Vulkan
//    framebuffer coordinates the same point is (i + 0.5, j + 0.5) = (u + 0.5, v + 0.5).
//  - Triangles are clipped against the camera-frame plane z = near (Sutherland-Hodgman, giving
//    0, 1 or 2 triangles); the far plane is a per-pixel test: depth > far is background.
//  - Coverage: edge functions in double at pixel centres with the top-left fill rule, so a
//    pixel centre exactly on an edge shared by two triangles is covered exactly once.
//  - Depth test: strictly nearer camera z wins, so of equal depths the first drawn stays.
//  - Attributes (uv, vertex colour) are interpolated perspective-correctly; depth is the exact
//    camera z of the triangle's plane along the pixel's ray.
//  - Textures are sampled trilinearly from a mip chain (buildMipLevels) with REPEAT wrapping, as
//    Vulkan does with mipmapMode LINEAR, minLod 0 and no maxLod clamp. The level of detail is
//    per 2 x 2 pixel quad, as GPUs compute it: with (s, t) the interpolated uv in level-0 texels
//    (s = u_tex width, t = v_tex height) at the quad's pixel centres (x0, y0), (x0 + 1, y0),
//    (x0, y0 + 1) (x0, y0 even; the plane equations extend outside the triangle as helper
//    invocations do),
//        rho_x = |(s, t)(x0 + 1, y0) - (s, t)(x0, y0)|,  rho_y = |(s, t)(x0, y0 + 1) - (s, t)(x0, y0)|,
//        lambda = log2(max(rho_x, rho_y))   (Vulkan spec, "Scale Factor Operation", with coarse
//    derivatives). lambda <= 0 samples level 0 bilinearly (magnification); otherwise levels
//    floor(lambda) and floor(lambda) + 1 are sampled bilinearly and blended by lambda's fraction,
//    and lambda beyond the last level samples the last level.
//
// Winding and back faces. Model triangles (a, b, c) are counter-clockwise seen from outside,
// i.e. the outward normal is n = (b - a) x (c - a). A rigid transform (det R = +1) preserves
// cross products, so in the camera frame n_c = (b_c - a_c) x (c_c - a_c), and the triangle is
// seen from its front (outside) exactly when the camera centre lies on the side n_c points to:
//     front  <=>  n_c . (0 - a_c) > 0  <=>  det[a_c b_c c_c] = a_c . (b_c x c_c) < 0.
// With q = p / z = (x/z, y/z, 1), det[a b c] = z_a z_b z_c det[q_a q_b q_c], and in pixels
// (u = fx x/z + cx, v = fy y/z + cy) the signed area
//     A = (u_b - u_a)(v_c - v_a) - (u_c - u_a)(v_b - v_a) = fx fy det[q_a q_b q_c],
// so for vertices in front of the camera (z > 0, fx, fy > 0):
//     front-facing  <=>  A < 0.
// A < 0 with u right and v down is a triangle that looks counter-clockwise on the screen as
// displayed (v down): a CCW-from-outside triangle keeps its CCW look in the image; it is
// "clockwise" only if (u, v) are read as a y-up Cartesian frame. Vulkan's polygon area is
// a = -1/2 sum(x_i y_{i+1} - x_{i+1} y_i) = -A / 2 in framebuffer coordinates (a translation of
// (u, v)), so with projectionMatrix() (no y flip) the GPU equivalent is
// VK_FRONT_FACE_COUNTER_CLOCKWISE with VK_CULL_MODE_BACK_BIT. Clipping keeps vertex order and
// all clipped vertices have z >= near > 0, so the test is decided once per triangle from the
// camera-frame determinant; zero-area (edge-on) triangles cover no pixel either way.
#include "vkloc/render/cpu_renderer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "vkloc/render/mipmap.hpp"

namespace vkloc {
namespace {

/// Interpolated vertex attributes: texture u, v, then vertex colour r, g, b (0..1).
constexpr int kAttributeCount = 5;

/// A triangle corner in the camera frame with its interpolated attributes.
struct ClipVertex {
  Eigen::Vector3d p;                                ///< Camera frame, metres.
  std::array<double, kAttributeCount> attribute{};  ///< See kAttributeCount.
};

/// A projected corner in pixel coordinates.
struct ScreenVertex {
  double u = 0;
  double v = 0;
};

/// One triangle edge with its endpoints in a canonical (lexicographic) order, so that two
/// triangles sharing the edge evaluate bit-identical edge functions, and the sign and
/// top-left flag that turn it into this triangle's inside test.
struct Edge {
  double pu = 0, pv = 0;  ///< Canonical start point.
  double du = 0, dv = 0;  ///< Canonical direction (end - start).
  double sign = 1;        ///< +1 or -1: makes the value positive inside the triangle.
  bool top_left = false;  ///< A centre exactly on the edge (value 0) is inside.

  double eval(double u, double v) const { return sign * (du * (v - pv) - dv * (u - pu)); }
};

/// Signed area term A (twice the area) of the projected triangle, u right, v down.
double signedArea(const ScreenVertex& a, const ScreenVertex& b, const ScreenVertex& c) {
  return (b.u - a.u) * (c.v - a.v) - (c.u - a.u) * (b.v - a.v);
}

/// Builds the edge from `from` to `to` of a triangle with signed area `area` (nonzero).
Edge makeEdge(const ScreenVertex& from, const ScreenVertex& to, double area) {
  const bool forward = from.u < to.u || (from.u == to.u && from.v < to.v);
  const ScreenVertex& p = forward ? from : to;
  const ScreenVertex& q = forward ? to : from;
  Edge e;
  e.pu = p.u;
  e.pv = p.v;
  e.du = q.u - p.u;
  e.dv = q.v - p.v;
  // The directed edge function E(s) = (to - from) x (s - from) equals the signed area of
  // (from, to, s): it has the sign of `area` inside the triangle.
  const double direction = forward ? 1.0 : -1.0;
  const double inside = area > 0 ? 1.0 : -1.0;
  e.sign = direction * inside;
  // Top-left rule in the orientation where inside is positive (A > 0, which looks clockwise
  // on screen with v down): walking the edge in that order, a "left" edge goes up (dv < 0)
  // and a "top" edge is horizontal going right (dv == 0, du > 0).
  const double wu = (to.u - from.u) * inside;
  const double wv = (to.v - from.v) * inside;
  e.top_left = wv < 0 || (wv == 0 && wu > 0);
  return e;
}

/// v / 255.0 for every byte v (the same quotients, looked up instead of divided per texel).
const std::array<double, 256> kByteUnit = [] {
  std::array<double, 256> unit{};
  for (int v = 0; v < 256; ++v) unit[static_cast<size_t>(v)] = v / 255.0;
  return unit;
}();

/// Bilinear texture lookup with REPEAT wrap; texel k's centre is at uv = (k + 0.5) / size
/// and (0, 0) is the top-left of the image. Writes 0..1 RGB.
void sampleBilinearRepeat(const Texture& tex, double s, double t, double rgb[3]) {
  if (!std::isfinite(s)) s = 0;
  if (!std::isfinite(t)) t = 0;
  double x = s * tex.width - 0.5;
  double y = t * tex.height - 0.5;
  if (!std::isfinite(x)) x = -0.5;  // a finite uv so large that it overflows: as uv 0
  if (!std::isfinite(y)) y = -0.5;
  const double x0 = std::floor(x);
  const double y0 = std::floor(y);
  const double ax = x - x0;
  const double ay = y - y0;
  // k is a whole number; k mod n in 0..n-1 (in integers where k fits, as it does for any uv a
  // model holds in practice).
  auto wrap = [](double k, int n) {
    if (std::abs(k) < 1e15) {
      const int64_t m = static_cast<int64_t>(k) % n;
      return static_cast<int>(m < 0 ? m + n : m);
    }
    double m = std::fmod(k, static_cast<double>(n));
    if (m < 0) m += n;
    const int i = static_cast<int>(m);
    return i >= n ? 0 : i;
  };
  const int xa = wrap(x0, tex.width);
  const int xb = wrap(x0 + 1, tex.width);
  const int ya = wrap(y0, tex.height);
  const int yb = wrap(y0 + 1, tex.height);
  auto texel = [&](int xi, int yi, int channel) -> double {
    return kByteUnit[tex.rgba[(static_cast<size_t>(yi) * tex.width + xi) * 4 + channel]];
  };
  for (int ch = 0; ch < 3; ++ch) {
    rgb[ch] = (1 - ay) * ((1 - ax) * texel(xa, ya, ch) + ax * texel(xb, ya, ch)) +
              ay * ((1 - ax) * texel(xa, yb, ch) + ax * texel(xb, yb, ch));
  }
}

/// Trilinear lookup with REPEAT wrap at level of detail `lambda` = log2(rho) (see the file
/// comment; 0 where rho is 0 or not finite), rho the pixel footprint in level-0 texels;
/// levels[k] is mip level k + 1 of `base`.
void sampleTrilinearRepeat(const Texture& base, const std::vector<Texture>& levels, double s, double t, double lambda,
                           double rgb[3]) {
  if (!(lambda > 0) || levels.empty()) {
    sampleBilinearRepeat(base, s, t, rgb);
    return;
  }
  const int last = static_cast<int>(levels.size());
  auto level = [&](int l) -> const Texture& { return l == 0 ? base : levels[static_cast<size_t>(l - 1)]; };
  if (lambda >= last) {
    sampleBilinearRepeat(level(last), s, t, rgb);
    return;
  }
  const int d = static_cast<int>(std::floor(lambda));
  const double f = lambda - d;
  double hi[3], lo[3];
  sampleBilinearRepeat(level(d), s, t, hi);
  sampleBilinearRepeat(level(d + 1), s, t, lo);
  for (int ch = 0; ch < 3; ++ch) rgb[ch] = (1 - f) * hi[ch] + f * lo[ch];
}

/// Checks what the rasterizer indexes: attribute sizes, indices, ranges, blocks, materials,
/// textures, finite positions and uvs. Returns a one-line message, empty when fine.
std::string checkModel(const Model& m) {
  if (m.positions.size() % 3 != 0) return "model: positions size is not a multiple of 3";
  if (m.indices.size() % 3 != 0) return "model: index count is not a multiple of 3";
  const size_t nv = m.vertexCount();
  if (!m.uvs.empty() && m.uvs.size() != nv * 2) return "model: uvs size does not match the vertex count";
  if (!m.colors.empty() && m.colors.size() != nv * 4) {
    return "model: colors size does not match the vertex count";
  }
  for (size_t i = 0; i < m.positions.size(); ++i) {
    if (!std::isfinite(m.positions[i])) return fmt::format("model: vertex {} is not finite", i / 3);
  }
  for (size_t i = 0; i < m.uvs.size(); ++i) {
    if (!std::isfinite(m.uvs[i])) return fmt::format("model: uv of vertex {} is not finite", i / 2);
  }
  for (size_t i = 0; i < m.indices.size(); ++i) {
    if (m.indices[i] >= nv) {
      return fmt::format("model: index {} = {} is out of range ({} vertices)", i, m.indices[i], nv);
    }
  }
  for (size_t r = 0; r < m.ranges.size(); ++r) {
    const DrawRange& dr = m.ranges[r];
    if (dr.index_count % 3 != 0 || static_cast<uint64_t>(dr.first_index) + dr.index_count > m.indices.size()) {
      return fmt::format("model: draw range {} lies outside the index buffer", r);
    }
    if (!m.materials.empty() && (dr.material < 0 || dr.material >= static_cast<int>(m.materials.size()))) {
      return fmt::format("model: draw range {} uses missing material {}", r, dr.material);
    }
  }
  for (size_t b = 0; b < m.blocks.size(); ++b) {
    const Block& bl = m.blocks[b];
    if (static_cast<uint64_t>(bl.first_range) + bl.range_count > m.ranges.size()) {
      return fmt::format("model: block {} refers to missing draw ranges", b);
    }
  }
  for (size_t k = 0; k < m.materials.size(); ++k) {
    const int t = m.materials[k].texture;
    if (t < 0) continue;
    if (t >= static_cast<int>(m.textures.size())) {
      return fmt::format("model: material {} uses missing texture {}", k, t);
    }
    const Texture& tex = m.textures[t];
    if (tex.width <= 0 || tex.height <= 0 || tex.rgba.size() != static_cast<size_t>(tex.width) * tex.height * 4) {
      return fmt::format("model: texture {} ('{}') has inconsistent size", t, tex.name);
    }
  }
  return {};
}

/// The rasterizer state for one render.
class Rasterizer {
 public:
  /// `mip_levels[k]` holds levels 1.. of model.textures[k] (buildMipLevels) for every texture a
  /// material uses.
  /// Draws rows [row_begin, row_end) of the output (row_begin even: a 2 x 2 quad stays in one
  /// band); `p_camera` holds the model's vertices in the camera frame.
  Rasterizer(const Model& model, const std::vector<std::vector<Texture>>& mip_levels, const PinholeCamera& camera,
             const RenderSettings& settings, const std::vector<Eigen::Vector3d>& p_camera, int row_begin, int row_end,
             RenderOutput& out)
      : model_(model),
        mip_levels_(mip_levels),
        cam_(camera),
        settings_(settings),
        out_(out),
        shade_((settings.outputs & kRenderColor) != 0),
        row_begin_(row_begin),
        row_end_(row_end),
        band_offset_(static_cast<size_t>(row_begin) * camera.width),
        winner_(shade_ ? static_cast<size_t>(camera.width) * (row_end - row_begin) : 0, -1),
        p_camera_(p_camera),
        depth_(static_cast<size_t>(camera.width) * (row_end - row_begin), std::numeric_limits<double>::infinity()) {}

  /// Draws triangles [first, first + count) of the index buffer with one material.
  void drawRange(uint32_t first_index, uint32_t index_count, const Material& material) {
    TextureRef tex;
    if (material.texture >= 0) {
      tex.base = &model_.textures[static_cast<size_t>(material.texture)];
      tex.levels = &mip_levels_[static_cast<size_t>(material.texture)];
    }
    const std::array<double, 3> base = {material.base_color[0], material.base_color[1], material.base_color[2]};
    for (uint32_t k = 0; k + 3 <= index_count; k += 3) {
      const uint32_t* t = &model_.indices[first_index + k];
      drawTriangle(t[0], t[1], t[2], tex, base);
    }
  }

  /// Shades the pixels (colour asked for) and writes the double depth buffer into the float
  /// output.
  void finish() {
    if (shade_) shadeWinners();
    for (size_t i = 0; i < depth_.size(); ++i) {
      out_.depth.data[band_offset_ + i] = std::isfinite(depth_[i]) ? static_cast<float>(depth_[i]) : kBackgroundDepth;
    }
  }

 private:
  /// A material's texture: level 0 and the levels below it; base null when untextured.
  struct TextureRef {
    const Texture* base = nullptr;
    const std::vector<Texture>* levels = nullptr;
  };

  /// What colouring a pixel of one rasterized triangle needs (shadeWinners).
  struct Shading {
    Edge edge[3];
    double inv_z[3];
    std::array<double, kAttributeCount> attribute[3];  ///< Of corners a, b, c.
    TextureRef tex;
    std::array<double, 3> base;
  };

  /// Perspective-correct texture coordinates in level-0 texels at any point of the triangle's
  /// plane (inside or not); false where the point's ray misses the plane's front.
  static bool texelsAt(const Shading& sh, double pu, double pv, double st[2]) {
    double wk[3];
    double w_sum = 0;
    for (int k = 0; k < 3; ++k) {
      wk[k] = sh.edge[k].eval(pu, pv) * sh.inv_z[k];
      w_sum += wk[k];
    }
    if (!(w_sum > 0)) return false;
    st[0] = (wk[0] * sh.attribute[0][0] + wk[1] * sh.attribute[1][0] + wk[2] * sh.attribute[2][0]) / w_sum *
            sh.tex.base->width;
    st[1] = (wk[0] * sh.attribute[0][1] + wk[1] * sh.attribute[1][1] + wk[2] * sh.attribute[2][1]) / w_sum *
            sh.tex.base->height;
    return std::isfinite(st[0]) && std::isfinite(st[1]);
  }

  ClipVertex vertex(uint32_t index) const {
    ClipVertex c;
    c.p = p_camera_[index];
    if (!model_.uvs.empty()) {  // Without uvs a texture is sampled at uv (0, 0).
      c.attribute[0] = model_.uvs[2 * static_cast<size_t>(index)];
      c.attribute[1] = model_.uvs[2 * static_cast<size_t>(index) + 1];
    }
    for (int ch = 0; ch < 3; ++ch) {
      c.attribute[2 + ch] = model_.colors.empty() ? 1.0 : model_.colors[4 * static_cast<size_t>(index) + ch] / 255.0;
    }
    return c;
  }

  void drawTriangle(uint32_t ia, uint32_t ib, uint32_t ic, const TextureRef& tex, const std::array<double, 3>& base) {
    const ClipVertex tri[3] = {vertex(ia), vertex(ib), vertex(ic)};
    // Face normal and plane (camera frame) of the whole triangle; see the file comment.
    const Eigen::Vector3d n = (tri[1].p - tri[0].p).cross(tri[2].p - tri[0].p);
    const double plane_d = n.dot(tri[0].p);  // n . p for points p on the plane.
    if (settings_.cull_back_faces && !(plane_d < 0)) return;
    const double n_norm = n.norm();
    if (!(n_norm > 0) || !std::isfinite(n_norm)) return;  // Degenerate: covers nothing.
    // Orient towards the camera: n . p < 0 on the surface.
    const Eigen::Vector3f normal = ((plane_d > 0 ? -1.0 : 1.0) / n_norm * n).cast<float>();

    // Sutherland-Hodgman against z >= near. A new vertex on an edge is always interpolated
    // from the inside endpoint towards the outside one, so both triangles sharing the edge get
    // the bit-identical vertex (no cracks).
    const double near = settings_.near_m;
    ClipVertex poly[4];
    int count = 0;
    for (int k = 0; k < 3; ++k) {
      const ClipVertex& a = tri[k];
      const ClipVertex& b = tri[(k + 1) % 3];
      const bool a_in = a.p.z() >= near;
      const bool b_in = b.p.z() >= near;
      if (a_in) poly[count++] = a;
      if (a_in != b_in) {
        const ClipVertex& in = a_in ? a : b;
        const ClipVertex& outv = a_in ? b : a;
        const double t = (near - in.p.z()) / (outv.p.z() - in.p.z());
        ClipVertex c;
        c.p = in.p + t * (outv.p - in.p);
        c.p.z() = near;
        for (int m = 0; m < kAttributeCount; ++m) {
          c.attribute[m] = in.attribute[m] + t * (outv.attribute[m] - in.attribute[m]);
        }
        poly[count++] = c;
      }
    }
    if (count < 3) return;
    for (int k = 1; k + 1 < count; ++k) {
      rasterize(poly[0], poly[k], poly[k + 1], n, plane_d, normal, tex, base);
    }
  }

  /// Rasterizes one triangle with all vertices at z >= near.
  void rasterize(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c, const Eigen::Vector3d& plane_n,
                 double plane_d, const Eigen::Vector3f& normal, const TextureRef& tex,
                 const std::array<double, 3>& base) {
    const ClipVertex* corner[3] = {&a, &b, &c};
    ScreenVertex s[3];
    double inv_z[3];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = corner[k]->p;
      inv_z[k] = 1.0 / p.z();
      s[k].u = cam_.fx * p.x() * inv_z[k] + cam_.cx;
      s[k].v = cam_.fy * p.y() * inv_z[k] + cam_.cy;
      if (!std::isfinite(s[k].u) || !std::isfinite(s[k].v)) return;
    }
    const double area = signedArea(s[0], s[1], s[2]);
    if (area == 0 || !std::isfinite(area)) return;
    const uint8_t back_face = plane_d < 0 ? 0 : 255;  // see the file comment
    // Edge k is opposite corner k; its value is corner k's (unnormalised) barycentric.
    const Edge edge[3] = {makeEdge(s[1], s[2], area), makeEdge(s[2], s[0], area), makeEdge(s[0], s[1], area)};

    const double u_min = std::min({s[0].u, s[1].u, s[2].u});
    const double u_max = std::max({s[0].u, s[1].u, s[2].u});
    const double v_min = std::min({s[0].v, s[1].v, s[2].v});
    const double v_max = std::max({s[0].v, s[1].v, s[2].v});
    const double i_lo = std::max(0.0, std::ceil(u_min));
    const double i_hi = std::min(static_cast<double>(cam_.width - 1), std::floor(u_max));
    const double j_lo = std::max(static_cast<double>(row_begin_), std::ceil(v_min));
    const double j_hi = std::min(static_cast<double>(row_end_ - 1), std::floor(v_max));
    if (i_lo > i_hi || j_lo > j_hi) return;

    const double nx = plane_n.x();
    const double ny = plane_n.y();
    const double nz = plane_n.z();
    const int w = cam_.width;
    int32_t id = -1;  ///< This triangle's Shading, once a pixel shows it.
    for (int j = static_cast<int>(j_lo); j <= static_cast<int>(j_hi); ++j) {
      const double v = j;
      const double ray_y = (v - cam_.cy) / cam_.fy;
      for (int i = static_cast<int>(i_lo); i <= static_cast<int>(i_hi); ++i) {
        const double u = i;
        double e[3];
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
          e[k] = edge[k].eval(u, v);
          inside = e[k] > 0 || (e[k] == 0 && edge[k].top_left);
        }
        if (!inside) continue;
        // Exact camera z: the pixel ray (x/z, y/z, 1) meets the plane n . p = plane_d.
        const double ray_x = (u - cam_.cx) / cam_.fx;
        const double z = plane_d / (nx * ray_x + ny * ray_y + nz);
        if (!(z > 0) || z > settings_.far_m) continue;
        const size_t idx = static_cast<size_t>(j) * w + i;  // in the output
        const size_t band_idx = idx - band_offset_;         // in this band's buffers
        if (!(z < depth_[band_idx])) continue;
        depth_[band_idx] = z;
        if (!out_.normals.empty()) {
          for (int ch = 0; ch < 3; ++ch) out_.normals.data[idx * 3 + ch] = normal[ch];
          out_.back_faces.data[idx] = back_face;
        }
        if (!shade_) continue;  // colour not asked for: it stays the background
        // Shaded once per pixel after all triangles (shadeWinners): a surface drawn over later
        // costs no texture lookups.
        if (id < 0) {
          id = static_cast<int32_t>(shadings_.size());
          shadings_.push_back(Shading{{edge[0], edge[1], edge[2]},
                                      {inv_z[0], inv_z[1], inv_z[2]},
                                      {a.attribute, b.attribute, c.attribute},
                                      tex,
                                      base});
        }
        winner_[band_idx] = id;
      }
    }
  }

  /// Colour of every pixel from the triangle that won its depth test: perspective-correct
  /// attributes, the texture's level of detail over the pixel's 2 x 2 quad (file comment) and
  /// output = round(255 * texture * vertex colour * base colour), all plain 0..1 values.
  void shadeWinners() {
    const int w = cam_.width;
    // The level of detail (lambda) of a 2 x 2 quad, kept for the quad's other pixels that show
    // the same triangle (quad_winner: that triangle's Shading, -1 none yet), per row pair.
    std::vector<int32_t> quad_winner(static_cast<size_t>(w / 2 + 1), -1);
    std::vector<double> quad_lambda(quad_winner.size());
    for (int j = row_begin_; j < row_end_; ++j) {
      if ((j & 1) == 0) std::fill(quad_winner.begin(), quad_winner.end(), -1);
      for (int i = 0; i < w; ++i) {
        const size_t idx = static_cast<size_t>(j) * w + i;
        const int32_t winner = winner_[idx - band_offset_];
        if (winner < 0) continue;
        const Shading& sh = shadings_[static_cast<size_t>(winner)];
        const double u = i, v = j;
        double e[3];
        for (int k = 0; k < 3; ++k) e[k] = sh.edge[k].eval(u, v);
        // Perspective-correct barycentrics: screen barycentrics e_k / sum(e) weighted by 1/z_k.
        const double e_sum = e[0] + e[1] + e[2];
        double wk[3];
        double w_sum = 0;
        for (int k = 0; k < 3; ++k) {
          wk[k] = (e_sum > 0 ? e[k] / e_sum : 1.0 / 3.0) * sh.inv_z[k];
          w_sum += wk[k];
        }
        double attr[kAttributeCount];
        for (int m = 0; m < kAttributeCount; ++m) {
          attr[m] = (wk[0] * sh.attribute[0][m] + wk[1] * sh.attribute[1][m] + wk[2] * sh.attribute[2][m]) / w_sum;
        }
        double tex_rgb[3] = {1.0, 1.0, 1.0};
        if (sh.tex.base != nullptr) {
          // Level of detail of the pixel's 2 x 2 quad (file comment).
          const size_t quad = static_cast<size_t>(i / 2);
          if (quad_winner[quad] != winner) {
            const double x0 = i & ~1, y0 = j & ~1;
            double st00[2], st10[2], st01[2];
            double rho = 0;
            if (texelsAt(sh, x0, y0, st00) && texelsAt(sh, x0 + 1, y0, st10) && texelsAt(sh, x0, y0 + 1, st01)) {
              const double dx0 = st10[0] - st00[0], dx1 = st10[1] - st00[1];
              const double dy0 = st01[0] - st00[0], dy1 = st01[1] - st00[1];
              rho = std::max(std::hypot(dx0, dx1), std::hypot(dy0, dy1));
            }
            quad_winner[quad] = winner;
            quad_lambda[quad] = rho > 0 && std::isfinite(rho) ? std::log2(rho) : 0.0;
          }
          sampleTrilinearRepeat(*sh.tex.base, *sh.tex.levels, attr[0], attr[1], quad_lambda[quad], tex_rgb);
        }
        uint8_t* px = &out_.rgba.data[idx * 4];
        for (int ch = 0; ch < 3; ++ch) {
          const double value = std::clamp(tex_rgb[ch] * attr[2 + ch] * sh.base[ch], 0.0, 1.0) * 255.0;
          px[ch] = static_cast<uint8_t>(std::lround(value));
        }
        px[3] = 255;
      }
    }
  }

  const Model& model_;
  const std::vector<std::vector<Texture>>& mip_levels_;
  const PinholeCamera& cam_;
  const RenderSettings& settings_;
  RenderOutput& out_;
  const bool shade_;                              ///< Colour asked for (RenderSettings::outputs).
  const int row_begin_, row_end_;                 ///< The band of output rows drawn.
  const size_t band_offset_;                      ///< Output index of the band's first pixel.
  std::vector<Shading> shadings_;                 ///< Of the triangles some pixel of the band showed.
  std::vector<int32_t> winner_;                   ///< Per band pixel: its Shading, -1 where none (empty: no shading).
  const std::vector<Eigen::Vector3d>& p_camera_;  ///< Vertices in the camera frame.
  std::vector<double> depth_;                     ///< Camera z per band pixel, +inf where empty.
};

/// Mip levels 1.. of every texture a material uses (consistent ones: see checkModel); empty for
/// the others.
std::vector<std::vector<Texture>> buildModelMipLevels(const Model& model) {
  std::vector<std::vector<Texture>> levels(model.textures.size());
  std::vector<bool> used(model.textures.size(), false);
  for (const Material& m : model.materials) {
    if (m.texture >= 0 && m.texture < static_cast<int>(model.textures.size()))
      used[static_cast<size_t>(m.texture)] = true;
  }
  for (size_t k = 0; k < model.textures.size(); ++k) {
    const Texture& t = model.textures[k];
    if (used[k] && t.width > 0 && t.height > 0 && t.rgba.size() == static_cast<size_t>(t.width) * t.height * 4) {
      levels[k] = buildMipLevels(t);
    }
  }
  return levels;
}

Result<RenderOutput> renderWithMipLevels(const Model& model, const std::vector<std::vector<Texture>>& mip_levels,
                                         const PinholeCamera& camera, const Pose& T_world_camera,
                                         const RenderSettings& settings) {
  if (Status valid = validateCamera(camera); !valid.ok()) return valid.error();
  if (!isValidPose(T_world_camera)) {
    return makeError(ErrorCode::kInvalidArgument, "renderReference: T_world_camera is not a finite rigid transform");
  }
  if (Status valid = validateRenderSettings(settings); !valid.ok()) return valid.error();
  if (std::string problem = checkModel(model); !problem.empty()) {
    return makeError(ErrorCode::kInvalidArgument, problem);
  }

  const int w = camera.width;
  const int h = camera.height;
  RenderOutput out;
  out.rgba = ImageU8(w, h, 4);
  for (size_t i = 0; i < out.rgba.data.size(); i += 4) {
    std::copy(settings.background_rgba.begin(), settings.background_rgba.end(), &out.rgba.data[i]);
  }
  out.depth = ImageF32(w, h, 1, kBackgroundDepth);
  if (settings.outputs & kRenderNormals) {
    out.normals = ImageF32(w, h, 3, 0.0f);
    out.back_faces = ImageU8(w, h, 1, 0);
  }

  const Pose T_camera_world = T_world_camera.inverse(Eigen::Isometry);
  std::vector<Eigen::Vector3d> p_camera(model.vertexCount());
  for (size_t i = 0; i < p_camera.size(); ++i) {
    p_camera[i] = T_camera_world *
                  Eigen::Vector3d(model.positions[3 * i], model.positions[3 * i + 1], model.positions[3 * i + 2]);
  }
  const Material default_material;
  auto materialOf = [&](int index) -> const Material& {
    return model.materials.empty() ? default_material : model.materials[index];
  };
  // The draw calls, culled and counted once: the blocks in the frustum, their ranges in order.
  struct DrawCall {
    uint32_t first_index, index_count;
    const Material* material;
  };
  std::vector<DrawCall> calls;
  auto addRanges = [&](uint32_t first_range, uint32_t range_count) {
    for (uint32_t r = first_range; r < first_range + range_count; ++r) {
      const DrawRange& dr = model.ranges[r];
      out.triangles_drawn += dr.index_count / 3;
      calls.push_back({dr.first_index, dr.index_count, &materialOf(dr.material)});
    }
  };
  if (!model.blocks.empty()) {
    for (const Block& block : model.blocks) {
      if (!aabbInFrustumFromCamera(block.bounds, camera, T_camera_world, settings.near_m, settings.far_m)) {
        continue;
      }
      ++out.blocks_drawn;
      addRanges(block.first_range, block.range_count);
    }
  } else if (!model.indices.empty()) {
    // A model without blocks (e.g. built by hand) is drawn as one block over all its ranges,
    // or over all its triangles with the first material when it has no ranges either.
    Aabb bounds;
    for (size_t i = 0; i < model.vertexCount(); ++i) bounds.extend(&model.positions[3 * i]);
    if (aabbInFrustum(bounds, camera, T_world_camera, settings.near_m, settings.far_m)) {
      ++out.blocks_drawn;
      if (!model.ranges.empty()) {
        addRanges(0, static_cast<uint32_t>(model.ranges.size()));
      } else {
        const auto n = static_cast<uint32_t>(model.indices.size());
        out.triangles_drawn += n / 3;
        calls.push_back({0, n, &materialOf(0)});
      }
    }
  }
  // Bands of an even number of rows (a 2 x 2 quad stays in one), at most one per 32 rows, one
  // per thread. An exception in a band is rethrown here once every thread has joined; bands whose
  // thread could not be started are drawn on this one.
  const int bands = std::max(1, std::min(settings.threads, h / 32));
  const int band_rows = ((h + bands - 1) / bands + 1) & ~1;
  const int used_bands = (h + band_rows - 1) / band_rows;
  std::vector<std::exception_ptr> failures(static_cast<size_t>(used_bands));
  // Every band makes every call into its own rows: a pixel sees the triangles in the same order
  // whatever the bands, so the output does not depend on their number.
  auto drawBandCaught = [&](int b) {
    try {
      Rasterizer raster(model, mip_levels, camera, settings, p_camera, b * band_rows, std::min(h, (b + 1) * band_rows),
                        out);
      for (const DrawCall& call : calls) raster.drawRange(call.first_index, call.index_count, *call.material);
      raster.finish();
    } catch (...) {
      failures[static_cast<size_t>(b)] = std::current_exception();
    }
  };
  std::vector<std::thread> workers;
  workers.reserve(static_cast<size_t>(used_bands - 1));
  int next = 1;
  for (; next < used_bands; ++next) {
    try {
      workers.emplace_back(drawBandCaught, next);
    } catch (const std::system_error&) {
      break;
    }
  }
  drawBandCaught(0);
  for (; next < used_bands; ++next) drawBandCaught(next);
  for (std::thread& worker : workers) worker.join();
  for (const std::exception_ptr& failure : failures) {
    if (failure) std::rethrow_exception(failure);
  }
  out.gray = rgbaToGray(out.rgba);
  return out;
}

}  // namespace

Result<RenderOutput> renderReference(const Model& model, const PinholeCamera& camera, const Pose& T_world_camera,
                                     const RenderSettings& settings) {
  return renderWithMipLevels(model, buildModelMipLevels(model), camera, T_world_camera, settings);
}

Result<std::unique_ptr<CpuRenderer>> CpuRenderer::create(const Model& model) {
  VKLOC_TRY_STATUS(validateModel(model));
  auto copy = std::make_shared<const Model>(model);
  auto mip_levels = std::make_shared<const std::vector<std::vector<Texture>>>(buildModelMipLevels(*copy));
  return std::unique_ptr<CpuRenderer>(new CpuRenderer(std::move(copy), std::move(mip_levels)));
}

Result<RenderOutput> CpuRenderer::render(const PinholeCamera& camera, const Pose& T_world_camera,
                                         const RenderSettings& settings) {
  return renderWithMipLevels(*model_, *mip_levels_, camera, T_world_camera, settings);
}

std::string CpuRenderer::describe() const { return "the CPU reference rasterizer"; }

RendererFactory cpuRendererFactory() {
  return [](const Model& model) -> Result<std::unique_ptr<Renderer>> {
    auto created = CpuRenderer::create(model);
    if (!created.ok()) return created.error();
    return std::unique_ptr<Renderer>(std::move(created).value());
  };
}

}  // namespace vkloc
