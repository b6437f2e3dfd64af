#include "core/mesh/mesh_clean.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/common/error.h"

namespace satmesh {
namespace {

// Each vertex -> the lowest-indexed earlier kept vertex within `distance` of it (itself if
// none; a vertex mapped to another is not kept), through a hash of cells of edge
// kCellsPerDistance x `distance`: a vertex probes only the cells its ball of radius
// `distance` reaches, about 2 instead of the 27 around cells of edge `distance`. The
// probes are cache misses into a table of about one cell per vertex, and they were most
// of a tile's clipping and a job's assembly (stereo 0.5 m, 336k vertices: 1.3 s of 21 s,
// docs/benchmarks-history.md, session 28). The cells' vertices are chained in insertion
// order (head, tail, next: no allocation per cell).
std::vector<int> MergeMap(const TriangleMesh& mesh, double distance, size_t* merged) {
  constexpr double kCellsPerDistance = 8;
  const double cell = kCellsPerDistance * distance;
  const size_t nv = mesh.vertices.size();
  // Open addressing (linear probing) over a power-of-two table of at least twice as many
  // slots as vertices: a probe is one cache miss, where a node-based map took two or more.
  size_t capacity = 16;
  while (capacity < 2 * nv) capacity *= 2;
  const size_t mask = capacity - 1;
  std::vector<std::array<int64_t, 3>> slot_cell(capacity);
  std::vector<int> head(capacity, -1), tail(capacity, -1);
  const auto slot_of = [&](const std::array<int64_t, 3>& c) {
    uint64_t h = uint64_t(c[0]) * 0x9E3779B97F4A7C15ULL ^ uint64_t(c[1]) * 0xC2B2AE3D27D4EB4FULL ^
                 uint64_t(c[2]) * 0x165667B19E3779F9ULL;
    h ^= h >> 29;
    size_t s = size_t(h) & mask;
    while (head[s] >= 0 && slot_cell[s] != c) s = (s + 1) & mask;
    return s;  // the cell's slot, or the empty one where it would go
  };
  std::vector<int> next(nv, -1);
  std::vector<int> map(nv);
  const double d2 = distance * distance;
  *merged = 0;
  for (size_t i = 0; i < nv; ++i) {
    const Eigen::Vector3d v = mesh.vertices[i].cast<double>();
    int64_t lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = int64_t(std::floor((v[a] - distance) / cell));
      hi[a] = int64_t(std::floor((v[a] + distance) / cell));
    }
    int found = -1;
    for (int64_t x = lo[0]; x <= hi[0]; ++x)
      for (int64_t y = lo[1]; y <= hi[1]; ++y)
        for (int64_t z = lo[2]; z <= hi[2]; ++z)
          for (int j = head[slot_of({x, y, z})]; j >= 0 && (found < 0 || j < found); j = next[j])
            if ((mesh.vertices[j].cast<double>() - v).squaredNorm() < d2) {
              found = j;
              break;
            }
    if (found >= 0) {
      map[i] = found;
      ++*merged;
      continue;
    }
    map[i] = int(i);
    const std::array<int64_t, 3> c{int64_t(std::floor(v.x() / cell)), int64_t(std::floor(v.y() / cell)),
                                   int64_t(std::floor(v.z() / cell))};
    const size_t s = slot_of(c);
    if (head[s] < 0) {
      slot_cell[s] = c;
      head[s] = int(i);
    } else {
      next[tail[s]] = int(i);
    }
    tail[s] = int(i);
  }
  return map;
}

bool Degenerate(const TriangleMesh& mesh, const Eigen::Vector3i& f, double min_height) {
  if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return true;
  const Eigen::Vector3d a = mesh.vertices[f[0]].cast<double>(), b = mesh.vertices[f[1]].cast<double>(),
                        c = mesh.vertices[f[2]].cast<double>();
  const double twice_area = (b - a).cross(c - a).norm();
  const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  return !(twice_area >= min_height * longest);  // NaN counts as degenerate
}

// Faces kept (indices into mesh.faces, after the vertex map), counting what is dropped: a
// degenerate face, or one whose vertex set an earlier face has (found by sorting the faces'
// sorted vertex triples, ties by index, so the first of duplicates stays).
std::vector<int> KeptFaces(const TriangleMesh& mesh, const std::vector<int>& map,
                           const MeshCleanOptions& options, MeshDebris* debris) {
  const size_t nf = mesh.faces.size();
  std::vector<std::pair<std::array<int, 3>, int>> keys;
  keys.reserve(nf);
  for (size_t i = 0; i < nf; ++i) {
    const Eigen::Vector3i f(map[mesh.faces[i][0]], map[mesh.faces[i][1]], map[mesh.faces[i][2]]);
    if (Degenerate(mesh, f, options.min_face_height_m)) {
      ++debris->degenerate_faces;
      continue;
    }
    std::array<int, 3> key{f[0], f[1], f[2]};
    std::sort(key.begin(), key.end());
    keys.emplace_back(key, int(i));
  }
  std::sort(keys.begin(), keys.end());
  std::vector<int> kept;
  kept.reserve(keys.size());
  for (size_t k = 0; k < keys.size(); ++k) {
    if (k > 0 && keys[k].first == keys[k - 1].first) {
      ++debris->duplicate_faces;
      continue;
    }
    kept.push_back(keys[k].second);
  }
  std::sort(kept.begin(), kept.end());  // the faces' order as given
  return kept;
}

MeshDebris Analyse(const TriangleMesh& mesh, const MeshCleanOptions& options,
                   std::vector<int>* map, std::vector<int>* kept, std::vector<bool>* used) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "MeshCleanOptions: " + problem);
  ValidateMesh(mesh, "clean");
  MeshDebris debris;
  *map = MergeMap(mesh, options.merge_distance_m, &debris.close_vertices);
  *kept = KeptFaces(mesh, *map, options, &debris);
  used->assign(mesh.vertices.size(), false);
  for (int i : *kept)
    for (int k = 0; k < 3; ++k) (*used)[(*map)[mesh.faces[i][k]]] = true;
  for (size_t v = 0; v < mesh.vertices.size(); ++v)
    if ((*map)[v] == int(v) && !(*used)[v]) ++debris.unreferenced_vertices;
  return debris;
}

}  // namespace

std::string MeshCleanOptions::Check() const {
  if (!(merge_distance_m > 0)) return "merge_distance_m must be > 0, got " + std::to_string(merge_distance_m);
  if (!(min_face_height_m > 0)) return "min_face_height_m must be > 0, got " + std::to_string(min_face_height_m);
  return "";
}

std::string MeshDebris::ToString() const {
  return std::to_string(close_vertices) + " close vertices, " + std::to_string(degenerate_faces) +
         " degenerate faces, " + std::to_string(duplicate_faces) + " duplicate faces, " +
         std::to_string(unreferenced_vertices) + " unreferenced vertices";
}

MeshDebris FindDebris(const TriangleMesh& mesh, const MeshCleanOptions& options) {
  std::vector<int> map, kept;
  std::vector<bool> used;
  return Analyse(mesh, options, &map, &kept, &used);
}

MeshDebris CleanMesh(TriangleMesh* mesh, const MeshCleanOptions& options) {
  std::vector<int> map, kept;
  std::vector<bool> used;
  const MeshDebris debris = Analyse(*mesh, options, &map, &kept, &used);
  if (debris.Total() == 0) return debris;
  const bool sigma = mesh->height_sigma.size() == mesh->vertices.size();
  std::vector<int> index(mesh->vertices.size(), -1);
  std::vector<Eigen::Vector3f> vertices;
  std::vector<float> height_sigma;
  for (size_t v = 0; v < mesh->vertices.size(); ++v) {
    if (map[v] != int(v) || !used[v]) continue;
    index[v] = int(vertices.size());
    vertices.push_back(mesh->vertices[v]);
    if (sigma) height_sigma.push_back(mesh->height_sigma[v]);
  }
  std::vector<Eigen::Vector3i> faces;
  faces.reserve(kept.size());
  for (int i : kept) {
    const Eigen::Vector3i& f = mesh->faces[i];
    faces.emplace_back(index[map[f[0]]], index[map[f[1]]], index[map[f[2]]]);
  }
  mesh->vertices = std::move(vertices);
  mesh->faces = std::move(faces);
  if (sigma) mesh->height_sigma = std::move(height_sigma);
  return debris;
}

}  // namespace satmesh
