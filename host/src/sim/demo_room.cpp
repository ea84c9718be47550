// The built-in demo room (vkloc::makeDemoRoom).
#include <functional>

#include "sim/demo_internal.hpp"

namespace vkloc {

using namespace demo_detail;

// ================================================================================================
// Room
// ================================================================================================
namespace {

struct RoomMaterials {
  int floor, wall, ceiling, door, window, whiteboard, poster_graphic, poster_map, painting;
  int frame, wood, metal, fabric, cardboard, book, light, rug, screen, pot, leaves;
};

RoomMaterials addRoomMaterials(MeshBuilder& mb, uint32_t seed, int size) {
  uint32_t k = 0;
  auto ts = [&] { return textureSeed(seed, 2, k++); };
  RoomMaterials m{};
  m.floor = mb.addTexturedMaterial(woodFloorTexture(size, ts()));
  m.wall = mb.addTexturedMaterial(wallTexture(size, ts()));
  m.ceiling = mb.addTexturedMaterial(ceilingTexture(size, ts()));
  m.door = mb.addTexturedMaterial(doorTexture(size, ts()));
  m.window = mb.addTexturedMaterial(windowTexture(size, ts()));
  m.whiteboard = mb.addTexturedMaterial(whiteboardTexture(size, ts()));
  m.poster_graphic = mb.addTexturedMaterial(posterTexture(size, ts(), 0));
  m.poster_map = mb.addTexturedMaterial(posterTexture(size, ts(), 1));
  m.painting = mb.addTexturedMaterial(posterTexture(size, ts(), 2));
  m.frame = mb.addTexturedMaterial(plainTexture(size, ts(), "frame_wood", {92, 62, 40}, 0.05, 0.2, 2, 32));
  m.wood = mb.addTexturedMaterial(plainTexture(size, ts(), "wood", {196, 160, 112}, 0.05, 0.2, 2, 48));
  m.metal = mb.addTexturedMaterial(plainTexture(size, ts(), "metal", {150, 154, 160}, 0.04, 0.06, 4, 4));
  m.fabric = mb.addTexturedMaterial(plainTexture(size, ts(), "fabric", {200, 200, 200}, 0.08, 0.1, 8, 8));
  m.cardboard = mb.addTexturedMaterial(cardboardTexture(size, ts()));
  m.book = mb.addTexturedMaterial(bookTexture(size, ts()));
  m.light = mb.addTexturedMaterial(lightPanelTexture(size, ts()));
  m.rug = mb.addTexturedMaterial(rugTexture(size, ts()));
  m.screen = mb.addTexturedMaterial(screenTexture(size, ts()));
  m.pot = mb.addTexturedMaterial(plainTexture(size, ts(), "terracotta", {176, 96, 64}, 0.08, 0.1, 4, 4));
  m.leaves = mb.addTexturedMaterial(leavesTexture(size, ts()));
  return m;
}

constexpr double kRoomX = 3.0, kRoomY = 2.5, kRoomH = 3.0;

/// An opening [s0, s1] x [t0, t1] in a wall frame, recessed `depth` behind the wall: reveal
/// faces (jambs, head, and a sill when t0 > 0) and a back panel, all facing into the room.
void addRecess(MeshBuilder& mb, const Frame& f, double s0, double t0, double s1, double t1, double depth,
               int reveal_material, int panel_material) {
  const V3 n = cross(f.eu, f.ev);
  const V3 back = -depth * n;
  const double w = s1 - s0, h = t1 - t0;
  mb.rect(Frame{f.at(s0, t0) + back, f.eu, f.ev}, 0, 0, w, h, fitUv(0, 0, w, h, 0, 0, 1, 1), panel_material);
  auto reveal = [&](V3 a, V3 b, V3 facing, double len) {
    // Quad a, b, b + back, a + back; texture from the plain upper part of the wall paint.
    mb.quad(a, b, b + back, a + back, {0, 0.1}, {len / 3, 0.1}, {len / 3, 0.1 + depth / 3}, {0, 0.1 + depth / 3},
            reveal_material, kWhite, facing);
  };
  reveal(f.at(s0, t0), f.at(s0, t1), f.eu, h);
  reveal(f.at(s1, t0), f.at(s1, t1), -1.0 * f.eu, h);
  reveal(f.at(s0, t1), f.at(s1, t1), -1.0 * f.ev, w);
  if (t0 > 0) reveal(f.at(s0, t0), f.at(s1, t0), f.ev, w);
}

/// A thin wall-mounted panel (poster, whiteboard, painting): `front` faces the room.
void addWallPanel(MeshBuilder& mb, V3 lo, V3 hi, BoxFace front, int front_material, int edge_material) {
  std::array<FaceLook, 6> look = allFaces(edge_material, 0.5);
  look[front] = FaceLook{front_material, {0, 0, 1, 1}, 0, true};
  addBox(mb, lo, hi, look, kWhite);
}

}  // namespace

Model makeDemoRoom(const DemoModelOptions& options) {
  const int size = clampTextureSize(options.texture_size);
  Rng rng(hash4(options.seed, 0x800Au));
  MeshBuilder mb;
  const RoomMaterials rm = addRoomMaterials(mb, options.seed, size);
  const double X = kRoomX, Y = kRoomY, H = kRoomH;

  // ---- shell: walls (seen from inside), floor, ceiling ----------------------------------------
  const Frame south{{X, -Y, 0}, kNegX, kZ}, north{{-X, Y, 0}, kX, kZ};
  const Frame west{{-X, -Y, 0}, kY, kZ}, east{{X, Y, 0}, kNegY, kZ};
  const UvMap wall_uv{1 / 3.0, 0, -1 / H, 1};
  const double win_x0 = -0.9, win_x1 = 0.5, win_z0 = 0.9, win_z1 = 2.1, win_depth = 0.2;
  const double door_y0 = 1.2, door_y1 = 2.1, door_h = 2.1, door_depth = 0.12;
  const Rect window_st{X - win_x1, win_z0, X - win_x0, win_z1};  // In the south wall's (s, t).
  const Rect door_st{Y - door_y1, 0, Y - door_y0, door_h};       // In the east wall's (s, t).
  mb.region(south, Region{{{0, 0, 2 * X, H}}, {window_st}}, wall_uv, rm.wall);
  mb.region(north, Region{{{0, 0, 2 * X, H}}, {}}, wall_uv, rm.wall);
  mb.region(west, Region{{{0, 0, 2 * Y, H}}, {}}, wall_uv, rm.wall);
  mb.region(east, Region{{{0, 0, 2 * Y, H}}, {door_st}}, wall_uv, rm.wall);
  addRecess(mb, south, window_st.x0, window_st.y0, window_st.x1, window_st.y1, win_depth, rm.wall, rm.window);
  addRecess(mb, east, door_st.x0, door_st.y0, door_st.x1, door_st.y1, door_depth, rm.wall, rm.door);
  mb.region(horizontalFrame(0), Region{{{-X, -Y, X, Y}, {X, door_y0, X + door_depth, door_y1}}, {}},
            UvMap{0.5, 0, 0.5, 0}, rm.floor);
  mb.region(Frame{{0, 0, H}, kX, kNegY}, Region{{{-X, -Y, X, Y}}, {}}, UvMap{1 / 2.4, 0, 1 / 2.4, 0}, rm.ceiling);

  // ---- wall-mounted items ---------------------------------------------------------------------
  const double g = kGap;
  addWallPanel(mb, {-1.8, Y - g - 0.025, 0.9}, {0.2, Y - g, 2.0}, kFaceNegY, rm.whiteboard, rm.metal);
  addWallPanel(mb, {0.8, Y - g - 0.004, 1.2}, {1.6, Y - g, 2.2}, kFaceNegY, rm.poster_graphic, rm.poster_graphic);
  addWallPanel(mb, {X - g - 0.03, -1.6, 1.2}, {X - g, -0.6, 1.9}, kFaceNegX, rm.painting, rm.frame);
  addWallPanel(mb, {1.2, -Y + g, 1.2}, {2.2, -Y + g + 0.004, 1.9}, kFacePosY, rm.poster_map, rm.poster_map);
  for (double lx : {-1.5, 0.9}) {
    std::array<FaceLook, 6> look = allFaces(rm.metal, 0.5);
    look[kFaceNegZ] = FaceLook{rm.light, {0, 0, 1, 1}, 0, true};
    addBox(mb, {lx, -0.6, H - g - 0.04}, {lx + 0.6, 0.6, H - g}, look, kWhite);
  }

  // ---- bookcase against the west wall ---------------------------------------------------------
  const double bx0 = -X + g, bx1 = -X + 0.35, by0 = -0.8, by1 = 0.8, bh = 2.0, board = 0.02;
  const Rgba8 shelf_tint = tint(rng, 0.2);
  addBox(mb, {bx0, by0, g}, {bx1, by0 + board, bh}, allFaces(rm.wood, 1.0), shelf_tint);
  addBox(mb, {bx0, by1 - board, g}, {bx1, by1, bh}, allFaces(rm.wood, 1.0), shelf_tint);
  addBox(mb, {bx0, by0 + board + g, g}, {bx0 + 0.01, by1 - board - g, bh - g}, allFaces(rm.wood, 1.0), shelf_tint);
  const double shelf_z[] = {0.06, 0.5, 0.95, 1.45, bh - board - g};
  for (double z : shelf_z)
    addBox(mb, {bx0 + 0.01 + g, by0 + board + g, z}, {bx1, by1 - board - g, z + board}, allFaces(rm.wood, 1.0),
           shelf_tint);
  static const Rgba8 kBookColors[] = {{170, 40, 40, 255},  {40, 60, 140, 255}, {40, 110, 60, 255},
                                      {220, 190, 70, 255}, {40, 40, 44, 255},  {230, 230, 225, 255},
                                      {120, 70, 130, 255}, {200, 110, 40, 255}};
  for (size_t k = 0; k + 1 < std::size(shelf_z); ++k) {
    const double z0 = shelf_z[k] + board + g, space = shelf_z[k + 1] - z0 - 0.02;
    double y = by0 + board + g + g;
    const double y_end = by1 - board - g - g;
    while (true) {
      const double w = rng.uniform(0.02, 0.055);
      if (y + w > y_end) break;
      if (rng.chance(0.08)) {  // A gap in the row.
        y += rng.uniform(0.04, 0.12);
        continue;
      }
      const double h = std::min(space, rng.uniform(0.17, 0.3)), d = rng.uniform(0.15, 0.24);
      std::array<FaceLook, 6> look = allFaces(rm.book);
      look[kFacePosX].uv = {0, 0, 1, 1};                                                     // Spine faces the room.
      look[kFacePosZ].uv = look[kFaceNegZ].uv = look[kFaceNegX].uv = {0.3, 0.3, 0.7, 0.55};  // Pages.
      look[kFacePosY].uv = look[kFaceNegY].uv = {0.02, 0.16, 0.1, 0.24};                     // Covers.
      addBox(mb, {bx1 - 0.005 - d, y, z0}, {bx1 - 0.005, y + w, z0 + h}, look, kBookColors[rng.range(0, 7)]);
      y += w + g;
    }
  }

  // ---- rug, table, chairs, things on the table -----------------------------------------------
  const double rug_top = g + 0.01;
  addBox(mb, {-1.0, -0.9, g}, {1.4, 1.5, rug_top},
         std::array<FaceLook, 6>{FaceLook{rm.rug, {0, 0, 0.05, 0.05}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}},
                                 FaceLook{rm.rug, {0, 0, 0.05, 0.05}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}},
                                 FaceLook{rm.rug, {0, 0, 1, 1}}, FaceLook{rm.rug, {0, 0, 0.05, 0.05}}},
         kWhite);
  const double tx0 = -0.6, tx1 = 1.0, ty0 = -0.15, ty1 = 0.75, tz = 0.74;
  addBox(mb, {tx0, ty0, tz - 0.04}, {tx1, ty1, tz}, allFaces(rm.wood, 1.0), kWhite);
  for (double lx : {tx0 + 0.05, tx1 - 0.1})
    for (double ly : {ty0 + 0.05, ty1 - 0.1})
      addBox(mb, {lx, ly, rug_top + g}, {lx + 0.05, ly + 0.05, tz - 0.04 - g}, allFaces(rm.metal, 0.5), kWhite);
  // Laptop: base and screen (screen texture towards -y).
  addBox(mb, {0.0, 0.1, tz + g}, {0.33, 0.33, tz + g + 0.018}, allFaces(rm.metal, 0.5), kWhite);
  {
    std::array<FaceLook, 6> look = allFaces(rm.metal, 0.5);
    look[kFaceNegY] = FaceLook{rm.screen, {0, 0, 1, 1}, 0, true};
    addBox(mb, {0.0, 0.335, tz + g}, {0.33, 0.345, tz + g + 0.22}, look, kWhite);
  }
  {
    std::array<FaceLook, 6> look = allFaces(rm.book);
    look[kFacePosZ].uv = {0, 0, 1, 1};
    addBox(mb, {0.55, 0.35, tz + g}, {0.8, 0.52, tz + g + 0.035}, look, kBookColors[1]);
    addBox(mb, {0.57, 0.36, tz + 2 * g + 0.035}, {0.78, 0.5, tz + 2 * g + 0.065}, look, kBookColors[3]);
  }
  addBox(mb, {0.42, -0.02, tz + g}, {0.5, 0.06, tz + g + 0.1}, allFaces(rm.metal, 0.2), Rgba8{240, 240, 240, 255});
  // Chairs: seat, four legs, back on the side away from the table.
  auto chair = [&](double cx, double cy, bool back_south) {
    const double s = 0.21, seat_z = 0.45;
    const Rgba8 c = tint(rng, 0.3);
    addBox(mb, {cx - s, cy - s, seat_z}, {cx + s, cy + s, seat_z + 0.04}, allFaces(rm.fabric, 0.5), c);
    for (double lx : {cx - s + 0.01, cx + s - 0.04})
      for (double ly : {cy - s + 0.01, cy + s - 0.04})
        addBox(mb, {lx, ly, rug_top + g}, {lx + 0.03, ly + 0.03, seat_z - g}, allFaces(rm.metal, 0.5), kWhite);
    const double y0 = back_south ? cy - s - g - 0.03 : cy + s + g, y1 = y0 + 0.03;
    addBox(mb, {cx - s, y0, seat_z + 0.05}, {cx + s, y1, 0.95}, allFaces(rm.fabric, 0.5), c);
  };
  chair(-0.15, -0.5, true);
  chair(0.65, -0.5, true);
  chair(0.2, 1.1, false);

  // ---- couch in the south-west corner ----------------------------------------------------------
  {
    const Rgba8 c = tint(rng, 0.5), cushion = tint(rng, 0.4);
    const double y0 = -Y + g, y1 = -1.6;
    const std::array<FaceLook, 6> fab = allFaces(rm.fabric, 0.5);
    addBox(mb, {-2.9, y0, g}, {-2.752, y1, 0.62}, fab, c);
    addBox(mb, {-1.248, y0, g}, {-1.1, y1, 0.62}, fab, c);
    addBox(mb, {-2.75, y0, g}, {-1.25, y1, 0.25}, fab, c);
    addBox(mb, {-2.75, y0, 0.25 + g}, {-1.25, -2.3, 0.85}, fab, c);
    for (double x0 : {-2.75, -1.998}) {
      addBox(mb, {x0, -2.3 + g, 0.25 + g}, {x0 + 0.748, y1, 0.42}, fab, cushion);
      addBox(mb, {x0, -2.3 + g, 0.42 + g}, {x0 + 0.748, -2.14, 0.8}, fab, cushion);
    }
  }

  // ---- cardboard boxes in the south-east corner, plant in the north-west corner ------------------
  {
    std::array<FaceLook, 6> look = allFaces(rm.cardboard);
    addBox(mb, {2.3, -Y + 0.05, g}, {2.95, -1.9, 0.45}, look, kWhite);
    addBox(mb, {2.35, -Y + 0.1, 0.45 + g}, {2.85, -1.95, 0.8}, look, Rgba8{235, 225, 215, 255});
    addBox(mb, {1.7, -Y + 0.05, g}, {2.2, -2.0, 0.35}, look, Rgba8{225, 220, 210, 255});
  }
  addBox(mb, {-2.9, 2.05, g}, {-2.5, 2.45, 0.4}, allFaces(rm.pot, 0.5), kWhite);
  addTree(mb, rm.wood, rm.leaves, -2.7, 2.25, 0.4, 0.35, 0.22, 0.02, rng);

  return mb.build("demo:room", options.target_triangles);
}

std::vector<std::string> demoModelNames() { return {"city", "room"}; }

}  // namespace vkloc
