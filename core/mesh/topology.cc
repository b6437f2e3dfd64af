#include "core/mesh/topology.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdint>
#include <utility>

namespace satmesh {
namespace {

uint64_t EdgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(uint32_t(a)) << 32) | uint32_t(b);
}

// Unnormalised face normal (twice the area vector), in double for accuracy.
Eigen::Vector3d AreaVector2(const TriangleMesh& mesh, const Eigen::Vector3i& f) {
  const Eigen::Vector3d a = mesh.vertices[f[0]].cast<double>();
  const Eigen::Vector3d b = mesh.vertices[f[1]].cast<double>();
  const Eigen::Vector3d c = mesh.vertices[f[2]].cast<double>();
  return (b - a).cross(c - a);
}

// Prefix sums of counts into offsets (size n+1).
std::vector<int> OffsetsFromCounts(const std::vector<int>& counts) {
  std::vector<int> offsets(counts.size() + 1, 0);
  for (size_t i = 0; i < counts.size(); ++i) offsets[i + 1] = offsets[i] + counts[i];
  return offsets;
}

}  // namespace

VertexAdjacency BuildVertexAdjacency(const TriangleMesh& mesh) {
  const size_t n = mesh.vertices.size();
  VertexAdjacency adj;
  std::vector<int> counts(n, 0);
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++counts[f[k]];
  adj.face_offsets = OffsetsFromCounts(counts);
  adj.faces.resize(adj.face_offsets.back());
  // Both other corners of each incident face, with repeats: an edge seen once is open.
  std::vector<int> ring(2 * adj.faces.size());
  std::vector<int> fill(adj.face_offsets.begin(), adj.face_offsets.end() - 1);
  for (size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    const auto& f = mesh.faces[fi];
    for (int k = 0; k < 3; ++k) {
      const int v = f[k], slot = fill[v]++;
      adj.faces[slot] = int(fi);
      ring[2 * slot] = f[(k + 1) % 3];
      ring[2 * slot + 1] = f[(k + 2) % 3];
    }
  }
  adj.is_boundary.assign(n, false);
  adj.neighbor_offsets.assign(n + 1, 0);
  adj.neighbors.reserve(adj.faces.size() + n);
  for (size_t v = 0; v < n; ++v) {
    const auto begin = ring.begin() + 2 * adj.face_offsets[v];
    const auto end = ring.begin() + 2 * adj.face_offsets[v + 1];
    std::sort(begin, end);
    for (auto it = begin; it != end;) {
      auto next = it;
      while (next != end && *next == *it) ++next;
      if (next - it == 1) adj.is_boundary[v] = true;
      adj.neighbors.push_back(*it);
      it = next;
    }
    adj.neighbor_offsets[v + 1] = int(adj.neighbors.size());
  }
  return adj;
}

std::vector<Eigen::Vector3f> FaceNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3f> normals(mesh.faces.size());
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(mesh.faces.size()); ++i) {
    const Eigen::Vector3d n = AreaVector2(mesh, mesh.faces[i]);
    const double len = n.norm();
    normals[i] = len > 0 ? Eigen::Vector3f((n / len).cast<float>()) : Eigen::Vector3f::Zero();
  }
  return normals;
}

std::vector<float> FaceAreas(const TriangleMesh& mesh) {
  std::vector<float> areas(mesh.faces.size());
  for (size_t i = 0; i < mesh.faces.size(); ++i)
    areas[i] = float(0.5 * AreaVector2(mesh, mesh.faces[i]).norm());
  return areas;
}

std::vector<Eigen::Vector3f> VertexNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> sums(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d n = AreaVector2(mesh, f);  // area-weighted
    for (int k = 0; k < 3; ++k) sums[f[k]] += n;
  }
  std::vector<Eigen::Vector3f> normals(sums.size());
  for (size_t i = 0; i < sums.size(); ++i) {
    const double len = sums[i].norm();
    normals[i] = len > 0 ? Eigen::Vector3f((sums[i] / len).cast<float>())
                         : Eigen::Vector3f::Zero();
  }
  return normals;
}

TriangleMesh SubdivideMarked(const TriangleMesh& mesh, const std::vector<char>& marked) {
  const size_t num_faces = mesh.faces.size();
  // Corner k of face f stands for its edge k -> k+1; edge_of[3f+k] numbers unique edges.
  std::vector<std::pair<uint64_t, uint32_t>> corner_edges(3 * num_faces);
  for (size_t f = 0; f < num_faces; ++f)
    for (int k = 0; k < 3; ++k)
      corner_edges[3 * f + k] = {EdgeKey(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3]),
                                 uint32_t(3 * f + k)};
  std::sort(corner_edges.begin(), corner_edges.end());
  std::vector<int> edge_of(3 * num_faces);
  std::vector<uint64_t> edge_key;
  for (size_t i = 0; i < corner_edges.size(); ++i) {
    if (i == 0 || corner_edges[i].first != corner_edges[i - 1].first)
      edge_key.push_back(corner_edges[i].first);
    edge_of[corner_edges[i].second] = int(edge_key.size()) - 1;
  }
  std::vector<char> split(edge_key.size(), 0);
  for (size_t f = 0; f < num_faces; ++f)
    if (marked[f])
      for (int k = 0; k < 3; ++k) split[edge_of[3 * f + k]] = 1;
  // Closure: two split edges make three. Each pass only adds splits, so it ends.
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t f = 0; f < num_faces; ++f) {
      const int* e = &edge_of[3 * f];
      if (split[e[0]] + split[e[1]] + split[e[2]] == 2) {
        split[e[0]] = split[e[1]] = split[e[2]] = 1;
        changed = true;
      }
    }
  }
  TriangleMesh out;
  out.origin = mesh.origin;
  out.crs = mesh.crs;
  out.vertices = mesh.vertices;
  std::vector<int> midpoint(edge_key.size(), -1);
  for (size_t e = 0; e < edge_key.size(); ++e) {
    if (!split[e]) continue;
    const int a = int(edge_key[e] >> 32), b = int(edge_key[e] & 0xffffffffu);
    midpoint[e] = int(out.vertices.size());
    out.vertices.push_back(0.5f * (mesh.vertices[a] + mesh.vertices[b]));
  }
  out.faces.reserve(num_faces * 2);
  for (size_t f = 0; f < num_faces; ++f) {
    const Eigen::Vector3i& v = mesh.faces[f];
    const int m[3] = {midpoint[edge_of[3 * f]], midpoint[edge_of[3 * f + 1]],
                      midpoint[edge_of[3 * f + 2]]};
    const int count = (m[0] >= 0) + (m[1] >= 0) + (m[2] >= 0);
    if (count == 0) {
      out.faces.push_back(v);
    } else if (count == 3) {
      out.faces.push_back({v[0], m[0], m[2]});
      out.faces.push_back({m[0], v[1], m[1]});
      out.faces.push_back({m[2], m[1], v[2]});
      out.faces.push_back({m[0], m[1], m[2]});
    } else {  // one split edge k (v[k] -> v[k+1]): bisect from the opposite corner
      const int k = m[0] >= 0 ? 0 : m[1] >= 0 ? 1 : 2;
      const int a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
      out.faces.push_back({a, m[k], c});
      out.faces.push_back({m[k], b, c});
    }
  }
  return out;
}

TriangleMesh Subdivide1To4(const TriangleMesh& mesh) {
  return SubdivideMarked(mesh, std::vector<char>(mesh.num_faces(), 1));
}

std::vector<Eigen::Vector2i> UniqueEdges(const TriangleMesh& mesh) {
  std::vector<uint64_t> keys;
  keys.reserve(3 * mesh.faces.size());
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) keys.push_back(EdgeKey(f[k], f[(k + 1) % 3]));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<Eigen::Vector2i> edges(keys.size());
  for (size_t i = 0; i < keys.size(); ++i)
    edges[i] = {int(keys[i] >> 32), int(keys[i] & 0xffffffffu)};
  return edges;
}

double MeanEdgeLength(const TriangleMesh& mesh) {
  const std::vector<Eigen::Vector2i> edges = UniqueEdges(mesh);
  if (edges.empty()) return 0.0;
  double sum = 0;
  for (const auto& e : edges)
    sum += (mesh.vertices[e[0]].cast<double>() - mesh.vertices[e[1]].cast<double>()).norm();
  return sum / double(edges.size());
}

namespace {

// Interleaves the low 21 bits of x, y, z (Morton / Z-order code).
uint64_t Morton3(uint32_t x, uint32_t y, uint32_t z) {
  auto spread = [](uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

}  // namespace

void SortSpatially(TriangleMesh* mesh) {
  const size_t nv = mesh->vertices.size();
  if (nv == 0) return;
  Eigen::Vector3f lo = mesh->vertices[0], hi = lo;
  for (const auto& p : mesh->vertices) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector3f scale = (hi - lo).cwiseMax(1e-6f).cwiseInverse() * float((1 << 21) - 1);
  std::vector<std::pair<uint64_t, int>> keys(nv);
  for (size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3f q = (mesh->vertices[i] - lo).cwiseProduct(scale);
    keys[i] = {Morton3(uint32_t(q.x()), uint32_t(q.y()), uint32_t(q.z())), int(i)};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> new_index(nv);
  std::vector<Eigen::Vector3f> vertices(nv);
  for (size_t k = 0; k < nv; ++k) {
    new_index[keys[k].second] = int(k);
    vertices[k] = mesh->vertices[keys[k].second];
  }
  mesh->vertices = std::move(vertices);
  for (auto& f : mesh->faces)
    for (int k = 0; k < 3; ++k) f[k] = new_index[f[k]];
  // Faces in the order of their smallest vertex (orientation kept).
  std::sort(mesh->faces.begin(), mesh->faces.end(),
            [](const Eigen::Vector3i& a, const Eigen::Vector3i& b) {
              return a.minCoeff() < b.minCoeff();
            });
}

}  // namespace satmesh
