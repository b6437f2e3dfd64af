#pragma once
// One pair's walls moved as patches (RefineLevel at level 0, wall_patch_rings).
//
// A wall vertex's photometric gradient across the wall is weak and noisy: a ZNCC window
// sees a wall at grazing incidence, and the wall's foot only once its roof edge has moved.
// With one pair the walls both views see stayed about a pixel out of a DSM start (stereo
// 0.5 m seed 71: its east walls moved 0.16 m by the images, a coarse level's few unknowns
// moved them as one and 0.24 m further; docs/benchmarks-history.md, session 43). Several
// pairs move them themselves (multi-date: to the objective's optimum), and pooling there
// cost 5-9 points of facades (session 44).
//
// So each wall vertex's step across its wall is taken from the patch around it: the
// vertices of the same wall facing within its rings, whose gradients along the vertex's
// wall normal are pooled. Their mean m over n members, where it is at least one standard
// error from zero, replaces the vertex's own component as sqrt(n) m: the step that n
// agreeing vertices' evidence gives, with the noise of one vertex's step (the mean's
// standard error times sqrt(n)). Where the patch does not agree on a direction beyond its
// noise the vertex keeps its own gradient.
#include <Eigen/Core>

#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace satmesh {

// The wall patches of a mesh: per wall vertex its horizontal unit wall normal and the wall
// vertices (itself included) within `rings` edges whose wall normals are within
// kWallPatchMaxTurnDeg of its own (compressed rows).
struct WallPatches {
  std::vector<Eigen::Vector3f> normal;  // per vertex; zero for a vertex of no wall face
  std::vector<int> offsets, members;    // members of vertex v: [offsets[v], offsets[v + 1])
  size_t num_walls() const;             // vertices with a wall normal
};

// A neighbour within the rings joins a patch where its wall normal turns by at most this.
inline constexpr double kWallPatchMaxTurnDeg = 37.0;

// Wall faces are those of WallVertices (edge_bias.h, steeper than 60 degrees); a vertex's
// wall normal is its wall faces' area-weighted horizontal normal. rings 0: each patch is
// its vertex alone.
WallPatches MakeWallPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                            int rings);

// `gradient` (per vertex, 3D) with each wall vertex's component along its wall normal
// replaced by its patch's pooled component (above). Other components and other vertices
// are kept. Returns the number of vertices whose component was replaced.
size_t PoolWallGradients(const WallPatches& patches, std::vector<Eigen::Vector3d>* gradient);

}  // namespace satmesh
