#pragma once
// Ground-truth products of a synthetic scene beyond the DSM: the roof mask and surface
// samples on facades.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/dsm/dsm.h"
#include "core/synth/render.h"

namespace satmesh::synth {

// 1 where the highest surface of a cell is roof (flat or sloped) and no roof edge,
// material change or height step (> 0.5 m between neighbours) lies within edge_band_m.
// `grid` must be in the city mesh's CRS (truth DSM).
std::vector<uint8_t> RoofMask(const RenderScene& scene, const Dsm& truth, double edge_band_m);

// Area-uniform samples on building walls, gable ends and soffits (|n_z| < 0.9 or facing
// down) above the local ground and inside the box [xy_min, xy_max] (scene CRS).
void SampleFacadePoints(const CityModel& city, const Eigen::Vector2d& xy_min,
                        const Eigen::Vector2d& xy_max, double spacing_m, uint64_t seed,
                        std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3f>* normals);

// NMAD (1.4826 median |r - median r|) and 68th percentile of |r| of finite residuals
// a - b on mask cells; {NaN, NaN} if none.
Eigen::Vector2d MaskedNmadP68(const Dsm& a, const Dsm& b, const std::vector<uint8_t>& mask);

}  // namespace satmesh::synth
