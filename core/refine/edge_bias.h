#pragma once
// The photometric term's bias at occluding edges, and its removal.
//
// A pixel at a roof edge mixes the roof's radiance with what lies beyond it (the optics'
// blur, the pixel's own footprint). Between two views such mixed pixels move with the
// edge, i.e. with the foreground's parallax, so a ZNCC window over them agrees best when
// the foreground surface claims them: the objective prefers every occluding edge about
// half a pixel too far out. Measured with the refinement's own objective on the truth
// meshes of the synthetic scenes (`satmesh zncc`, common windows, stereo 0.5 m s1): the
// truth 0.4125, its walls moved out by 0.1 / 0.2 / 0.3 / 0.4 m 0.4186 / 0.4204 / 0.4195 /
// 0.4184; at 0.3 m GSD the best is 0.1-0.15 m out: 0.4-0.6 px either way
// (docs/benchmarks-history.md, session 35). The refined walls end where the objective
// peaks, so this bias is taken off at the end (Refine's step 4b).
#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

// A face is part of a wall (an occluding edge's flank) when its normal's |z| is below this
// (steeper than 60 degrees).
inline constexpr float kWallMaxNormalZ = 0.5f;

// Per vertex, 1 if it belongs to a wall face (|normal z| < kWallMaxNormalZ).
std::vector<char> WallVertices(const TriangleMesh& mesh);

// Per vertex, the horizontal unit normal of its wall faces (their horizontal normals
// weighted by area); zero for a vertex of no wall face.
std::vector<Eigen::Vector3f> WallNormals(const TriangleMesh& mesh);

struct EdgeBiasStats {
  size_t moved = 0;  // vertices moved
};

// Moves every vertex of a wall face, other than boundary vertices (tile seams), so that its
// walls move `distance_m` inward horizontally (least squares over its wall faces' outward
// normals, weighted by area: a vertex of one wall moves against its normal, a corner into
// the corner): walls, their tops and feet shift inward together; roofs and the ground away
// from walls stay. distance_m < 0 moves them outward (a fattened surface, as the tests
// compare); 0: nothing moves.
EdgeBiasStats DeflateOccludingEdges(double distance_m, TriangleMesh* mesh);

}  // namespace satmesh
