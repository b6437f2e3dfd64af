#pragma once
// Debris removal: the elements a cut (tile trimming, clipping to a box) or a careless
// exporter leaves behind, and that tools downstream choke on (Open3D 0.16 aborts on a
// zero-area triangle when it computes point-to-mesh distances).
#include <cstddef>
#include <string>

#include "core/mesh/mesh.h"

namespace satmesh {

struct MeshCleanOptions {
  // Vertices closer than this are one vertex (m, > 0). Tile-local floats resolve ~0.1 mm
  // at 1 km from the origin, so a cut point this close to a vertex is that vertex.
  double merge_distance_m = 1e-3;
  // A face whose smallest height (2 area / longest edge) is below this is degenerate
  // (m, > 0): a needle or a zero-area triangle (three collinear points).
  double min_face_height_m = 1e-3;
  std::string Check() const;
};

// What FindDebris counts and CleanMesh removes.
struct MeshDebris {
  size_t close_vertices = 0;         // vertices within merge_distance_m of an earlier one
  size_t degenerate_faces = 0;       // repeated vertex (after merging) or below min height
  size_t duplicate_faces = 0;        // the same three vertices as an earlier face
  size_t unreferenced_vertices = 0;  // used by no face (after the above)
  size_t Total() const {
    return close_vertices + degenerate_faces + duplicate_faces + unreferenced_vertices;
  }
  std::string ToString() const;      // "2 close vertices, 0 degenerate faces, ..."
};

// Merges close vertices (the first of a cluster stays; height_sigma follows it), drops
// degenerate and duplicate faces, then unreferenced vertices. Face order and orientation
// of what is kept are unchanged. O(n) expected (spatial hash). Returns what it removed.
MeshDebris CleanMesh(TriangleMesh* mesh, const MeshCleanOptions& options = {});

// The same counts without changing the mesh (a clean mesh gives all zeros).
MeshDebris FindDebris(const TriangleMesh& mesh, const MeshCleanOptions& options = {});

}  // namespace satmesh
