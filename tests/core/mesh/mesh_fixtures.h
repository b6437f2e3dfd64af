#pragma once
// Tiny meshes for the mesh tests.
#include <cmath>

#include "core/mesh/mesh.h"

namespace satmesh::testing {

// (n+1) x (n+1) vertices on a wavy grid of `spacing` metres, 2*n*n faces (CCW from +z).
inline TriangleMesh CreateGridMesh(int n, float spacing = 1.f, bool wavy = false) {
  TriangleMesh mesh;
  for (int r = 0; r <= n; ++r)
    for (int c = 0; c <= n; ++c) {
      const float z = wavy ? 2.f * std::sin(0.7f * c) * std::cos(0.4f * r) : 0.f;
      mesh.vertices.emplace_back(c * spacing, r * spacing, z);
    }
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const int v = r * (n + 1) + c;
      mesh.faces.emplace_back(v, v + 1, v + n + 2);
      mesh.faces.emplace_back(v, v + n + 2, v + n + 1);
    }
  return mesh;
}

// Closed unit cube (8 vertices, 12 faces, outward normals).
inline TriangleMesh CreateCube() {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) mesh.vertices.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    mesh.faces.emplace_back(q[0], q[1], q[2]);
    mesh.faces.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

}  // namespace satmesh::testing
