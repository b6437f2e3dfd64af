#pragma once
// Which suns light each view's surface points (moving shadows of a multi-date view set).
// Two images of different dates see a surface point under different suns: where it lies
// in shadow in one and in sunlight in the other, their difference is not the gain and
// offset ZNCC allows for, and the pair says nothing about the point's height there.
#include <Eigen/Core>

#include <cstdint>
#include <utility>
#include <vector>

#include "core/image/acquisition_info.h"
#include "core/mesh/mesh.h"
#include "core/refine/view_level.h"

namespace satmesh {

// Unit direction towards the sun in the local frame (x east, y north, z up), or zero
// when the acquisition does not say where the sun was.
Eigen::Vector3f SunDirection(const AcquisitionInfo& acquisition);

// For every view in `views` and each of its hit pixels: bit s of hit_map.sunlit set when
// the hit point is lit by sun_directions[s] (a ray from just off the surface towards it
// hits nothing of `mesh`), for the suns s < 64 with a non-zero direction of the view
// itself and of its partners in `pairs` (view indices; the only suns its pair-directions
// compare); 0 where the pixel hits nothing. hit_map.suns_marked says which s were traced.
// `mesh` and the views' hit maps must be current and in the same frame.
void MarkSunlight(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& face_normals,
                  const std::vector<Eigen::Vector3f>& sun_directions,
                  const std::vector<std::pair<int, int>>& pairs, std::vector<ViewLevel>* views);

}  // namespace satmesh
