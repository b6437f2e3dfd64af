#include "core/refine/gradient_patch.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/refine/edge_bias.h"

namespace satmesh {

size_t GradientPatches::num_directed() const {
  return size_t(std::count_if(normal.begin(), normal.end(),
                              [](const Eigen::Vector3f& n) { return !n.isZero(); }));
}

namespace {

// The patches of the vertices `centre` marks (null: all) over the directions `normal`.
GradientPatches MakePatches(std::vector<Eigen::Vector3f> normal, const VertexAdjacency& adjacency,
                            int rings, const std::vector<char>* centre) {
  GradientPatches patches;
  const size_t nv = normal.size();
  patches.normal = std::move(normal);
  const float min_dot = float(std::cos(kWallPatchMaxTurnDeg * M_PI / 180));
  // Breadth-first over the vertices of a similar direction, each thread over a contiguous
  // range of vertices (their patches are joined in vertex order); `mark` holds the vertex
  // whose patch last took a vertex.
  const int threads = std::max(1, omp_get_max_threads());
  std::vector<std::vector<int>> members(threads), sizes(threads);
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num();
    const size_t begin = nv * size_t(t) / size_t(threads), end = nv * size_t(t + 1) / size_t(threads);
    std::vector<int> mark(nv, -1), frontier, next;
    for (size_t v = begin; v < end; ++v) {
      const size_t before = members[t].size();
      const Eigen::Vector3f& h = patches.normal[v];
      if (!h.isZero() && (!centre || (*centre)[v])) {
        mark[v] = int(v);
        members[t].push_back(int(v));
        frontier.assign(1, int(v));
        for (int r = 0; r < rings && !frontier.empty(); ++r) {
          next.clear();
          for (int u : frontier) {
            for (int k = adjacency.neighbor_offsets[u]; k < adjacency.neighbor_offsets[u + 1]; ++k) {
              const int w = adjacency.neighbors[k];
              if (mark[w] == int(v) || patches.normal[w].dot(h) < min_dot) continue;
              mark[w] = int(v);
              next.push_back(w);
              members[t].push_back(w);
            }
          }
          frontier.swap(next);
        }
      }
      sizes[t].push_back(int(members[t].size() - before));
    }
  }
  patches.offsets.assign(nv + 1, 0);
  size_t v = 0;
  for (int t = 0; t < threads; ++t) {
    for (int n : sizes[t]) patches.offsets[v + 1] = patches.offsets[v] + n, ++v;
    patches.members.insert(patches.members.end(), members[t].begin(), members[t].end());
  }
  return patches;
}

}  // namespace

size_t GradientPatches::num_patches() const {
  size_t n = 0;
  for (size_t v = 0; v + 1 < offsets.size(); ++v) n += offsets[v + 1] > offsets[v];
  return n;
}

GradientPatches MakeWallPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                                int rings) {
  return MakePatches(WallNormals(mesh), adjacency, rings, nullptr);
}

GradientPatches MakeRoofPatches(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                                int rings, const std::vector<float>& prior_weight) {
  std::vector<Eigen::Vector3f> normal = VertexNormals(mesh);
  const std::vector<Eigen::Vector3f> wall = WallNormals(mesh);
  std::vector<char> weak(normal.size(), 0);
  for (size_t v = 0; v < normal.size(); ++v) {
    if (!wall[v].isZero()) normal[v].setZero();
    weak[v] = !normal[v].isZero() && prior_weight[v] >= kRoofPatchMinPriorWeight;
  }
  GradientPatches patches = MakePatches(std::move(normal), adjacency, rings, &weak);
  patches.step_factor = kRoofPatchStepFactor;
  return patches;
}

size_t PoolPatchGradients(const GradientPatches& patches, std::vector<Eigen::Vector3d>* gradient,
                          const std::vector<int>* moves) {
  const std::vector<Eigen::Vector3d>& g = *gradient;
  const long nv = long(g.size());
  // Each replaced vertex's new component first (its patch reads the gradients as they came),
  // then written.
  std::vector<double> pooled(nv, std::numeric_limits<double>::quiet_NaN());
  size_t replaced = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : replaced)
  for (long v = 0; v < nv; ++v) {
    if (moves && (*moves)[v] == 0) continue;
    const int begin = patches.offsets[v], end = patches.offsets[v + 1];
    const double n = end - begin;
    if (n < 3) continue;  // no spread to test against (n = 0: no patch of its own)
    const Eigen::Vector3d h = patches.normal[v].cast<double>();
    double sum = 0, sum2 = 0;
    for (int k = begin; k < end; ++k) {
      const double x = g[patches.members[k]].dot(h);
      sum += x, sum2 += x * x;
    }
    const double mean = sum / n;
    const double variance = std::max(0.0, (sum2 - n * mean * mean) / (n - 1));
    if (std::abs(mean) < kWallPatchSignificance * std::sqrt(variance / n)) continue;
    pooled[v] = patches.step_factor * std::sqrt(n) * mean;
    ++replaced;
  }
#pragma omp parallel for schedule(static)
  for (long v = 0; v < nv; ++v) {
    if (std::isnan(pooled[v])) continue;
    const Eigen::Vector3d h = patches.normal[v].cast<double>();
    (*gradient)[v] += (pooled[v] - (*gradient)[v].dot(h)) * h;
  }
  return replaced;
}

}  // namespace satmesh
