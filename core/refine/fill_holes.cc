#include "core/refine/fill_holes.h"

#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <vector>

#include "core/raycast/ray_scene.h"
#include "core/refine/cgal_surface.h"

namespace satmesh {

using cgal_surface::Kernel;
using cgal_surface::SurfaceMesh;
namespace PMP = CGAL::Polygon_mesh_processing;

HoleFill FillHoles(double max_extent_m, std::vector<Eigen::Vector3d>* points,
                   std::vector<Eigen::Vector3i>* faces) {
  HoleFill out;
  SurfaceMesh sm;
  for (const auto& p : *points) sm.add_vertex(Kernel::Point_3(p.x(), p.y(), p.z()));
  std::vector<Eigen::Vector3i> kept;  // faces CGAL cannot take, kept as they are
  for (const auto& f : *faces)
    if (sm.add_face(SurfaceMesh::Vertex_index(f[0]), SurfaceMesh::Vertex_index(f[1]),
                    SurfaceMesh::Vertex_index(f[2])) == SurfaceMesh::null_face())
      kept.push_back(f);
  std::vector<SurfaceMesh::Halfedge_index> cycles;
  PMP::extract_boundary_cycles(sm, std::back_inserter(cycles));
  // A hole something covers from above (the ground's cut-out under a building whose walls
  // do not share its vertices) is no gap: what the images see is there. The test: a ray
  // up from the border's centroid, above its highest point, hits the mesh.
  std::vector<SurfaceMesh::Halfedge_index> holes;
  std::vector<Ray> up;
  const Eigen::Vector3d origin =  // float coordinates about it for Embree
      points->empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(points->front().array().round());
  for (const auto h0 : cycles) {
    // Shoelace area (x, y) and box of the cycle.
    double area2 = 0, xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (const auto h : CGAL::halfedges_around_face(h0, sm)) {
      const auto& a = sm.point(sm.source(h));
      const auto& b = sm.point(sm.target(h));
      area2 += a.x() * b.y() - b.x() * a.y();
      xmin = std::min(xmin, a.x()), xmax = std::max(xmax, a.x());
      ymin = std::min(ymin, a.y()), ymax = std::max(ymax, a.y());
    }
    if (!(area2 > 0)) continue;  // an outer border
    if (std::hypot(xmax - xmin, ymax - ymin) > max_extent_m) {
      ++out.too_big;
      continue;
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    double zmax = -1e300;
    int n = 0;
    for (const auto v : CGAL::vertices_around_face(h0, sm)) {
      const auto& p = sm.point(v);
      centroid += Eigen::Vector3d(p.x(), p.y(), p.z()), ++n;
      zmax = std::max(zmax, p.z());
    }
    centroid /= double(n);
    holes.push_back(h0);
    const Eigen::Vector3d start(centroid.x(), centroid.y(), zmax + 0.1);
    up.push_back(Ray{(start - origin).cast<float>(), Eigen::Vector3f::UnitZ()});
  }
  std::vector<RayHit> hits(up.size());
  if (!up.empty()) {
    TriangleMesh frame;
    frame.faces = *faces;
    for (const auto& p : *points) frame.vertices.push_back((p - origin).cast<float>());
    RayScene(frame).Intersect(up.data(), hits.data(), up.size());
  }
  for (size_t i = 0; i < holes.size(); ++i) {
    if (hits[i].hit()) {
      ++out.covered;
      continue;
    }
    const auto h0 = holes[i];
    std::vector<SurfaceMesh::Face_index> new_faces;
    std::vector<SurfaceMesh::Vertex_index> new_vertices;
    PMP::triangulate_refine_and_fair_hole(sm, h0, std::back_inserter(new_faces),
                                          std::back_inserter(new_vertices));
    if (!new_faces.empty()) ++out.filled, out.faces_added += new_faces.size();
  }
  if (out.filled == 0) return out;
  // Vertices keep their indices (nothing was removed); new ones follow.
  points->resize(sm.number_of_vertices());
  for (auto v : sm.vertices()) {
    const auto& p = sm.point(v);
    (*points)[uint32_t(v)] = Eigen::Vector3d(p.x(), p.y(), p.z());
  }
  faces->clear();
  for (auto f : sm.faces()) {
    Eigen::Vector3i tri;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) tri[k++] = int(uint32_t(v));
    faces->push_back(tri);
  }
  faces->insert(faces->end(), kept.begin(), kept.end());
  return out;
}

}  // namespace satmesh
