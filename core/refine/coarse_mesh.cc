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
std::vector<int> AssignBlocks(const TriangleMesh& mesh, size_t faces_per_block, int* num_blocks) {
  const size_t nf = mesh.faces.size();
  std::vector<int> block(nf, 0);
  const int wanted = int((nf + faces_per_block - 1) / faces_per_block);
  *num_blocks = 1;
  if (wanted <= 1) return block;
  Eigen::Vector2f lo = mesh.vertices[0].head<2>(), hi = lo;
  for (const auto& v : mesh.vertices) lo = lo.cwiseMin(v.head<2>()), hi = hi.cwiseMax(v.head<2>());
  const Eigen::Vector2f size = (hi - lo).cwiseMax(1e-3f);
  // bx / by follows the extent's aspect.
  int bx = std::max(1, int(std::lround(std::sqrt(wanted * size.x() / size.y()))));
  int by = std::max(1, int(std::lround(double(wanted) / bx)));
  *num_blocks = bx * by;
  for (size_t f = 0; f < nf; ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector2f c =
        (mesh.vertices[t[0]].head<2>() + mesh.vertices[t[1]].head<2>() + mesh.vertices[t[2]].head<2>()) / 3.0f;
    const int ix = std::clamp(int((c.x() - lo.x()) / size.x() * bx), 0, bx - 1);
    const int iy = std::clamp(int((c.y() - lo.y()) / size.y() * by), 0, by - 1);
    block[f] = iy * bx + ix;
  }
  return block;
}

// Splits, at their midpoints, every edge longer than max_len that lies on the mesh's
// border or between two blocks, until none is: the blocks' borders are then short enough
// to be kept as they are (protected) while each block is remeshed on its own. A split
// face's two halves stay in its block. Edges of more than two faces are left alone.
void SplitLongBlockBorders(double max_len, TriangleMesh* mesh, std::vector<int>* block) {
  std::unordered_map<uint64_t, std::vector<int>> edge_faces;
  edge_faces.reserve(mesh->faces.size() * 2);
  for (size_t f = 0; f < mesh->faces.size(); ++f)
    for (int k = 0; k < 3; ++k)
      edge_faces[EdgeKey(mesh->faces[f][k], mesh->faces[f][(k + 1) % 3])].push_back(int(f));
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
      auto& e12 = edge_faces[EdgeKey(p1, p2)];
      std::replace(e12.begin(), e12.end(), f, g);
      edge_faces[EdgeKey(p0, m)].push_back(f);
      edge_faces[EdgeKey(m, p1)].push_back(g);
      auto& em2 = edge_faces[EdgeKey(m, p2)];
      em2.push_back(f);
      em2.push_back(g);
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
// constrained edges are kept where they are: split and collapsed (protect = false) or kept
// as they are (protect = true).
template <typename ConstraintMap>
void RemeshInPlace(const CoarseMeshOptions& options, ConstraintMap is_constrained, bool protect,
                   const std::function<bool()>& cancelled, SurfaceMesh* sm) {
  const SurfaceProjector input(*sm);
  auto hints = sm->add_property_map<SurfaceMesh::Vertex_index, uint32_t>(
                     "v:projected", SurfaceProjector::kNoHint).first;
  for (int it = 0; it < options.iterations && !cancelled(); ++it) {
    PMP::isotropic_remeshing(faces(*sm), options.target_edge_m, *sm,
                             PMP::parameters::number_of_iterations(1)
                                 .number_of_relaxation_steps(0)
                                 .do_project(false)
                                 .projection_functor(KeepPosition{sm})
                                 .edge_is_constrained_map(is_constrained)
                                 .protect_constraints(protect)
                                 .relax_constraints(false));
    RelaxTangentially(is_constrained, input, hints, sm);
  }
  sm->remove_property_map(hints);
}

// One block: its faces remeshed with the block's border protected. Returns the result;
// `global` holds, per result vertex, the input vertex it is (border vertices are never
// moved or removed) or -1 for a new one. Faces CGAL cannot take (non-manifold within the
// block) come back unchanged in `kept`.
struct BlockResult {
  SurfaceMesh sm;
  std::vector<int> global;
  std::vector<Eigen::Vector3i> kept;  // input vertex indices
};

BlockResult RemeshBlock(const TriangleMesh& mesh, const std::vector<int>& face_ids,
                        const CoarseMeshOptions& options, const std::function<bool()>& cancelled) {
  BlockResult out;
  std::unordered_map<int, SurfaceMesh::Vertex_index> local;
  auto g = out.sm.add_property_map<SurfaceMesh::Vertex_index, int>("v:global", -1).first;
  auto vertex = [&](int i) {
    auto [it, added] = local.try_emplace(i);
    if (added) {
      const auto& p = mesh.vertices[i];
      it->second = out.sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
      g[it->second] = i;
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
    RemeshInPlace(options, ConstrainedEdges(&out.sm, options.crease_angle_deg), /*protect=*/true,
                  cancelled, &out.sm);
  out.sm.collect_garbage();
  out.global.assign(out.sm.number_of_vertices(), -1);
  // Interior input vertices were moved: only the (protected) border's are shared.
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

// The blocks' results as one mesh: a kept input vertex of `mesh` is one vertex of the
// whole (marked in the "v:seed" property), a new one is its block's own. Consumes the
// results.
SurfaceMesh StitchBlocks(const TriangleMesh& mesh, std::vector<BlockResult>* results) {
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> shared(mesh.vertices.size());  // null: not added yet
  auto seed = sm.add_property_map<SurfaceMesh::Vertex_index, bool>("v:seed", false).first;
  auto shared_vertex = [&](int i) {
    SurfaceMesh::Vertex_index& v = shared[size_t(i)];
    if (v == SurfaceMesh::null_vertex()) {
      const auto& p = mesh.vertices[i];
      v = sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
      seed[v] = true;
    }
    return v;
  };
  size_t dropped = 0;
  for (BlockResult& r : *results) {
    std::vector<SurfaceMesh::Vertex_index> index(r.sm.number_of_vertices());
    for (auto v : r.sm.vertices()) {
      const int gi = r.global[uint32_t(v)];
      index[uint32_t(v)] = gi >= 0 ? shared_vertex(gi) : sm.add_vertex(r.sm.point(v));
    }
    for (auto f : r.sm.faces()) {
      std::array<SurfaceMesh::Vertex_index, 3> tri;
      int k = 0;
      for (auto v : CGAL::vertices_around_face(r.sm.halfedge(f), r.sm)) tri[k++] = index[uint32_t(v)];
      dropped += sm.add_face(tri[0], tri[1], tri[2]) == SurfaceMesh::null_face();
    }
    for (const auto& t : r.kept)
      dropped += sm.add_face(shared_vertex(t[0]), shared_vertex(t[1]), shared_vertex(t[2])) ==
                 SurfaceMesh::null_face();
    r = BlockResult{};
  }
  if (dropped > 0) spdlog::debug("remesh: dropped {} non-manifold faces", dropped);
  DropIsolatedVertices(&sm);
  SATMESH_CHECK(sm.number_of_faces() > 0, ErrorCode::kInvalidInput,
                "remesh: the initial mesh has no usable (manifold) face");
  return sm;
}

// Large meshes: the blocks remeshed in parallel with their borders kept, stitched at the
// kept border vertices, then the band around the borders (two rings of faces) remeshed
// as one patch, so that no trace of the blocks is left.
SurfaceMesh RemeshInBlocks(TriangleMesh mesh, std::vector<int> block, int num_blocks,
                           const CoarseMeshOptions& options, const Progress& progress) {
  SplitLongBlockBorders(4.0 / 3.0 * options.target_edge_m, &mesh, &block);
  std::vector<std::vector<int>> block_faces(num_blocks);
  for (size_t f = 0; f < mesh.faces.size(); ++f) block_faces[block[f]].push_back(int(f));

  std::vector<BlockResult> results(num_blocks);
  const std::function<bool()> cancelled = [&] { return progress.Cancelled(); };
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic, 1)
  for (int b = 0; b < num_blocks; ++b) {
    try {
      results[b] = RemeshBlock(mesh, block_faces[b], options, cancelled);
    } catch (...) {
#pragma omp critical(satmesh_remesh_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  progress.ThrowIfCancelled();

  SurfaceMesh sm = StitchBlocks(mesh, &results);
  auto seed = sm.property_map<SurfaceMesh::Vertex_index, bool>("v:seed").first;

  // The band: faces within two rings of a kept (border) vertex (ring 1 or 2); what its
  // relaxed vertices are put back on: within four (ring 1 to 4), not the whole surface (a
  // tree of the band's neighbourhood, not of every face: stereo 0.5 m s1, 0.35 -> 0.05 s).
  std::vector<char> ring_of(sm.number_of_faces(), 0);
  std::vector<SurfaceMesh::Vertex_index> ring;
  for (auto v : sm.vertices())
    if (seed[v]) ring.push_back(v);
  std::vector<char> seen(sm.number_of_vertices(), 0);
  for (int r = 1; r <= 4; ++r) {
    std::vector<SurfaceMesh::Vertex_index> next;
    for (auto v : ring) {
      if (seen[uint32_t(v)]) continue;
      seen[uint32_t(v)] = 1;
      for (auto f : CGAL::faces_around_target(sm.halfedge(v), sm)) {
        if (f == SurfaceMesh::null_face() || ring_of[uint32_t(f)]) continue;
        ring_of[uint32_t(f)] = char(r);
        for (auto w : CGAL::vertices_around_face(sm.halfedge(f), sm)) next.push_back(w);
      }
    }
    ring = std::move(next);
  }
  const auto in_band = [&](SurfaceMesh::Face_index f) {
    return ring_of[uint32_t(f)] > 0 && ring_of[uint32_t(f)] <= 2;
  };
  std::vector<SurfaceMesh::Face_index> band, near_band;
  for (auto f : sm.faces()) {
    if (in_band(f)) band.push_back(f);
    if (ring_of[uint32_t(f)] > 0) near_band.push_back(f);
  }
  const auto is_constrained = ConstrainedEdges(&sm, options.crease_angle_deg);
  spdlog::debug("remesh: {} blocks, band of {} faces", num_blocks, band.size());
  // The band, one iteration at a time (its face range does not survive one): then the
  // faces with a vertex off the blocks' remeshed insides (a vertex CGAL makes is).
  auto inside = sm.add_property_map<SurfaceMesh::Vertex_index, bool>("v:inside", false).first;
  for (auto f : sm.faces())
    if (!in_band(f))
      for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) inside[v] = true;
  const SurfaceProjector input(sm, near_band);
  auto hints = sm.add_property_map<SurfaceMesh::Vertex_index, uint32_t>(
                    "v:projected", SurfaceProjector::kNoHint).first;
  for (int it = 0; it < options.iterations && !band.empty(); ++it) {
    progress.ThrowIfCancelled();
    if (it > 0) {
      band.clear();
      for (auto f : sm.faces())
        for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm))
          if (!inside[v]) {
            band.push_back(f);
            break;
          }
    }
    PMP::isotropic_remeshing(band, options.target_edge_m, sm,
                             PMP::parameters::number_of_iterations(1)
                                 .number_of_relaxation_steps(0)
                                 .do_project(false)
                                 .projection_functor(KeepPosition{&sm})
                                 .edge_is_constrained_map(is_constrained)
                                 .protect_constraints(false)
                                 .relax_constraints(false));
    RelaxTangentially(is_constrained, input, hints, &sm,
                      [&](SurfaceMesh::Vertex_index v) { return !inside[v]; });
  }
  sm.remove_property_map(hints);
  progress.ThrowIfCancelled();
  return sm;
}

}  // namespace

TriangleMesh RemeshIsotropic(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                             const Progress& progress) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "CoarseMeshOptions: " + problem);
  SATMESH_CHECK(!mesh.faces.empty(), ErrorCode::kInvalidInput, "remesh: the initial mesh has no face");
  int num_blocks = 1;
  std::vector<int> block = AssignBlocks(mesh, options.faces_per_block, &num_blocks);
  SurfaceMesh sm = num_blocks > 1
                       ? RemeshInBlocks(mesh, std::move(block), num_blocks, options, progress)
                       : RemeshWhole(mesh, options, progress);
  sm.collect_garbage();
  TriangleMesh out = FromSurfaceMesh(sm, mesh);
  SortSpatially(&out);
  return out;
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
            [](const Eigen::Vector3i& a, const Eigen::Vector3i& b) { return a.minCoeff() < b.minCoeff(); });
}

}  // namespace satmesh
