#pragma once
// A mesh start's coarse levels carried onto the start itself (CoarseToFine in refine.cc).
#include "core/mesh/mesh.h"

namespace satmesh {

// The displacement a level made carried onto another mesh of the same surface: each vertex
// of `target` moves as the point of `start` closest to it moved (`start` and `end`: one
// topology, the level's mesh before and after its iterations; barycentric in the closest
// face, CGAL's AABB tree), times its up-facing weight (1 where its normal is within 37
// degrees of up, n_z >= 0.8; 0 from 60 degrees, n_z <= 0.5: walls, undersides; linear
// between) and the weight of that face being of its surface (1 where their normals are
// within 18 degrees, 0 from 37: near a wall a coarse mesh bridges roof and street). So a finer level of a mesh start begins from the user's mesh, walls and eaves
// kept, with roofs and ground corrected by what the coarser level found at its scale,
// rather than from the coarser level's remesh (CoarseToFine; walls moved too cost 3 points
// of facades on a stereo 0.5 m scene, docs/benchmarks-history.md, session 21). All three
// meshes in one frame (x east, y north, z up; one origin). Throws Error{kInvalidArgument} if start and end differ in vertices or
// start has no face.
TriangleMesh CarryDisplacement(const TriangleMesh& start, const TriangleMesh& end,
                               TriangleMesh target);

}  // namespace satmesh
