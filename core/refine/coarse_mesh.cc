#include "core/refine/coarse_mesh.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdint>
#include <unordered_map>

#include "core/common/error.h"

namespace satmesh {
namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

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
  // Drop vertices no face uses.
  for (auto v : out.vertices()) {
    if (out.is_isolated(v)) out.remove_vertex(v);
  }
  out.collect_garbage();
  return out;
}

TriangleMesh FromSurfaceMesh(const SurfaceMesh& sm, const TriangleMesh& like) {
  TriangleMesh out;
  out.origin = like.origin;
  out.crs = like.crs;
  std::unordered_map<uint32_t, int> index;
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
  return "";
}

TriangleMesh RemeshIsotropic(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                             const Progress& progress) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "CoarseMeshOptions: " + problem);
  size_t dropped = 0;
  SurfaceMesh sm = ToSurfaceMesh(mesh, &dropped);
  if (dropped > 0) spdlog::debug("remesh: dropped {} non-manifold faces", dropped);
  SATMESH_CHECK(sm.number_of_faces() > 0, ErrorCode::kInvalidInput,
                "remesh: the initial mesh has no usable (manifold) face");

  auto is_constrained =
      sm.add_property_map<SurfaceMesh::Edge_index, bool>("e:is_constrained", false).first;
  std::vector<SurfaceMesh::Halfedge_index> border;
  PMP::border_halfedges(faces(sm), sm, std::back_inserter(border));
  for (auto h : border) is_constrained[edge(h, sm)] = true;

  // One CGAL iteration at a time: a large tile's remeshing takes tens of seconds, and
  // cancellation must reach it within one iteration.
  for (int it = 0; it < options.iterations; ++it) {
    progress.ThrowIfCancelled();
    PMP::isotropic_remeshing(faces(sm), options.target_edge_m, sm,
                             PMP::parameters::number_of_iterations(1)
                                 .edge_is_constrained_map(is_constrained)
                                 .protect_constraints(false)
                                 .relax_constraints(false));
  }
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
