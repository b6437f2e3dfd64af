#pragma once
// Gradients pooled over patches of the surface at level 0 (RefineLevel): one pair's walls
// (wall_patch_rings) and the roofs and ground the images alone barely constrain
// (roof_patch_rings), each moved as a patch where the patch agrees beyond its noise.
//
// Walls.
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
//
// Roofs and ground. A vertex of a weakly textured roof is held near the initial surface by
// the pull towards it (InitialPriorWeights), and its own gradient is the images' noise: a
// roof the initial DSM has 0.5-0.75 m too high stays 0.2-0.6 m too high while its edges and
// what texture it has say where it lies (one pair; docs/benchmarks-history.md, session 42).
// So a non-wall vertex whose images constrain its height less than the initial surface's
// sigma does (its pull weight at least kRoofPatchMinPriorWeight) takes its step along its
// normal from its patch as a wall vertex does: the non-wall vertices within its rings whose
// normals turn by at most kWallPatchMaxTurnDeg (a roof's plane, not across its ridge or
// down its walls), with kRoofPatchStepFactor of the wall's step. A vertex the images
// constrain keeps its own gradient: on the Pleiades triplet's textured roofs almost all do,
// and pooling every roof vertex there lowered the held-out pairs' ZNCC
// (docs/benchmarks-history.md, session 45).
#include <Eigen/Core>

#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace satmesh {

// Patches of a mesh's vertices: per vertex a unit direction (zero: none; it takes part in
// no patch) and its patch, the vertices (itself first) within `rings` edges whose
// directions are within kWallPatchMaxTurnDeg of its own, pooled along its direction
// (compressed rows; empty where the vertex has no patch of its own).
struct GradientPatches {
  std::vector<Eigen::Vector3f> normal;  // per vertex; zero: none
  std::vector<int> offsets, members;    // members of vertex v: [offsets[v], offsets[v + 1])
  double step_factor = 1.0;             // the pooled component is this x sqrt(n) m
  size_t num_directed() const;          // vertices with a direction
  size_t num_patches() const;           // vertices with a patch of their own
};

// A neighbour within the rings joins a patch where its direction (wall normal, or a roof
// vertex's normal) turns by at most this.
inline constexpr double kWallPatchMaxTurnDeg = 37.0;

// A patch's mean replaces a vertex's component where it is at least this many standard
// errors from zero. Under no true direction sqrt(n) m is as noisy as one vertex's component
// but moves the whole patch as one; at 1 standard error (32% of noise patches pass) walls
// started on the truth drifted (stereo 0.5 m seed 71 from the true DSM: F 74.2 -> 73.5,
// facades 64.0 -> 63.1%), at 2 (5% pass) they stay (74.2, 64.1%) and a DSM start's walls
// still come in (docs/benchmarks-history.md, session 44).
inline constexpr double kWallPatchSignificance = 2.0;

// The wall patches: wall faces are those of WallVertices (edge_bias.h, steeper than 60
// degrees); a vertex's direction is its wall faces' area-weighted horizontal normal (zero
// for a vertex of no wall face). rings 0: each patch is its vertex alone.
GradientPatches MakeWallPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                                int rings);

// A non-wall vertex's pull weight (InitialPriorWeights) from which it takes its patch's
// step: 0.5, where the images alone constrain its height as much as the initial surface's
// sigma does. Stereo 0.5 m: pooling every roof vertex gives s2 and seed 51 0.006-0.011 m more
// roofs than 0.5, 0.3 0.004-0.009 m, but the Pleiades pairs held out of both the s2p DSM and
// the refinement lose 0.0010-0.0013 of their ZNCC's rise (0.3: 0.0002; 0.5: none, the DSM's
// own pairs 0.0001-0.0002; docs/benchmarks-history.md, session 45).
inline constexpr double kRoofPatchMinPriorWeight = 0.5;

// A roof patch's pooled component is this times sqrt(n) m. Neighbouring vertices' ZNCC
// windows overlap, so n roof vertices' gradients are not n independent measurements: the
// full sqrt(n) m doubled the drift from a true start (stereo 0.5 m s1 from the truth mesh:
// roofs NMAD 0.010 -> 0.019 m, F 98.7 -> 98.1; at 0.5 0.015, 98.4), where a striped gable
// roof's periodic texture gives one pair a consistent wrong match, and keeps 65-80% of the
// DSM starts' roof gain (s2, seeds 51 and 77; docs/benchmarks-history.md, session 45).
inline constexpr double kRoofPatchStepFactor = 0.5;

// The roof patches: a vertex of no wall face whose prior_weight (per vertex) is at least
// kRoofPatchMinPriorWeight gets its vertex normal as its direction and the vertices of no
// wall face within `rings` edges whose normals turn by at most kWallPatchMaxTurnDeg as its
// patch; other vertices have none (but join the patches around them). step_factor
// kRoofPatchStepFactor.
GradientPatches MakeRoofPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                                int rings, const std::vector<float>& prior_weight);

// `gradient` (per vertex, 3D) with each patch's vertex's component along its direction
// replaced by its patch's pooled component (above). Other components and other vertices
// are kept, and so are vertices `moves` (per vertex; null: all) marks 0 (the level holds
// them: no pair-direction sees them). Returns the number of vertices whose component was
// replaced.
size_t PoolPatchGradients(const GradientPatches& patches, std::vector<Eigen::Vector3d>* gradient,
                          const std::vector<int>* moves = nullptr);

}  // namespace satmesh
