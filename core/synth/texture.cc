#include "core/synth/texture.h"

#include <algorithm>
#include <cmath>

namespace satmesh::synth {
namespace {

uint32_t Mix(uint32_t h) {  // murmur3 finaliser
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

float Smooth(float t) { return t * t * (3.f - 2.f * t); }
float Frac(float x) { return x - std::floor(x); }
float Lerp(float a, float b, float t) { return a + (b - a) * t; }

// Per-variant parameter in [lo, hi).
float VariantParam(uint32_t variant, int slot, float lo, float hi) {
  return lo + (hi - lo) * Hash01(int32_t(variant), slot, 7, 0x5eed);
}

// Fine grain: independent values per cell of `cell_m` (sensor-scale texture).
float Grain(const Eigen::Vector3f& p, float cell_m, uint32_t seed) {
  return Hash01(int32_t(std::floor(p.x() / cell_m)), int32_t(std::floor(p.y() / cell_m)),
                int32_t(std::floor(p.z() / cell_m)), seed) - 0.5f;
}

float Road(const Eigen::Vector3f& p, const TextureParams& tp) {
  float a = 0.10f + 0.025f * Fbm(p, 3.f, 3, tp.seed + 11) + 0.05f * Grain(p, 0.12f, tp.seed + 12);
  if (Fbm(p, 12.f, 2, tp.seed + 13) > 0.45f) a -= 0.025f;  // patched asphalt
  const float pitch = float(tp.street_pitch_m), half = float(tp.street_width_m) / 2;
  const float fx = Frac((p.x() - float(tp.street_offset_m)) / pitch + 0.5f) - 0.5f;
  const float fy = Frac((p.y() - float(tp.street_offset_m)) / pitch + 0.5f) - 0.5f;
  const float dx = std::abs(fx) * pitch, dy = std::abs(fy) * pitch;  // to centre lines
  const bool ns = dx < dy;  // on a north-south street
  const float lateral = ns ? dx : dy, other = ns ? dy : dx;
  const float along = ns ? p.y() : p.x();
  if (other < half) return a;  // intersection
  if (other < half + 3.5f && other > half + 0.5f && Frac(lateral / 0.9f) < 0.5f &&
      lateral < half - 0.3f)
    return 0.55f + 0.05f * Grain(p, 0.2f, tp.seed + 14);  // crosswalk
  if (lateral < 0.08f && Frac(along / 6.f) < 0.5f) return 0.6f;  // dashed centre line
  if (std::abs(lateral - (half - 0.4f)) < 0.07f) return 0.5f;     // edge line
  return std::max(0.02f, a);
}

float Facade(uint32_t v, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  const Eigen::Vector2f t = Eigen::Vector2f(-n.y(), n.x()).normalized();
  const float u = p.x() * t.x() + p.y() * t.y(), z = p.z();
  const float wall = VariantParam(v, 1, 0.22f, 0.55f) + 0.04f * Fbm(p, 2.f, 2, v) +
                     0.03f * Grain(p, 0.15f, v + 1);
  const float floor_h = VariantParam(v, 2, 3.0f, 3.8f), bay = VariantParam(v, 3, 2.2f, 3.8f);
  const float win_w = bay * VariantParam(v, 4, 0.35f, 0.75f);
  const float win_h = floor_h * VariantParam(v, 5, 0.4f, 0.65f);
  const float fu = Frac(u / bay) * bay, fz = Frac(z / floor_h) * floor_h;
  const float u0 = (bay - win_w) / 2, z0 = floor_h * 0.3f;
  if (fu < u0 || fu > u0 + win_w || fz < z0 || fz > z0 + win_h) return wall;
  const float frame = 0.08f;
  if (fu < u0 + frame || fu > u0 + win_w - frame || fz < z0 + frame || fz > z0 + win_h - frame)
    return std::min(0.9f, wall + 0.15f);
  // Glass: per-window reflection, a few lit or curtained windows.
  const int iu = int(std::floor(u / bay)), iz = int(std::floor(z / floor_h));
  const float r = Hash01(iu, iz, int32_t(v), 99);
  return (r > 0.85f ? 0.35f : 0.07f + 0.08f * r) + 0.02f * Grain(p, 0.2f, v + 2);
}

}  // namespace

// One murmur finaliser over a linear mix of the lattice coordinates (cheap enough to call
// eight times per noise sample; no visible lattice structure at the scales used).
float Hash01(int32_t x, int32_t y, int32_t z, uint32_t seed) {
  const uint32_t h = Mix(uint32_t(x) * 0x9e3779b1u + uint32_t(y) * 0x85ebca77u +
                         uint32_t(z) * 0xc2b2ae3du + Mix(seed));
  return float(h >> 8) * (1.f / 16777216.f);
}

float ValueNoise(const Eigen::Vector3f& p, uint32_t seed) {
  const float fx = std::floor(p.x()), fy = std::floor(p.y()), fz = std::floor(p.z());
  const float tx = Smooth(p.x() - fx), ty = Smooth(p.y() - fy), tz = Smooth(p.z() - fz);
  const uint32_t hx = uint32_t(int32_t(fx)) * 0x9e3779b1u, hy = uint32_t(int32_t(fy)) * 0x85ebca77u;
  const uint32_t hz = uint32_t(int32_t(fz)) * 0xc2b2ae3du + Mix(seed);
  float c[8];
  for (int k = 0; k < 8; ++k) {
    const uint32_t h = Mix(hx + (k & 1) * 0x9e3779b1u + hy + ((k >> 1) & 1) * 0x85ebca77u + hz +
                           (k >> 2) * 0xc2b2ae3du);
    c[k] = float(h >> 8) * (1.f / 16777216.f);
  }
  const float a = Lerp(Lerp(c[0], c[1], tx), Lerp(c[2], c[3], tx), ty);
  const float b = Lerp(Lerp(c[4], c[5], tx), Lerp(c[6], c[7], tx), ty);
  return 2.f * Lerp(a, b, tz) - 1.f;
}

float Fbm(const Eigen::Vector3f& p, float scale_m, int octaves, uint32_t seed) {
  float sum = 0, amp = 1, norm = 0, s = scale_m;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * ValueNoise(p / s, seed + 131u * uint32_t(o));
    norm += amp;
    amp *= 0.5f;
    s *= 0.5f;
  }
  return sum / norm;
}

bool IsRoof(Material m) {
  return m == Material::kRoofGravel || m == Material::kRoofPanel || m == Material::kRoofTiles;
}
bool IsBuilding(Material m) {
  return IsRoof(m) || m == Material::kFacade || m == Material::kSoffit || m == Material::kRooftop;
}

const char* MaterialName(Material m) {
  static const char* names[] = {"grass",      "road",   "sidewalk", "roof_gravel",
                                "roof_panel", "roof_tiles", "facade", "soffit",
                                "rooftop",    "tree"};
  return m < Material::kCount ? names[int(m)] : "unknown";
}

float Albedo(Material material, uint32_t v, const Eigen::Vector3f& p, const Eigen::Vector3f& n,
             const TextureParams& tp) {
  const uint32_t s = tp.seed * 7919u;
  float a = 0.2f;
  switch (material) {
    case Material::kGrass:
      a = 0.11f + 0.05f * Fbm(p, 5.f, 3, s + 1) + 0.04f * Grain(p, 0.25f, s + 2);
      if (Fbm(p, 9.f, 2, s + 3) > 0.4f) a += 0.06f;  // dry patches
      break;
    case Material::kRoad: a = Road(p, tp); break;
    case Material::kSidewalk: {
      const float slab = 1.5f;
      const float jx = Frac(p.x() / slab) * slab, jy = Frac(p.y() / slab) * slab;
      a = 0.30f + 0.06f * (Hash01(int(std::floor(p.x() / slab)), int(std::floor(p.y() / slab)), 0,
                                  s + 4) - 0.5f) +
          0.03f * Grain(p, 0.1f, s + 5) + 0.03f * Fbm(p, 4.f, 2, s + 6);
      if (jx < 0.06f || jy < 0.06f) a -= 0.08f;
      break;
    }
    case Material::kRoofGravel:
      a = VariantParam(v, 6, 0.25f, 0.5f) + 0.05f * Fbm(p, 3.f, 2, v + s) +
          0.06f * Grain(p, 0.12f, v + s + 1);
      if (Fbm(p, 6.f, 2, v + s + 2) > 0.35f) a -= 0.07f;  // stains
      break;
    case Material::kRoofPanel: {
      const float px = Frac(p.x() / 1.1f), py = Frac(p.y() / 1.8f);
      a = (px < 0.08f || py < 0.06f) ? 0.4f : 0.07f + 0.03f * Grain(p, 0.3f, s + 7);
      break;
    }
    case Material::kRoofTiles: {
      const Eigen::Vector2f d = Eigen::Vector2f(n.x(), n.y()).normalized();
      const float along = p.x() * d.x() + p.y() * d.y();
      a = VariantParam(v, 7, 0.14f, 0.36f) * (0.8f + 0.2f * std::sin(along * 2 * float(M_PI) / 0.4f)) +
          0.04f * Fbm(p, 2.f, 2, v + s + 3) + 0.03f * Grain(p, 0.2f, v + s + 4);
      break;
    }
    case Material::kFacade: a = Facade(v + s, p, n); break;
    case Material::kSoffit: a = 0.25f + 0.04f * Fbm(p, 1.f, 2, s + 8); break;
    case Material::kRooftop: {
      const float rib = std::abs(n.z()) > 0.7f ? p.x() : p.z();
      a = 0.45f + 0.08f * std::sin(rib * 2 * float(M_PI) / 0.5f) + 0.04f * Grain(p, 0.2f, s + 9);
      break;
    }
    case Material::kTree:
      a = 0.09f + 0.06f * Fbm(p, 1.2f, 3, s + 10) + 0.04f * Grain(p, 0.3f, s + 11);
      break;
    default: break;
  }
  return std::clamp(a, 0.02f, 0.95f);
}

}  // namespace satmesh::synth
