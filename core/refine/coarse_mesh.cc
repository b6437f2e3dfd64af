#include "core/refine/coarse_mesh.h"

#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/detect_features.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <functional>
#include <cstdint>
#include <unordered_map>

#include "core/common/error.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/cgal_surface.h"

namespace satmesh {
namespace {
using cgal_surface::Kernel;
using cgal_surface::RelaxTangentially;
using cgal_surface::SurfaceMesh;
using cgal_surface::SurfaceProjector;
namespace PMP = CGAL::Polygon_mesh_processing;

// Removes the vertices no face uses and compacts the mesh (property maps are kept).
void DropIsolatedVertices(SurfaceMesh* sm) {
  for (auto v : sm->vertices())
    if (sm->is_isolated(v)) sm->remove_vertex(v);
  sm->collect_garbage();
}

// An edge property map with the mesh's border edges set, and with crease_angle_deg > 0 its
// creases (edges whose faces' normals differ by more: CGAL's detect_sharp_edges): what the
// remeshing keeps.
SurfaceMesh::Property_map<SurfaceMesh::Edge_index, bool> ConstrainedEdges(SurfaceMesh* sm,
                                                                         double crease_angle_deg) {
  auto is_constrained =
      sm->add_property_map<SurfaceMesh::Edge_index, bool>("e:is_constrained", false).first;
  std::vector<SurfaceMesh::Halfedge_index> border;
  PMP::border_halfedges(faces(*sm), *sm, std::back_inserter(border));
  for (auto h : border) is_constrained[edge(h, *sm)] = true;
  if (crease_angle_deg > 0) {
    auto sharp = sm->add_property_map<SurfaceMesh::Edge_index, bool>("e:sharp", false).first;
    PMP::detect_sharp_edges(*sm, crease_angle_deg, sharp);
    for (auto e : sm->edges())
      if (sharp[e]) is_constrained[e] = true;
    sm->remove_property_map(sharp);
  }
  return is_constrained;
}

SurfaceMesh ToSurfaceMesh(const TriangleMesh& mesh, size_t* dropped) {
  SurfaceMesh out;
  std::vector<SurfaceMesh::Vertex_index> index(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    index[i] = out.add_vertex(Kernel::Point_3(v.x(), v.y(), v.z()));
  }
  *dropped = 0;
  for (const auto& f : mesh.faces) {
    if (out.add_face(index[f[0]], index[f[1]], index[f[2]]) == SurfaceMesh::null_face()) {
      ++*dropped;
    }
  }
  DropIsolatedVertices(&out);
  return out;
}

TriangleMesh FromSurfaceMesh(const SurfaceMesh& sm, const TriangleMesh& like) {
  TriangleMesh out;
  out.origin = like.origin;
  out.crs = like.crs;
  std::vector<int> index(sm.num_vertices(), -1);  // by CGAL's index (removed ones too)
  out.vertices.reserve(sm.number_of_vertices());
  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    index[uint32_t(v)] = int(out.vertices.size());
    out.vertices.emplace_back(float(p.x()), float(p.y()), float(p.z()));
  }
  out.faces.reserve(sm.number_of_faces());
  for (auto f : sm.faces()) {
    Eigen::Vector3i tri;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) tri[k++] = index[uint32_t(v)];
    out.faces.push_back(tri);
  }
  return out;
}
}  // namespace

std::string CoarseMeshOptions::Check() const {
  if (!(target_edge_m > 0)) return "target_edge_m must be > 0, got " + std::to_string(target_edge_m);
  if (iterations < 1 || iterations > 20)
    return "iterations must be in [1, 20], got " + std::to_string(iterations);
  if (faces_per_block < 1000)
    return "faces_per_block must be >= 1000, got " + std::to_string(faces_per_block);
  if (!(crease_angle_deg >= 0 && crease_angle_deg < 180))
    return "crease_angle_deg must be in [0, 180), got " + std::to_string(crease_angle_deg);
  return "";
}

double GridKeepingTargetEdge(double edge_m, double cell_m) {
  const double keeps_diagonals = 1.005 * 0.75 * std::sqrt(2.0) * cell_m;
  return edge_m < keeps_diagonals && edge_m > 0.9 * cell_m ? keeps_diagonals : edge_m;
}

namespace {

uint64_t EdgeKey(int a, int b) {
  if (a > b) std::swap(a, b);
  return uint64_t(uint32_t(a)) << 32 | uint32_t(b);
}

// The blocks of a mesh: a bx x by grid over the faces' centroids (x, y), about
// faces_per_block faces each. Depends on the mesh and the option only, never on the
// number of threads, so that every machine remeshes a tile the same way.
struct BlockGrid {
  Eigen::Vector2f lo = Eigen::Vector2f::Zero(), size = Eigen::Vector2f::Ones();
  int bx = 1, by = 1;
  int num_blocks() const { return bx * by; }
  // Face f's block; shifted: its cell of the grid moved by half a block in x and y, whose
  // (bx + 1) x (by + 1) cells have the blocks' corners inside and cut their borders
  // half-way between corners.
  int Of(const TriangleMesh& mesh, size_t f, bool shifted = false) const {
    const auto& t = mesh.faces[f];
    const Eigen::Vector2f c =
        (mesh.vertices[t[0]].head<2>() + mesh.vertices[t[1]].head<2>() + mesh.vertices[t[2]].head<2>()) / 3.0f;
    const float half = shifted ? 0.5f : 0.f;
    const int nx = bx + (shifted ? 1 : 0), ny = by + (shifted ? 1 : 0);
    const int ix = std::clamp(int(std::floor((c.x() - lo.x()) / size.x() * bx + half)), 0, nx - 1);
    const int iy = std::clamp(int(std::floor((c.y() - lo.y()) / size.y() * by + half)), 0, ny - 1);
    return iy * nx + ix;
  }
};

BlockGrid MakeBlockGrid(const TriangleMesh& mesh, size_t faces_per_block) {
  BlockGrid grid;
  const int wanted = int((mesh.faces.size() + faces_per_block - 1) / faces_per_block);
  if (wanted <= 1) return grid;
  Eigen::Vector2f lo = mesh.vertices[0].head<2>(), hi = lo;
  for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v.head<2>()), hi = hi.cwiseMax(v.head<2>());
  grid.lo = lo;
  grid.size = (hi - lo).cwiseMax(1e-3f);
  // bx / by follows the extent's aspect.
  grid.bx = std::max(1, int(std::lround(std::sqrt(wanted * grid.size.x() / grid.size.y()))));
  grid.by = std::max(1, int(std::lround(double(wanted) / grid.bx)));
  return grid;
}

// Splits, at their midpoints, every edge longer than max_len that lies on the mesh's
// border or between two blocks, until none is: the blocks' borders are then short enough
// to be kept as they are (protected) while each block is remeshed on its own. A split
// face's two halves stay in its block. Edges of more than two faces are left alone.
void SplitLongBlockBorders(double max_len, TriangleMesh* mesh, std::vector<int>* block) {
  // The edges on a border (one face, or two of different blocks), with their faces: from
  // the faces' edges sorted, not a hash map of every edge (0.47 s for 580k faces).
  std::vector<std::pair<uint64_t, int>> sides(mesh->faces.size() * 3);
  for (size_t f = 0; f < mesh->faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      sides[3 * f + k] = {EdgeKey(mesh->faces[f][k], mesh->faces[f][(k + 1) % 3]), int(f)};
  std::sort(sides.begin(), sides.end());
  std::unordered_map<uint64_t, std::vector<int>> edge_faces;  // the border edges only
  for (size_t i = 0; i < sides.size();) {
    size_t j = i + 1;
    while (j < sides.size() && sides[j].first == sides[i].first) ++j;
    if (j - i == 1 || (j - i == 2 && (*block)[sides[i].second] != (*block)[sides[i + 1].second])) {
      auto& fs = edge_faces[sides[i].first];
      for (size_t k = i; k < j; ++k) fs.push_back(sides[k].second);
    }
    i = j;
  }
  sides = {};
  const float max_sq = float(max_len * max_len);
  auto is_long_border = [&](uint64_t key, const std::vector<int>& fs) {
    if (fs.empty() || fs.size() > 2) return false;
    if (fs.size() == 2 && (*block)[fs[0]] == (*block)[fs[1]]) return false;
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    return (mesh->vertices[a] - mesh->vertices[b]).squaredNorm() > max_sq;
  };
  std::vector<uint64_t> queue;
  for (const auto& [key, fs] : edge_faces)
    if (is_long_border(key, fs)) queue.push_back(key);
  std::sort(queue.begin(), queue.end());  // a deterministic order
  while (!queue.empty()) {
    const uint64_t key = queue.back();
    queue.pop_back();
    auto it = edge_faces.find(key);
    if (it == edge_faces.end() || !is_long_border(key, it->second)) continue;
    const std::vector<int> fs = std::move(it->second);
    edge_faces.erase(it);
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    const int m = int(mesh->vertices.size());
    mesh->vertices.push_back(0.5f * (mesh->vertices[a] + mesh->vertices[b]));
    for (int f : fs) {
      // Rotate so that the split edge is (p0, p1) in the face's orientation.
      Eigen::Vector3i t = mesh->faces[f];
      while (!((t[0] == a && t[1] == b) || (t[0] == b && t[1] == a))) t = Eigen::Vector3i(t[1], t[2], t[0]);
      const int p0 = t[0], p1 = t[1], p2 = t[2];
      const int g = int(mesh->faces.size());
      mesh->faces[f] = Eigen::Vector3i(p0, m, p2);
      mesh->faces.emplace_back(m, p1, p2);
      block->push_back((*block)[f]);
      // (p1, p2) is g's now; (m, p2) lies inside the block (f and g).
      if (auto e12 = edge_faces.find(EdgeKey(p1, p2)); e12 != edge_faces.end())
        std::replace(e12->second.begin(), e12->second.end(), f, g);
      edge_faces[EdgeKey(p0, m)].push_back(f);
      edge_faces[EdgeKey(m, p1)].push_back(g);
    }
    for (uint64_t k : {EdgeKey(a, m), EdgeKey(m, b)})
      if (is_long_border(k, edge_faces[k])) queue.push_back(k);
  }
}

// CGAL's remesher, given no projection of its own, builds no AABB tree of the mesh it
// starts from and does not project every vertex onto it after each iteration: with no
// relaxation of its own it moves no vertex off that surface (splits put new vertices at
// edge midpoints, collapses and flips keep positions), so the projection only cost time
// (a tree and every vertex's closest point per block and iteration; stereo 0.5 m, 300 m
// DSM tile: remeshing and the sigma pass 8.1 -> 5.5 s, the whole job 13.8 -> 11.4 s, 4 of
// 291k vertices differ; docs/benchmarks-history.md, session 22). RelaxTangentially
// projects what it moves onto the input.
struct KeepPosition {
  const SurfaceMesh* sm;
  Kernel::Point_3 operator()(SurfaceMesh::Vertex_index v) const { return sm->point(v); }
};

// CGAL's isotropic remeshing of all of `sm`, iterations one at a time (cancellation
// reaches it within one), each with its tangential relaxation (RelaxTangentially). The
// constrained edges (the border, the creases) are kept where they are: split and
// collapsed (protect = false) or kept as they are (protect = true). The vertices marked in
// "v:kept" (if sm has the property) are kept as they are.
template <typename ConstraintMap>
void RemeshInPlace(const CoarseMeshOptions& options, ConstraintMap is_constrained, bool protect,
                   const std::function<bool()>& cancelled, SurfaceMesh* sm) {
  const SurfaceProjector input(*sm);
  auto hints = sm->add_property_map<SurfaceMesh::Vertex_index, uint32_t>(
                     "v:projected", SurfaceProjector::kNoHint).first;
  auto kept = sm->add_property_map<SurfaceMesh::Vertex_index, bool>("v:kept", false).first;
  for (int it = 0; it < options.iterations && !cancelled(); ++it) {
    PMP::isotropic_remeshing(faces(*sm), options.target_edge_m, *sm,
                             PMP::parameters::number_of_iterations(1)
                                 .number_of_relaxation_steps(0)
                                 .do_project(false)
                                 .projection_functor(KeepPosition{sm})
                                 .edge_is_constrained_map(is_constrained)
                                 .vertex_is_constrained_map(kept)
                                 .protect_constraints(protect)
                                 .relax_constraints(false));
    RelaxTangentially(is_constrained, input, hints, sm);
  }
  sm->remove_property_map(hints);
}

// One block: its faces remeshed with the block's border kept. Without `shared` the border
// and the creases are kept as they are (protected); with it (per input vertex: a face
// outside the block uses it) only the shared vertices are, and the rest of the border
// (the mesh's own) and the creases are split and collapsed, as RemeshWhole does. Returns
// the result; `global` holds, per result vertex, the input vertex it is (on the border,
// never moved) or -1 for a new one. Faces CGAL cannot take (non-manifold within the block)
// come back unchanged in `kept`.
struct BlockResult {
  SurfaceMesh sm;
  std::vector<int> global;
  std::vector<Eigen::Vector3i> kept;  // input vertex indices
};

BlockResult RemeshBlock(const TriangleMesh& mesh, const std::vector<int>& face_ids,
                        const CoarseMeshOptions& options, const std::function<bool()>& cancelled,
                        const std::vector<char>* shared = nullptr) {
  BlockResult out;
  std::unordered_map<int, SurfaceMesh::Vertex_index> local;
  auto g = out.sm.add_property_map<SurfaceMesh::Vertex_index, int>("v:global", -1).first;
  auto kept = out.sm.add_property_map<SurfaceMesh::Vertex_index, bool>("v:kept", false).first;
  auto vertex = [&](int i) {
    auto [it, added] = local.try_emplace(i);
    if (added) {
      const auto& p = mesh.vertices[i];
      it->second = out.sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
      g[it->second] = i;
      kept[it->second] = shared && (*shared)[size_t(i)];
    }
    return it->second;
  };
  for (int f : face_ids) {
    const auto& t = mesh.faces[f];
    const auto a = vertex(t[0]), b = vertex(t[1]), c = vertex(t[2]);
    if (out.sm.add_face(a, b, c) == SurfaceMesh::null_face()) out.kept.push_back(t);
  }
  DropIsolatedVertices(&out.sm);
  if (out.sm.number_of_faces() > 0)
    RemeshInPlace(options, ConstrainedEdges(&out.sm, options.crease_angle_deg),
                  /*protect=*/shared == nullptr, cancelled, &out.sm);
  out.sm.remove_property_map(kept);
  out.sm.collect_garbage();
  out.global.assign(out.sm.number_of_vertices(), -1);
  // Interior input vertices were moved: only the border's are shared.
  for (auto v : out.sm.vertices())
    if (out.sm.is_border(v)) out.global[uint32_t(v)] = g[v];
  return out;
}

// The whole mesh as one CGAL patch, its border split and collapsed but never moved.
SurfaceMesh RemeshWhole(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                        const Progress& progress) {
  size_t dropped = 0;
  SurfaceMesh sm = ToSurfaceMesh(mesh, &dropped);
  if (dropped > 0) spdlog::debug("remesh: dropped {} non-manifold faces", dropped);
  SATMESH_CHECK(sm.number_of_faces() > 0, ErrorCode::kInvalidInput,
                "remesh: the initial mesh has no usable (manifold) face");
  RemeshInPlace(options, ConstrainedEdges(&sm, options.crease_angle_deg), /*protect=*/false,
                [&] { return progress.Cancelled(); }, &sm);
  progress.ThrowIfCancelled();
  return sm;
}

// `mesh` with the faces of the blocks (in_block) replaced by the blocks' results and the
// others kept: a block's border vertex is the input vertex it was, a new vertex its
// block's own; vertices no face uses are left out. Consumes the results. border: per
// output vertex, 1 for a block's border vertex.
TriangleMesh JoinBlocks(const TriangleMesh& mesh, const std::vector<char>& in_block,
                        std::vector<BlockResult>* results, std::vector<char>* border) {
  TriangleMesh out;
  out.origin = mesh.origin;
  out.crs = mesh.crs;
  border->clear();
  std::vector<int> index(mesh.vertices.size(), -1);
  auto shared = [&](int i) {
    int& k = index[size_t(i)];
    if (k < 0) {
      k = int(out.vertices.size());
      out.vertices.push_back(mesh.vertices[i]);
      border->push_back(0);
    }
    return k;
  };
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (in_block[f]) continue;
    const auto& t = mesh.faces[f];
    out.faces.emplace_back(shared(t[0]), shared(t[1]), shared(t[2]));
  }
  for (BlockResult& r : *results) {
    std::vector<int> local(r.sm.num_vertices(), -1);  // by CGAL's index
    auto vertex = [&](SurfaceMesh::Vertex_index v) {
      int& k = local[uint32_t(v)];
      if (k >= 0) return k;
      const int gi = r.global[uint32_t(v)];
      if (gi >= 0) {
        k = shared(gi);
        (*border)[size_t(k)] = 1;
      } else {
        const auto& p = r.sm.point(v);
        k = int(out.vertices.size());
        out.vertices.emplace_back(float(p.x()), float(p.y()), float(p.z()));
        border->push_back(0);
      }
      return k;
    };
    for (auto f : r.sm.faces()) {
      Eigen::Vector3i tri;
      int k = 0;
      for (auto v : CGAL::vertices_around_face(r.sm.halfedge(f), r.sm)) tri[k++] = vertex(v);
      out.faces.push_back(tri);
    }
    for (const auto& t : r.kept) out.faces.emplace_back(shared(t[0]), shared(t[1]), shared(t[2]));
    r = BlockResult{};
  }
  return out;
}

// The faces of each list remeshed on their own (RemeshBlock: keep_shared_only, only the
// vertices a list shares with the rest of the mesh kept, else its whole border and its
// creases), the lists in parallel; then `mesh` with them replaced (JoinBlocks).
TriangleMesh RemeshFaceLists(const TriangleMesh& mesh, const std::vector<std::vector<int>>& lists,
                             const CoarseMeshOptions& options, const Progress& progress,
                             bool keep_shared_only, std::vector<char>* border) {
  std::vector<char> in_block(mesh.faces.size(), 0);
  for (const auto& list : lists)
    for (int f : list) in_block[size_t(f)] = 1;
  // keep_shared_only: the vertices that faces of two lists, or of a list and the rest, use.
  std::vector<char> shared;
  if (keep_shared_only) {
    std::vector<int> owner(mesh.vertices.size(), -2);  // -2 unused, else its faces' list
    shared.assign(mesh.vertices.size(), 0);
    std::vector<int> list_of(mesh.faces.size(), -1);  // -1: no list
    for (size_t l = 0; l < lists.size(); ++l)
      for (int f : lists[l]) list_of[size_t(f)] = int(l);
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int c = 0; c < 3; ++c) {
        int& o = owner[size_t(mesh.faces[f][c])];
        if (o == -2) o = list_of[f];
        else if (o != list_of[f]) shared[size_t(mesh.faces[f][c])] = 1;
      }
  }
  std::vector<BlockResult> results(lists.size());
  const std::function<bool()> cancelled = [&] { return progress.Cancelled(); };
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t b = 0; b < lists.size(); ++b) {
    try {
      results[b] = RemeshBlock(mesh, lists[b], options, cancelled,
                               keep_shared_only ? &shared : nullptr);
    } catch (...) {
#pragma omp critical(satmesh_remesh_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  progress.ThrowIfCancelled();
  return JoinBlocks(mesh, in_block, &results, border);
}

// Large meshes: the blocks remeshed in parallel with their borders kept; then the band
// around those borders (the faces within two rings of a kept vertex) remeshed so that no
// trace of the blocks is left, in pieces cut by the blocks' grid moved by half a block
// (one piece around each corner of the blocks, cut half-way along their borders), also in
// parallel, each keeping only the vertices it shares with the rest (its creases and the
// mesh's own border split and collapsed, as in one piece). Only the short cuts across the
// band, where a piece's border crosses it, keep the blocks' edges. (Before, the band was
// remeshed as one patch by one thread: stereo 0.5 m s1, 42 blocks, a band of 67k faces,
// 0.7 s of a 6.7 s job, and its stitching into one CGAL mesh 0.2 s more.)
TriangleMesh RemeshInBlocks(TriangleMesh mesh, const BlockGrid& grid,
                            const CoarseMeshOptions& options, const Progress& progress) {
  std::vector<int> block(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) block[f] = grid.Of(mesh, f);
  SplitLongBlockBorders(4.0 / 3.0 * options.target_edge_m, &mesh, &block);
  std::vector<std::vector<int>> lists(grid.num_blocks());
  for (size_t f = 0; f < mesh.faces.size(); ++f) lists[block[f]].push_back(int(f));
  std::vector<char> kept;  // the blocks' border vertices
  TriangleMesh joined =
      RemeshFaceLists(mesh, lists, options, progress, /*keep_shared_only=*/false, &kept);

  // The band: faces within two rings of a kept vertex.
  const VertexAdjacency adjacency = BuildVertexAdjacency(joined);
  std::vector<char> in_band(joined.faces.size(), 0), ring(kept);
  for (int r = 0; r < 2; ++r) {
    std::vector<char> next(ring.size(), 0);
    for (size_t v = 0; v < ring.size(); ++v) {
      if (!ring[v]) continue;
      for (int k = adjacency.face_offsets[v]; k < adjacency.face_offsets[v + 1]; ++k) {
        const int f = adjacency.faces[k];
        if (in_band[size_t(f)]) continue;
        in_band[size_t(f)] = 1;
        for (int c = 0; c < 3; ++c) next[size_t(joined.faces[f][c])] = 1;
      }
    }
    ring = std::move(next);
  }
  // The pieces' borders split as the blocks' were: no edge there is left for the remesh to
  // split on one side only.
  const int num_pieces = (grid.bx + 1) * (grid.by + 1);
  std::vector<int> piece(joined.faces.size(), num_pieces);  // num_pieces: not in the band
  size_t band_faces = 0;
  for (size_t f = 0; f < joined.faces.size(); ++f)
    if (in_band[f]) piece[f] = grid.Of(joined, f, /*shifted=*/true), ++band_faces;
  SplitLongBlockBorders(4.0 / 3.0 * options.target_edge_m, &joined, &piece);
  std::vector<std::vector<int>> pieces(num_pieces);
  for (size_t f = 0; f < joined.faces.size(); ++f)
    if (piece[f] < num_pieces) pieces[piece[f]].push_back(int(f));
  std::erase_if(pieces, [](const std::vector<int>& p) { return p.empty(); });
  spdlog::debug("remesh: {} blocks, band of {} faces in {} pieces", grid.num_blocks(), band_faces,
                pieces.size());
  return RemeshFaceLists(joined, pieces, options, progress, /*keep_shared_only=*/true, &kept);
}

}  // namespace

TriangleMesh RemeshIsotropic(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                             const Progress& progress) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "CoarseMeshOptions: " + problem);
  SATMESH_CHECK(!mesh.faces.empty(), ErrorCode::kInvalidInput, "remesh: the initial mesh has no face");
  const BlockGrid grid = MakeBlockGrid(mesh, options.faces_per_block);
  TriangleMesh out;
  if (grid.num_blocks() > 1) {
    out = RemeshInBlocks(mesh, grid, options, progress);
  } else {
    SurfaceMesh sm = RemeshWhole(mesh, options, progress);
    sm.collect_garbage();
    out = FromSurfaceMesh(sm, mesh);
  }
  SortSpatially(&out);
  return out;
}

}  // namespace satmesh
