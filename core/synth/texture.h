#pragma once
// Procedural surface reflectance as a function of the 3D point, the surface normal and a
// material: usable for any mesh (a single tilted plane as much as the synthetic city).
// Rich at the 0.3 m scale, built from hashed lattice noise, so it is not periodic.
#include <Eigen/Core>
#include <cstdint>

namespace satmesh::synth {

enum class Material : uint8_t {
  kGrass = 0,
  kRoad,        // asphalt with lane markings along the street grid
  kSidewalk,    // concrete slabs
  kRoofGravel,  // flat roof
  kRoofPanel,   // solar panels / metal sheet on flat roofs
  kRoofTiles,   // sloped roofs
  kFacade,      // walls with window grids
  kSoffit,      // underside of overhangs, arcade ceilings
  kRooftop,     // rooftop structures (HVAC, stair housings)
  kTree,
  kCount
};

bool IsRoof(Material m);
bool IsBuilding(Material m);  // roof, facade, soffit or rooftop structure
const char* MaterialName(Material m);

struct TextureParams {
  uint32_t seed = 1;               // noise seed
  double street_pitch_m = 80;      // street grid period (lane markings), > 0
  double street_offset_m = 0;      // position of a street centre line, m
  double street_width_m = 12;      // kerb to kerb, m, > 0
};

// Reflectance in (0, 1) at scene point p (metres, any frame with z up) with unit normal n.
// `variant` selects per-object parameters (e.g. a building's colour and window layout).
float Albedo(Material material, uint32_t variant, const Eigen::Vector3f& p,
             const Eigen::Vector3f& n, const TextureParams& params = {});

// Smooth value noise in [-1, 1] (trilinear on a hashed lattice of unit spacing).
float ValueNoise(const Eigen::Vector3f& p, uint32_t seed);
// Fractal sum of `octaves` value noises, first at `scale_m`, halving; in about [-1, 1].
float Fbm(const Eigen::Vector3f& p, float scale_m, int octaves, uint32_t seed);
// Uniform hash in [0, 1) of an integer triple.
float Hash01(int32_t x, int32_t y, int32_t z, uint32_t seed);

}  // namespace satmesh::synth
