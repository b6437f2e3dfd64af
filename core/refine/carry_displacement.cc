#include "core/refine/carry_displacement.h"

#include <algorithm>
#include <string>

#include "core/common/error.h"
#include "core/mesh/topology.h"
#include "core/refine/cgal_surface.h"

namespace satmesh {

using cgal_surface::Kernel;

TriangleMesh CarryDisplacement(const TriangleMesh& start, const TriangleMesh& end,
                               TriangleMesh target) {
  SATMESH_CHECK(start.num_vertices() == end.num_vertices() && start.num_faces() > 0,
                ErrorCode::kInvalidArgument,
                "CarryDisplacement: start and end must be one mesh with faces (" +
                    std::to_string(start.num_vertices()) + " vs " +
                    std::to_string(end.num_vertices()) + " vertices, " +
                    std::to_string(start.num_faces()) + " faces)");
  const auto point = [&](int v) {
    const Eigen::Vector3f& p = start.vertices[size_t(v)];
    return Kernel::Point_3(p.x(), p.y(), p.z());
  };
  cgal_surface::ClosestTriangle faces;
  for (size_t f = 0; f < start.num_faces(); ++f) {
    const Eigen::Vector3i& t = start.faces[f];
    faces.Add(point(t[0]), point(t[1]), point(t[2]), f);
  }
  SATMESH_CHECK(!faces.empty(), ErrorCode::kInvalidArgument,
                "CarryDisplacement: start has only degenerate faces");
  faces.Build();
  const Eigen::Vector3d offset = target.origin - start.origin;
  const std::vector<Eigen::Vector3f> normals = VertexNormals(target);
#pragma omp parallel for schedule(dynamic, 1024)
  for (long v = 0; v < long(target.num_vertices()); ++v) {
    const Eigen::Vector3d p = target.vertices[size_t(v)].cast<double>() + offset;
    const auto [closest, face] = faces.Closest(Kernel::Point_3(p.x(), p.y(), p.z()));
    const Eigen::Vector3i& t = start.faces[face];
    // Barycentric coordinates of the closest point in its triangle (least squares, so a
    // point on an edge is exact too).
    const Eigen::Vector3d a = start.vertices[size_t(t[0])].cast<double>();
    const Eigen::Vector3d e1 = start.vertices[size_t(t[1])].cast<double>() - a;
    const Eigen::Vector3d e2 = start.vertices[size_t(t[2])].cast<double>() - a;
    const Eigen::Vector3d q = Eigen::Vector3d(closest.x(), closest.y(), closest.z()) - a;
    const double d00 = e1.dot(e1), d01 = e1.dot(e2), d11 = e2.dot(e2);
    const double d20 = q.dot(e1), d21 = q.dot(e2);
    const double den = d00 * d11 - d01 * d01;
    double b1 = 0, b2 = 0;
    if (den > 1e-12 * d00 * d11) {
      b1 = std::clamp((d11 * d20 - d01 * d21) / den, 0.0, 1.0);
      b2 = std::clamp((d00 * d21 - d01 * d20) / den, 0.0, 1.0 - b1);
    } else {  // a sliver (its corners collinear in double): its nearest corner's move
      const double q0 = q.squaredNorm(), q1 = (q - e1).squaredNorm(), q2 = (q - e2).squaredNorm();
      if (q1 < q0 && q1 <= q2)
        b1 = 1;
      else if (q2 < q0)
        b2 = 1;
    }
    const double b0 = 1.0 - b1 - b2;
    Eigen::Vector3d moved = Eigen::Vector3d::Zero();
    const double b[3] = {b0, b1, b2};
    for (int c = 0; c < 3; ++c)
      moved += b[c] * (end.vertices[size_t(t[c])] - start.vertices[size_t(t[c])]).cast<double>();
    // Up-facing parts (roofs, ground) move with the coarse level; walls and overhangs,
    // which a coarse mesh does not hold, keep their own place.
    // And only where the coarse face is of the same surface (normals within 37 degrees,
    // fading from 18): near a wall the coarse mesh bridges roof and street with a slope
    // whose move is the wall's blur, not the roof's or the street's correction.
    const Eigen::Vector3d n = normals[size_t(v)].cast<double>();
    const double up = std::clamp((n.z() - 0.5) / 0.3, 0.0, 1.0);
    const double same = std::clamp((e1.cross(e2).normalized().dot(n) - 0.8) / 0.15, 0.0, 1.0);
    moved *= up * same;
    target.vertices[size_t(v)] += moved.cast<float>();
  }
  target.height_sigma.clear();
  return target;
}

}  // namespace satmesh
