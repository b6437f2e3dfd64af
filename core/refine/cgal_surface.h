#pragma once
// CGAL's surface types as the refinement's meshing code uses them, and what it adds to
// them: the closest triangle (AABB tree) and the tangential relaxation of isotropic
// remeshing. Internal to core/refine (coarse_mesh.cc, carry_displacement.cc,
// fill_holes.cc): CGAL types stay out of the public headers.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace satmesh::cgal_surface {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;

// The closest point on a set of triangles and which triangle it is on (CGAL's AABB tree;
// degenerate triangles are left out). Add every triangle, then Build, then query (from
// any number of threads).
class ClosestTriangle {
 public:
  void Add(const Kernel::Point_3& a, const Kernel::Point_3& b, const Kernel::Point_3& c,
           size_t id) {
    const Triangle t(a, b, c);
    if (t.is_degenerate()) return;
    triangles_.push_back(t);
    ids_.push_back(id);
  }
  void Build() {
    if (triangles_.empty()) return;
    tree_.rebuild(triangles_.cbegin(), triangles_.cend());
    tree_.accelerate_distance_queries();
  }
  bool empty() const { return triangles_.empty(); }
  // The closest point and the id it was added with; not empty().
  std::pair<Kernel::Point_3, size_t> Closest(const Kernel::Point_3& p) const {
    const auto [q, it] = tree_.closest_point_and_primitive(p);
    return {q, ids_[size_t(it - triangles_.cbegin())]};
  }
  // The closest point, the search started from triangle *index when it is < size() (an
  // index this returned before, e.g. for a nearby point: any gives the same answer, a near
  // one sooner); *index is set to the closest triangle's index.
  static constexpr size_t kNoHint = ~size_t{0};
  Kernel::Point_3 Closest(const Kernel::Point_3& p, size_t* index) const {
    const auto [q, it] =
        *index < triangles_.size()
            ? tree_.closest_point_and_primitive(
                  p, std::make_pair(Kernel().construct_projected_point_3_object()(
                                        triangles_[*index], p),
                                    triangles_.cbegin() + long(*index)))
            : tree_.closest_point_and_primitive(p);
    *index = size_t(it - triangles_.cbegin());
    return q;
  }
  size_t size() const { return triangles_.size(); }

 private:
  using Triangle = Kernel::Triangle_3;
  using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
  std::vector<Triangle> triangles_;
  std::vector<size_t> ids_;
  CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>> tree_;
};

// The closest point on a surface: the input of a remeshing, which its vertices are put
// back on after they moved (as CGAL's remeshing projects them).
class SurfaceProjector {
 public:
  explicit SurfaceProjector(const SurfaceMesh& sm) {
    for (auto f : sm.faces()) {
      std::array<Kernel::Point_3, 3> q;
      int k = 0;
      for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) q[k++] = sm.point(v);
      faces_.Add(q[0], q[1], q[2], uint32_t(f));
    }
    faces_.Build();
  }
  // The closest point; *hint: the triangle of an earlier answer for a nearby point (or
  // kNoHint), set to this answer's, so a vertex relaxed again starts where it was
  // projected last.
  static constexpr uint32_t kNoHint = ~0u;
  Kernel::Point_3 Closest(const Kernel::Point_3& p, uint32_t* hint) const {
    if (faces_.empty()) return p;
    size_t index = *hint == kNoHint ? ClosestTriangle::kNoHint : size_t(*hint);
    const Kernel::Point_3 q = faces_.Closest(p, &index);
    *hint = uint32_t(index);
    return q;
  }

 private:
  ClosestTriangle faces_;
};

// The tangential relaxation of isotropic remeshing (Botsch and Kobbelt): each vertex inside
// the surface (no border or constrained edge at it) moves to the barycentre of its
// neighbours projected onto its tangent plane (area-weighted normal); a move that turns a
// face around it by 90 degrees or more, or makes one degenerate, is halved up to five times,
// then dropped; the moved vertices are then put on `surface` (the closest point). CGAL
// 5.5's own (inside isotropic_remeshing) reads a null halfedge when every face around a
// moved vertex is degenerate (the true tri-stereo 0.5 m building mesh remeshed at 2 m
// crashed), so it is off there and done here. hints ("v:projected", initially
// SurfaceProjector::kNoHint): per vertex, the triangle of `surface` it was last projected
// onto, read and written (valid for this `surface` only).
using ProjectionHints = SurfaceMesh::Property_map<SurfaceMesh::Vertex_index, uint32_t>;
template <typename ConstraintMap>
inline void RelaxTangentially(ConstraintMap is_constrained, const SurfaceProjector& surface,
                              ProjectionHints hints, SurfaceMesh* sm) {
  using Vector = Eigen::Vector3d;
  const auto at = [&](SurfaceMesh::Vertex_index v) {
    const auto& p = sm->point(v);
    return Vector(p.x(), p.y(), p.z());
  };
  const auto face_normal = [&](SurfaceMesh::Face_index f) {  // not normalised (2 x area)
    std::array<Vector, 3> q;
    int k = 0;
    for (auto w : CGAL::vertices_around_face(sm->halfedge(f), *sm)) q[k++] = at(w);
    return Vector((q[1] - q[0]).cross(q[2] - q[0]));
  };
  std::vector<std::pair<SurfaceMesh::Vertex_index, Vector>> moves;
  for (auto v : sm->vertices()) {
    if (sm->is_isolated(v) || sm->is_border(v, /*check_all_incident_halfedges=*/true)) continue;
    Vector centre = Vector::Zero(), normal = Vector::Zero();
    int n = 0;
    bool free = true;
    for (auto h : CGAL::halfedges_around_target(sm->halfedge(v), *sm)) {
      if (is_constrained[sm->edge(h)]) {
        free = false;
        break;
      }
      centre += at(sm->source(h));
      ++n;
      if (!sm->is_border(h)) normal += face_normal(sm->face(h));
    }
    if (!free || n < 3 || !(normal.squaredNorm() > 0)) continue;
    centre /= n;
    normal.normalize();
    const Vector p = at(v);
    moves.emplace_back(v, centre + (p - centre).dot(normal) * normal);
  }
  std::vector<SurfaceMesh::Vertex_index> moved;
  for (const auto& [v, target] : moves) {
    const Vector from = at(v);
    std::vector<std::pair<SurfaceMesh::Face_index, Vector>> before;
    for (auto f : CGAL::faces_around_target(sm->halfedge(v), *sm))
      if (f != SurfaceMesh::null_face()) before.emplace_back(f, face_normal(f));
    double frac = 1;
    for (int attempt = 0; attempt <= 5; ++attempt, frac *= 0.5) {
      const Vector q = attempt == 5 ? from : Vector(from + frac * (target - from));
      sm->point(v) = Kernel::Point_3(q.x(), q.y(), q.z());
      if (attempt == 5) break;
      bool ok = true;
      for (const auto& [f, n0] : before) {
        const Vector n1 = face_normal(f);
        if (!(n1.squaredNorm() > 1e-12 * n0.squaredNorm()) || !(n1.dot(n0) > 0)) {
          ok = false;
          break;
        }
      }
      if (ok) {
        moved.push_back(v);
        break;
      }
    }
  }
  for (auto v : moved) sm->point(v) = surface.Closest(sm->point(v), &hints[v]);
}

}  // namespace satmesh::cgal_surface
