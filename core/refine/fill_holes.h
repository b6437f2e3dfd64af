#pragma once
// The holes of an initial mesh filled before it is refined (core/tiling/initial_mesh.cc).
#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace satmesh {

// The result of FillHoles.
struct HoleFill {
  size_t filled = 0;   // holes triangulated
  size_t too_big = 0;  // holes left: larger than the limit
  size_t covered = 0;  // holes left: the mesh covers them from above (no gap to the images)
  size_t faces_added = 0;
};

// Fills the holes of a surface (x, y on the map, z up; metres): each border cycle that
// runs counter-clockwise seen from above (a hole in a surface whose faces face up; an
// outer border runs clockwise, as does a building's open base) whose extent (diagonal of
// its x, y box) is at most max_extent_m and which nothing covers from above (a ray up
// from its centroid hits no face: the ground's cut-out under a building is no gap) is
// triangulated, refined to its border's edge lengths and faired
// (CGAL::Polygon_mesh_processing::triangulate_refine_and_fair_hole).
// Faces CGAL cannot take (non-manifold) are kept as they are. New points and faces are
// appended; existing indices stay valid.
HoleFill FillHoles(double max_extent_m, std::vector<Eigen::Vector3d>* points,
                   std::vector<Eigen::Vector3i>* faces);

}  // namespace satmesh
