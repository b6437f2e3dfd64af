#pragma once
// Walls hang plumb under their tops (RefineLevel, plumb_walls).
//
// A DSM holds a wall as a slope: its matching spreads the roof's edge over the ground in
// front (s2p's and our generator's DSMs alike), so the initial surface's walls lean out at
// their feet. Where two views see a wall the images move it; where one view or none does
// (multi-date 0.5 m s2: 35% of the facades, five of its six views from the north), nothing
// in the images says where its lower part lies, and the pull towards the initial surface
// keeps the slope: its foot stays a metre out (completeness @0.5 m over the wall's lowest
// fifth 7%, over its highest fifth 52%; docs/benchmarks-history.md, session 46). The wall's
// top is the roof's edge, which the roof's views place. Buildings' walls are vertical, so a
// wall vertex the images constrain weakly is pulled towards the vertical through the top of
// its wall, where its start leans out, in place of its start. A sharp DSM's walls lean by
// at most a cell, which the hang takes up (from the true DSM, stereo 0.5 m seed 71:
// facades 64.1 -> 56.1%, 54.5% since session 47; the refinement alone takes that start's
// 88.2% to 64.1%: a DSM whose walls are in place is declared, trusted_initial); hanging
// half a cell outside the top, climbing a blurred wall's gentler toe, or hanging from the
// top's start traded the degraded DSMs' gain against it or lost more (session 46).
#include <Eigen/Core>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace satmesh {

// A wall vertex's next vertex up its wall: the neighbour, on a wall facing within
// kWallPatchMaxTurnDeg of its own, whose edge rises most steeply, at least this steeply
// (degrees from the horizontal). A DSM's wall rises at 75-85 degrees and its top is where
// the rise eases. At 45 degrees the walk went on over real roofs' rounded shoulders (the
// Pleiades triplet's terraces on their hill: 63 degrees over the metre behind the edge)
// and hung their walls a metre or two behind it: the pairs held out of the refinement lost
// 0.001-0.004 of their ZNCC's rise, at 60 degrees 0.0004-0.0014 (the DSM's own pair fell
// below its bar), at 70 at most 0.0002. On the generator's scenes 70 keeps half to all of
// 45's facade gain, 80 a fifth to most (docs/benchmarks-history.md, session 46).
inline constexpr double kPlumbMinRiseDeg = 70.0;

// Each iteration a hung vertex moves across its wall by this fraction of its offset from
// where it hangs (its start or its top's vertical) times its pull weight (InitialPriorWeights:
// 1 where the images do not constrain it, which then hangs at once, at most max_step_gsd an
// iteration), ten times the pull towards the start (kInitialPullPerIteration). At that pull a
// weakly constrained wall was still on its way after a level's 20 iterations: with 40 it
// went further in (tri-stereo 0.3 m s1 facades @0.5 m 57.8 -> 64.0%). 1 against 0.1, 0.3 and
// 0.5 (docs/benchmarks-history.md, session 47): tri-stereo 0.3 m s1 57.8 / 61.8 / 63.3 ->
// 65.3%, tri-stereo 0.5 m s2 62.0 / 63.3 / 63.9 -> 64.1%, multi-date 0.3 m s2 56.3 / 56.6 /
// 57.1 -> 57.4%, stereo 0.5 m s1 51.0 -> 51.4%, roofs within 0.002 m; the Pleiades held-out
// pairs' rise 0.0001-0.0003 lower.
inline constexpr double kPlumbPullPerIteration = 1.0;

// Per vertex: its wall's horizontal unit normal (WallNormals; zero: no wall vertex) and the
// top of its wall, the vertex where the walk up its wall's steepest edges ends (-1: none,
// the vertex is its wall's top or on no wall).
struct PlumbLines {
  std::vector<Eigen::Vector3f> normal;
  std::vector<int> top;
  size_t num_hung() const;  // vertices with a top
};

PlumbLines MakePlumbLines(const TriangleMesh& mesh, const VertexAdjacency& adjacency);

// Per vertex of `vertices`, how far it lies outside the vertical through its top, along its
// wall's normal (m; negative: inside; 0 without a top). Empty for lines without vertices.
std::vector<float> PlumbOffsets(const PlumbLines& lines,
                                const std::vector<Eigen::Vector3f>& vertices);

}  // namespace satmesh
