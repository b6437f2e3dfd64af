// MeshBoxes: exact boundary of a CSG of axis-aligned boxes on their breakpoint grid.
#include <algorithm>
#include <array>
#include <unordered_map>

#include "core/synth/city.h"

namespace satmesh::synth {
namespace {

std::vector<float> Breakpoints(const std::vector<CityBox>& boxes, int axis) {
  std::vector<float> v;
  for (const auto& b : boxes) {
    v.push_back(b.lo[axis]);
    v.push_back(b.hi[axis]);
  }
  std::sort(v.begin(), v.end());
  std::vector<float> out;
  for (float x : v)
    if (out.empty() || x - out.back() > 1e-4f) out.push_back(x);
  return out;
}

int IndexOf(const std::vector<float>& xs, float x) {
  return int(std::lower_bound(xs.begin(), xs.end(), x - 1e-4f) - xs.begin());
}

}  // namespace

BoxMeshPart MeshBoxes(const std::vector<CityBox>& boxes) {
  BoxMeshPart part;
  if (boxes.empty()) return part;
  const std::array<std::vector<float>, 3> g = {Breakpoints(boxes, 0), Breakpoints(boxes, 1),
                                               Breakpoints(boxes, 2)};
  const int n[3] = {int(g[0].size()) - 1, int(g[1].size()) - 1, int(g[2].size()) - 1};
  if (n[0] < 1 || n[1] < 1 || n[2] < 1) return part;
  std::vector<int> occ(size_t(n[0]) * n[1] * n[2], -1);
  auto cell = [&](int i, int j, int k) -> int& { return occ[(size_t(k) * n[1] + j) * n[0] + i]; };
  for (int b = 0; b < int(boxes.size()); ++b) {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = IndexOf(g[a], boxes[b].lo[a]);
      hi[a] = IndexOf(g[a], boxes[b].hi[a]);
    }
    for (int k = lo[2]; k < hi[2]; ++k)
      for (int j = lo[1]; j < hi[1]; ++j)
        for (int i = lo[0]; i < hi[0]; ++i) cell(i, j, k) = boxes[b].subtract ? -1 : b;
  }
  std::unordered_map<int64_t, int> vid;
  auto vertex = [&](int i, int j, int k) {
    const int64_t key = (int64_t(k) * (n[1] + 1) + j) * (n[0] + 1) + i;
    auto [it, inserted] = vid.emplace(key, int(part.vertices.size()));
    if (inserted) part.vertices.emplace_back(g[0][i], g[1][j], g[2][k]);
    return it->second;
  };
  // Per face direction: axis, side, and the two in-plane axes with e1 x e2 outward.
  struct Dir { int axis, side, e1, e2; };
  const Dir dirs[6] = {{0, 1, 1, 2}, {0, 0, 2, 1}, {1, 1, 2, 0},
                       {1, 0, 0, 2}, {2, 1, 0, 1}, {2, 0, 1, 0}};
  for (int k = 0; k < n[2]; ++k)
    for (int j = 0; j < n[1]; ++j)
      for (int i = 0; i < n[0]; ++i) {
        const int b = cell(i, j, k);
        if (b < 0) continue;
        const int c[3] = {i, j, k};
        for (const Dir& d : dirs) {
          int nb[3] = {i, j, k};
          nb[d.axis] += d.side ? 1 : -1;
          const bool outside = nb[d.axis] < 0 || nb[d.axis] >= n[d.axis];
          if (!outside && cell(nb[0], nb[1], nb[2]) >= 0) continue;
          Material m = boxes[b].wall;
          if (d.axis == 2) {
            if (!d.side && k == 0) continue;  // underground base
            m = d.side ? boxes[b].top : boxes[b].bottom;
            if (m == Material::kCount) continue;
          }
          int corner[4][3];
          for (int q = 0; q < 4; ++q) {
            for (int a = 0; a < 3; ++a) corner[q][a] = c[a];
            corner[q][d.axis] += d.side;
          }
          corner[1][d.e1] += 1;
          corner[2][d.e1] += 1;
          corner[2][d.e2] += 1;
          corner[3][d.e2] += 1;
          int v[4];
          for (int q = 0; q < 4; ++q) v[q] = vertex(corner[q][0], corner[q][1], corner[q][2]);
          part.faces.emplace_back(v[0], v[1], v[2]);
          part.faces.emplace_back(v[0], v[2], v[3]);
          part.face_material.push_back(m);
          part.face_material.push_back(m);
        }
      }
  return part;
}

}  // namespace satmesh::synth
