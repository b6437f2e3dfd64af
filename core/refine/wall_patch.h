#pragma once
// One pair's walls moved as patches (RefineLevel at level 0, wall_patch_rings).
//
// A wall vertex's photometric gradient across the wall is weak and noisy: a ZNCC window
// sees a wall at grazing incidence, and the wall's foot only once its roof edge has moved.
// With one pair the walls both views see stayed about a pixel out of a DSM start (stereo
// 0.5 m seed 71: its east walls moved 0.16 m by the images, a coarse level's few unknowns
// moved them as one and 0.24 m further; docs/benchmarks-history.md, session 43). Several
// pairs move them themselves (multi-date: to the objective's optimum), and pooling there
// cost up to 2 points of facades and 1 of F (session 44).
//
// So each wall vertex's step across its wall is taken from the patch around it: the
// vertices of the same wall facing within its rings, whose gradients along the vertex's
// wall normal are pooled. Their mean m over n members, where it is at least
// kWallPatchSignificance standard errors from zero, replaces the vertex's own component as
// sqrt(n) m: the step that n agreeing vertices' evidence gives, with the noise of one
// vertex's step (the mean's standard error times sqrt(n)). Where the patch does not agree on
// a direction beyond its noise the vertex keeps its own gradient.
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

// A patch's mean replaces a vertex's component where it is at least this many standard
// errors from zero. Under no true direction sqrt(n) m is as noisy as one vertex's component
// but moves the whole patch as one; at 1 standard error (32% of noise patches pass) walls
// started on the truth drifted (stereo 0.5 m seed 71 from the true DSM: F 74.2 -> 73.5,
// facades 64.0 -> 63.1%), at 2 (5% pass) they stay (74.2, 64.1%) and a DSM start's walls
// still come in (docs/benchmarks-history.md, session 44).
inline constexpr double kWallPatchSignificance = 2.0;

// Wall faces are those of WallVertices (edge_bias.h, steeper than 60 degrees); a vertex's
// wall normal is its wall faces' area-weighted horizontal normal. rings 0: each patch is
// its vertex alone.
WallPatches MakeWallPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                            int rings);

// `gradient` (per vertex, 3D) with each wall vertex's component along its wall normal
// replaced by its patch's pooled component (above). Other components and other vertices
// are kept, and so are vertices `moves` (per vertex; null: all) marks 0 (the level holds
// them: no pair-direction sees them). Returns the number of vertices whose component was
// replaced.
size_t PoolWallGradients(const WallPatches& patches, std::vector<Eigen::Vector3d>* gradient,
                         const std::vector<int>* moves = nullptr);

}  // namespace satmesh
