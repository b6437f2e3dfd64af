#include "core/refine/plumb_walls.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/refine/edge_bias.h"
#include "core/refine/gradient_patch.h"

namespace satmesh {

size_t PlumbLines::num_hung() const {
  return size_t(std::count_if(top.begin(), top.end(), [](int t) { return t >= 0; }));
}

PlumbLines MakePlumbLines(const TriangleMesh& mesh, const VertexAdjacency& adjacency) {
  PlumbLines lines;
  lines.normal = WallNormals(mesh);
  const long nv = long(mesh.vertices.size());
  const float min_dot = float(std::cos(kWallPatchMaxTurnDeg * M_PI / 180));
  const float min_slope = float(std::tan(kPlumbMinRiseDeg * M_PI / 180));
  // Per vertex, the next vertex up its wall (-1: none).
  std::vector<int> up(nv, -1);
#pragma omp parallel for schedule(static)
  for (long v = 0; v < nv; ++v) {
    const Eigen::Vector3f& h = lines.normal[v];
    if (h.isZero()) continue;
    const Eigen::Vector3f& p = mesh.vertices[v];
    float best = min_slope;
    for (int k = adjacency.neighbor_offsets[v]; k < adjacency.neighbor_offsets[v + 1]; ++k) {
      const int u = adjacency.neighbors[k];
      if (lines.normal[u].dot(h) < min_dot) continue;
      const Eigen::Vector3f d = mesh.vertices[u] - p;
      const float rise = d.z(), run = d.head<2>().norm();
      if (rise <= 0 || rise < best * run) continue;
      best = run > 0 ? rise / run : std::numeric_limits<float>::infinity();
      up[v] = u;
    }
  }
  // Each walk rises, so it ends; a wall's height in edges bounds it.
  lines.top.assign(nv, -1);
#pragma omp parallel for schedule(static)
  for (long v = 0; v < nv; ++v) {
    int t = up[v];
    if (t < 0) continue;
    while (up[t] >= 0) t = up[t];
    lines.top[v] = t;
  }
  return lines;
}

std::vector<float> PlumbOffsets(const PlumbLines& lines,
                                const std::vector<Eigen::Vector3f>& vertices) {
  std::vector<float> offset(lines.top.size(), 0.f);
  for (size_t v = 0; v < offset.size(); ++v)
    if (const int t = lines.top[v]; t >= 0)
      offset[v] = (vertices[v] - vertices[t]).dot(lines.normal[v]);
  return offset;
}

}  // namespace satmesh
