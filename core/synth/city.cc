#include "core/synth/city.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "core/common/error.h"
#include "core/raycast/ray_scene.h"

namespace satmesh::synth {
namespace {

struct Rng {
  std::mt19937_64 gen;
  double U(double a, double b) { return std::uniform_real_distribution<double>(a, b)(gen); }
  bool P(double p) { return U(0, 1) < p; }
  int I(int a, int b) { return std::uniform_int_distribution<int>(a, b)(gen); }
};

struct Rect { double x0, y0, x1, y1; };

// Distance to the nearest street centre line along each axis.
double StreetDistance(double v, const TextureParams& t) {
  const double f = (v - t.street_offset_m) / t.street_pitch_m;
  return std::abs(f - std::round(f)) * t.street_pitch_m;
}

void Append(CityModel* city, const BoxMeshPart& part, double angle, const Eigen::Vector2d& c,
            uint32_t variant) {
  const int base = int(city->mesh.vertices.size());
  const double ca = std::cos(angle), sa = std::sin(angle);
  for (const auto& v : part.vertices)
    city->mesh.vertices.emplace_back(float(c.x() + ca * v.x() - sa * v.y()),
                                     float(c.y() + sa * v.x() + ca * v.y()), v.z());
  for (size_t f = 0; f < part.faces.size(); ++f) {
    city->mesh.faces.push_back(part.faces[f] + Eigen::Vector3i::Constant(base));
    city->face_material.push_back(part.face_material[f]);
    city->face_variant.push_back(variant);
  }
}

void AddGround(CityModel* city, const CityOptions& o) {
  const double cell = o.ground_cell_m;
  const int n = int(std::ceil((o.aoi_size_m / 2 + o.ground_margin_m) / cell));
  const int side = 2 * n + 1;
  const int base = int(city->mesh.vertices.size());
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const double x = (i - n) * cell, y = (j - n) * cell;
      city->mesh.vertices.emplace_back(float(x), float(y), float(city->ground.Height(x, y)));
    }
  const double half = o.street_width_m / 2;
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i) {
      const double x = (i - n + 0.5) * cell, y = (j - n + 0.5) * cell;
      const double d = std::min(StreetDistance(x, city->texture), StreetDistance(y, city->texture));
      const Material m = d < half ? Material::kRoad
                         : d < half + o.sidewalk_width_m ? Material::kSidewalk
                                                         : Material::kGrass;
      const int v00 = base + j * side + i, v10 = v00 + 1, v01 = v00 + side, v11 = v01 + 1;
      city->mesh.faces.emplace_back(v00, v10, v11);
      city->mesh.faces.emplace_back(v00, v11, v01);
      for (int k = 0; k < 2; ++k) {
        city->face_material.push_back(m);
        city->face_variant.push_back(0);
      }
    }
}

// Gable or hip roof over [-hx,hx]x[-hy,hy] at eave height ze (ridge along x, hx >= hy).
void AddSlopedRoof(BoxMeshPart* part, float hx, float hy, float ze, float rise, bool hip) {
  auto find = [&](float x, float y) {
    for (size_t i = 0; i < part->vertices.size(); ++i)
      if ((part->vertices[i] - Eigen::Vector3f(x, y, ze)).norm() < 1e-4f) return int(i);
    part->vertices.emplace_back(x, y, ze);
    return int(part->vertices.size()) - 1;
  };
  const int c00 = find(-hx, -hy), c10 = find(hx, -hy), c11 = find(hx, hy), c01 = find(-hx, hy);
  const float inset = hip ? std::min(hy, 0.45f * hx) : 0.f;
  const int r0 = int(part->vertices.size());
  part->vertices.emplace_back(-hx + inset, 0.f, ze + rise);
  part->vertices.emplace_back(hx - inset, 0.f, ze + rise);
  const int r1 = r0 + 1;
  const Material end = hip ? Material::kRoofTiles : Material::kFacade;
  const std::pair<Eigen::Vector3i, Material> tris[] = {
      {{c00, c10, r1}, Material::kRoofTiles}, {{c00, r1, r0}, Material::kRoofTiles},
      {{c11, c01, r0}, Material::kRoofTiles}, {{c11, r0, r1}, Material::kRoofTiles},
      {{c01, c00, r0}, end},                  {{c10, c11, r1}, end}};
  for (const auto& [f, m] : tris) {
    part->faces.push_back(f);
    part->face_material.push_back(m);
  }
}

CityBox Box(double x0, double y0, double z0, double x1, double y1, double z1,
            Material wall = Material::kFacade, Material top = Material::kRoofGravel) {
  CityBox b;
  b.lo = Eigen::Vector3f(float(x0), float(y0), float(z0));
  b.hi = Eigen::Vector3f(float(x1), float(y1), float(z1));
  b.wall = wall;
  b.top = top;
  return b;
}
CityBox Cut(double x0, double y0, double z0, double x1, double y1, double z1) {
  CityBox b = Box(x0, y0, z0, x1, y1, z1);
  b.subtract = true;
  return b;
}

// Flat-roofed building boxes in its own frame; footprint [-hx,hx]x[-hy,hy].
std::vector<CityBox> FlatBuilding(Rng& r, const CityOptions& o, double hx, double hy, double zl,
                                  double z0, double height, bool balconies) {
  std::vector<CityBox> boxes;
  const bool l_shape = hx > 7 && hy > 7 && r.P(0.35);
  const bool setback = height >= 15 && r.P(0.4);
  const double h1 = setback ? height * r.U(0.45, 0.75) : height;
  boxes.push_back(Box(-hx, -hy, zl, hx, hy, z0 + h1));
  Rect main{-hx, -hy, hx, hy};
  if (l_shape) {
    const double a = 2 * hx * r.U(0.3, 0.55), b = 2 * hy * r.U(0.3, 0.55);
    boxes.push_back(Cut(hx - a, hy - b, zl - 1, hx + 1, hy + 1, z0 + height + 10));
    main = (2 * hx - a) * 2 * hy > 2 * hx * (2 * hy - b) ? Rect{-hx, -hy, hx - a, hy}
                                                          : Rect{-hx, -hy, hx, hy - b};
  }
  const bool arcade = h1 >= 8 && r.P(o.arcade_fraction);
  const double hg = r.U(3.5, 4.5);
  if (arcade) {  // recessed ground floor on the south and/or west side, with columns
    const double d = r.U(1.5, 3.0);
    const bool south = r.P(0.7), west = !south || r.P(0.5);
    const double spacing = r.U(4.0, 6.0);
    if (south) {
      boxes.push_back(Cut(-hx - 1, -hy - 1, zl - 1, hx + 1, -hy + d, z0 + hg));
      for (double x = -hx + 0.3; x < main.x1 - 0.5; x += spacing)
        boxes.push_back(Box(x, -hy + 0.2, zl, x + 0.5, -hy + 0.7, z0 + hg));
    }
    if (west) {
      boxes.push_back(Cut(-hx - 1, -hy - 1, zl - 1, -hx + d, hy + 1, z0 + hg));
      for (double y = -hy + 0.3; y < main.y1 - 0.5; y += spacing)
        boxes.push_back(Box(-hx + 0.2, y, zl, -hx + 0.7, y + 0.5, z0 + hg));
    }
  }
  if (h1 >= 10 && r.P(o.recess_fraction)) {  // loggia slot on the south facade
    const double w = std::min(r.U(4, 8), (main.x1 - main.x0) - 4), d = r.U(1.2, 2.0);
    const double x = r.U(main.x0 + 2, main.x1 - 2 - w);
    const double za = z0 + (arcade ? hg + 1 : r.U(3.5, 6)), zb = z0 + h1 - r.U(2, 3.5);
    if (w > 2 && zb - za > 3) boxes.push_back(Cut(x, -hy - 1, za, x + w, -hy + d, zb));
  }
  if (balconies) {  // slabs on the west facade (never cut by the L)
    const double floor_h = r.U(3.0, 3.4), spacing = r.U(5, 8), w = r.U(2.5, 3.5);
    for (int f = arcade ? 2 : 1; z0 + (f + 1) * floor_h < z0 + h1 - 0.5; ++f)
      for (double y = main.y0 + 1; y + w < main.y1 - 1; y += spacing) {
        const double z = z0 + f * floor_h;
        CityBox slab = Box(-hx - 1.3, y, z - 0.2, -hx, y + w, z, Material::kSoffit, Material::kSoffit);
        boxes.push_back(slab);
      }
  }
  Rect top = main;
  double ztop = z0 + h1;
  if (setback) {
    Rect t{main.x0 + (r.P(0.3) ? 0 : r.U(1.5, 5)), main.y0 + (r.P(0.3) ? 0 : r.U(1.5, 5)),
           main.x1 - (r.P(0.3) ? 0 : r.U(1.5, 5)), main.y1 - (r.P(0.3) ? 0 : r.U(1.5, 5))};
    if (t.x1 - t.x0 >= 5 && t.y1 - t.y0 >= 5) {
      boxes.push_back(Box(t.x0, t.y0, z0 + h1, t.x1, t.y1, z0 + height));
      top = t;
      ztop = z0 + height;
    }
  }
  const double tw = top.x1 - top.x0, th = top.y1 - top.y0;
  if (!l_shape && r.P(0.5)) {  // parapet
    const double t = 0.3, h = 0.8;
    const Material m = Material::kRooftop;
    boxes.push_back(Box(top.x0, top.y0, ztop, top.x1, top.y0 + t, ztop + h, Material::kFacade, m));
    boxes.push_back(Box(top.x0, top.y1 - t, ztop, top.x1, top.y1, ztop + h, Material::kFacade, m));
    boxes.push_back(Box(top.x0, top.y0, ztop, top.x0 + t, top.y1, ztop + h, Material::kFacade, m));
    boxes.push_back(Box(top.x1 - t, top.y0, ztop, top.x1, top.y1, ztop + h, Material::kFacade, m));
  }
  if (tw > 12 && th > 12 && r.P(0.3)) {  // solar panel field
    const double x0 = top.x0 + 2, y0 = top.y0 + 2;
    boxes.push_back(Box(x0, y0, ztop, x0 + (tw - 4) * 0.5, y0 + (th - 4) * r.U(0.4, 0.9),
                        ztop + 0.25, Material::kRooftop, Material::kRoofPanel));
  }
  const int structures = (tw > 8 && th > 8) ? r.I(0, 3) : 0;
  for (int s = 0; s < structures; ++s) {
    const double w = r.U(2, std::min(5.0, tw / 3)), d = r.U(2, std::min(5.0, th / 3));
    const double x = r.U(top.x0 + 1.5, top.x1 - 1.5 - w), y = r.U(top.y0 + 1.5, top.y1 - 1.5 - d);
    boxes.push_back(Box(x, y, ztop, x + w, y + d, ztop + r.U(1.5, 3.5), Material::kRooftop,
                        Material::kRooftop));
  }
  return boxes;
}

void AddBuilding(CityModel* city, const CityOptions& o, const Rect& lot, Rng& r) {
  const double height = o.min_height_m + (o.max_height_m - o.min_height_m) * std::pow(r.U(0, 1), 2.2);
  const bool sloped = height <= 18 && r.P(o.sloped_roof_fraction);
  const bool balconies = !sloped && height >= 9 && r.P(o.balcony_fraction);
  const double margin = 1.0 + (balconies ? 1.5 : 0.0);
  double angle = r.P(0.55) ? 0.0 : r.U(-0.45, 0.45);
  const double lw = lot.x1 - lot.x0 - 2 * margin, ld = lot.y1 - lot.y0 - 2 * margin;
  double w = lw * r.U(0.6, 1.0), d = ld * r.U(0.6, 1.0);
  if (sloped) w = std::min(w, 24.0), d = std::min(d, 24.0);
  const double c = std::abs(std::cos(angle)), s = std::abs(std::sin(angle));
  const double scale = std::min({1.0, lw / (w * c + d * s), ld / (w * s + d * c)});
  w *= scale;
  d *= scale;
  if (w < 6 || d < 6) return;
  if (sloped && w < d) std::swap(w, d), angle += M_PI / 2;
  const Eigen::Vector2d centre((lot.x0 + lot.x1) / 2, (lot.y0 + lot.y1) / 2);
  const double hx = w / 2, hy = d / 2;
  double gmin = 1e9, gmax = -1e9;
  for (double u : {-1.0, 0.0, 1.0})
    for (double v : {-1.0, 0.0, 1.0}) {
      const double x = u * hx, y = v * hy;
      const double g = city->ground.Height(centre.x() + std::cos(angle) * x - std::sin(angle) * y,
                                           centre.y() + std::sin(angle) * x + std::cos(angle) * y);
      gmin = std::min(gmin, g), gmax = std::max(gmax, g);
    }
  const double zl = gmin - 0.3, z0 = gmax + 0.1;  // walls just below the ground
  const uint32_t variant = uint32_t(++city->num_buildings);
  city->max_building_height_m = std::max(city->max_building_height_m, float(height + 4));
  if (sloped) {
    const double eave = std::clamp(height * 0.7, 3.5, 12.0);
    CityBox body = Box(-hx, -hy, zl, hx, hy, z0 + eave, Material::kFacade, Material::kCount);
    BoxMeshPart part = MeshBoxes({body});
    AddSlopedRoof(&part, float(hx), float(hy), float(z0 + eave),
                  float(hy * std::tan(r.U(25, 40) * M_PI / 180)), r.P(0.5));
    Append(city, part, angle, centre, variant);
    return;
  }
  Append(city, MeshBoxes(FlatBuilding(r, o, hx, hy, zl, z0, height, balconies)), angle, centre,
         variant);
}

void SplitLots(const Rect& rect, int depth, Rng& r, std::vector<Rect>* lots) {
  const double w = rect.x1 - rect.x0, h = rect.y1 - rect.y0, longest = std::max(w, h);
  if (depth < 3 && longest > 30 && (longest > 55 || r.P(0.7))) {
    const double f = r.U(0.35, 0.65), gap = 2;
    if (w >= h) {
      const double x = rect.x0 + f * w;
      SplitLots({rect.x0, rect.y0, x - gap / 2, rect.y1}, depth + 1, r, lots);
      SplitLots({x + gap / 2, rect.y0, rect.x1, rect.y1}, depth + 1, r, lots);
    } else {
      const double y = rect.y0 + f * h;
      SplitLots({rect.x0, rect.y0, rect.x1, y - gap / 2}, depth + 1, r, lots);
      SplitLots({rect.x0, y + gap / 2, rect.x1, rect.y1}, depth + 1, r, lots);
    }
    return;
  }
  lots->push_back(rect);
}

void AddTree(CityModel* city, const Eigen::Vector2d& at, Rng& r) {
  const double g = city->ground.Height(at.x(), at.y());
  const double radius = r.U(1.8, 2.6), zc = g + r.U(3.5, 5.0) + 0.6 * radius;
  CityBox trunk = Box(-0.18, -0.18, g - 0.5, 0.18, 0.18, zc, Material::kTree, Material::kCount);
  Append(city, MeshBoxes({trunk}), 0.0, at, 0);
  BoxMeshPart crown;
  const int rings = 6, segs = 10;
  crown.vertices.emplace_back(0.f, 0.f, float(zc + radius * r.U(0.7, 0.9)));
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segs; ++j) {
      const double th = M_PI * i / rings, ph = 2 * M_PI * (j + 0.5 * (i % 2)) / segs;
      const double rr = radius * r.U(0.85, 1.15);
      crown.vertices.emplace_back(float(rr * std::sin(th) * std::cos(ph)),
                                  float(rr * std::sin(th) * std::sin(ph)),
                                  float(zc + 0.8 * rr * std::cos(th)));
    }
  crown.vertices.emplace_back(0.f, 0.f, float(zc - 0.6 * radius));
  const int last = int(crown.vertices.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * segs + (j % segs); };
  for (int j = 0; j < segs; ++j) {
    crown.faces.emplace_back(0, ring(1, j), ring(1, j + 1));
    crown.faces.emplace_back(last, ring(rings - 1, j + 1), ring(rings - 1, j));
    for (int i = 1; i + 1 < rings; ++i) {
      crown.faces.emplace_back(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1));
      crown.faces.emplace_back(ring(i, j), ring(i + 1, j + 1), ring(i, j + 1));
    }
  }
  // Orient outward from the crown centre.
  const Eigen::Vector3f centre(0.f, 0.f, float(zc));
  for (auto& f : crown.faces) {
    const auto &a = crown.vertices[f[0]], &b = crown.vertices[f[1]], &c = crown.vertices[f[2]];
    if ((b - a).cross(c - a).dot((a + b + c) / 3 - centre) < 0) std::swap(f[1], f[2]);
  }
  crown.face_material.assign(crown.faces.size(), Material::kTree);
  Append(city, crown, 0.0, at, 0);
}

// Drops ground faces inside buildings (an upward ray first meets a back face) and
// compacts the vertices, so the truth mesh holds only surfaces that can be seen.
void PruneHiddenGround(CityModel* city, size_t ground_faces) {
  TriangleMesh& m = city->mesh;
  const RayScene scene(m);
  std::vector<Ray> rays(ground_faces);
  for (size_t f = 0; f < ground_faces; ++f) {
    const auto& t = m.faces[f];
    rays[f].origin = (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3.f +
                     Eigen::Vector3f(0, 0, 0.01f);
    rays[f].direction = Eigen::Vector3f::UnitZ();
    rays[f].t_far = 500.f;
  }
  std::vector<RayHit> hits(ground_faces);
  scene.Intersect(rays.data(), hits.data(), ground_faces);
  std::vector<char> keep(m.faces.size(), 1);
  for (size_t f = 0; f < ground_faces; ++f) {
    if (!hits[f].hit()) continue;
    const auto& t = m.faces[hits[f].face];
    const Eigen::Vector3f n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    if (n.z() > 0) keep[f] = 0;
  }
  std::vector<int> remap(m.vertices.size(), -1);
  TriangleMesh out;
  out.origin = m.origin;
  out.crs = m.crs;
  std::vector<Material> mats;
  std::vector<uint32_t> vars;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (!keep[f]) continue;
    Eigen::Vector3i t;
    for (int k = 0; k < 3; ++k) {
      int& r = remap[m.faces[f][k]];
      if (r < 0) {
        r = int(out.vertices.size());
        out.vertices.push_back(m.vertices[m.faces[f][k]]);
      }
      t[k] = r;
    }
    out.faces.push_back(t);
    mats.push_back(city->face_material[f]);
    vars.push_back(city->face_variant[f]);
  }
  m = std::move(out);
  city->face_material = std::move(mats);
  city->face_variant = std::move(vars);
}

}  // namespace

std::string CityOptions::Check() const {
  if (!(aoi_size_m > 0)) return "aoi_size_m must be > 0";
  if (!(building_margin_m >= 0) || !(ground_margin_m >= 0)) return "margins must be >= 0";
  if (!(ground_cell_m > 0 && ground_cell_m <= 10)) return "ground_cell_m must be in (0, 10]";
  if (!(relief_m >= 0 && relief_m <= 20)) return "relief_m must be in [0, 20]";
  if (!(street_width_m > 0) || !(sidewalk_width_m >= 0)) return "street widths must be positive";
  if (!(street_pitch_m > street_width_m + 2 * sidewalk_width_m + 10))
    return "street_pitch_m must exceed street_width_m + 2 sidewalks + 10";
  if (!(min_height_m >= 2 && max_height_m >= min_height_m)) return "need 2 <= min_height_m <= max_height_m";
  for (double f : {sloped_roof_fraction, arcade_fraction, recess_fraction, balcony_fraction})
    if (!(f >= 0 && f <= 1)) return "fractions must be in [0, 1]";
  return "";
}

double GroundRelief::Height(double x, double y) const {
  double h = 0;
  for (const auto& w : waves) h += w[0] * std::sin(w[1] * x + w[2] * y + w[3]);
  return h;
}

CityModel BuildCity(const CityOptions& o, uint32_t seed, const Eigen::Vector3d& origin,
                    const std::string& crs) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "CityOptions: " + why);
  Rng r{std::mt19937_64(seed * 0x9E3779B97F4A7C15ull + 17)};
  CityModel city;
  city.mesh.origin = origin;
  city.mesh.crs = crs;
  for (int k = 0; k < 3; ++k) {
    const double wl = r.U(150, 500), dir = r.U(0, 2 * M_PI);
    city.ground.waves.emplace_back(o.relief_m * r.U(0.3, 1.0) / 2, 2 * M_PI / wl * std::cos(dir),
                                   2 * M_PI / wl * std::sin(dir), r.U(0, 2 * M_PI));
  }
  city.texture.seed = seed;
  city.texture.street_pitch_m = o.street_pitch_m;
  city.texture.street_width_m = o.street_width_m;
  city.texture.street_offset_m = std::floor(r.U(0, o.street_pitch_m));
  AddGround(&city, o);
  const size_t ground_faces = city.mesh.faces.size();
  // Blocks between street centre lines, split into lots with one building each.
  const double reach = o.aoi_size_m / 2 + o.building_margin_m;
  const double inset = o.street_width_m / 2 + o.sidewalk_width_m + 1.0;
  const double off = city.texture.street_offset_m, pitch = o.street_pitch_m;
  const int k0 = int(std::floor((-reach - off) / pitch)) - 1, k1 = int(std::ceil((reach - off) / pitch));
  for (int kx = k0; kx < k1; ++kx)
    for (int ky = k0; ky < k1; ++ky) {
      const Rect block{off + kx * pitch + inset, off + ky * pitch + inset,
                       off + (kx + 1) * pitch - inset, off + (ky + 1) * pitch - inset};
      std::vector<Rect> lots;
      SplitLots(block, 0, r, &lots);
      for (const Rect& lot : lots) {
        const bool near = lot.x1 > -reach && lot.x0 < reach && lot.y1 > -reach && lot.y0 < reach;
        if (near && r.P(0.92)) AddBuilding(&city, o, lot, r);
      }
    }
  if (o.trees) {
    const double lateral = o.street_width_m / 2 + 0.9;
    for (int k = k0; k <= k1; ++k)
      for (int axis = 0; axis < 2; ++axis)
        for (double side : {-1.0, 1.0}) {
          const double c = off + k * pitch + side * lateral;
          for (double a = -reach; a < reach; a += r.U(8, 14)) {
            if (StreetDistance(a, city.texture) < o.street_width_m / 2 + o.sidewalk_width_m + 3) continue;
            if (std::abs(c) > reach || !r.P(0.7)) continue;
            AddTree(&city, axis == 0 ? Eigen::Vector2d(c, a) : Eigen::Vector2d(a, c), r);
          }
        }
  }
  PruneHiddenGround(&city, ground_faces);
  return city;
}

}  // namespace satmesh::synth
