#pragma once
// One photometric pass: the mean ZNCC and the gradient of every pair-direction through a
// fixed mesh (RefineLevel's iterations, MeasurePass), the directions shared among the
// threads.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/view_level.h"

namespace satmesh {

// One thread's buffers of the photometric pass, kept across iterations: they are tens
// of MB a thread at level 0, and fresh ones cost page faults and zeroing every pass.
struct PassScratch {
  GradientAccumulator accumulator;
  PairWorkspace workspace;
};

// The pair-directions (i, j) of `pairs`: both, or with one_direction >= 0 pair k as (i, j)
// if (one_direction + k) is even, else as (j, i).
std::vector<std::pair<int, int>> PairDirections(const std::vector<std::pair<int, int>>& pairs,
                                                int one_direction);

// Mean ZNCC over all pair-directions; fills the gradient and per-vertex pair counts.
// Pair-directions run in parallel (one per thread, or one after the other with every
// thread in each: OnePerThread; gathered per face by each thread's accumulator, added to
// the vertices once at the end). The views' hit maps, with their ray cosines, must be
// current for the mesh and its face normals; adjacency: the mesh's (BuildVertexAdjacency).
double PhotometricPass(std::vector<ViewLevel>& views, const std::vector<int>& slot,
                       const std::vector<std::pair<int, int>>& pairs, const TriangleMesh& mesh,
                       const std::vector<Eigen::Vector3f>& normals,
                       const VertexAdjacency& adjacency, const PhotometricOptions& options,
                       std::vector<PassScratch>* scratch,
                       std::vector<Eigen::Vector3d>* gradient, std::vector<int>* seen,
                       int one_direction = -1, std::vector<double>* information = nullptr,
                       std::vector<PairEnergy>* energies = nullptr,
                       std::vector<std::vector<float>>* windows = nullptr);

}  // namespace satmesh
