#include "core/refine/edge_bias.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>

#include "core/mesh/topology.h"

namespace satmesh {

namespace {

// Face f's normal scaled by twice its area (the edges' cross product).
Eigen::Vector3d AreaNormal(const TriangleMesh& mesh, const Eigen::Vector3i& f) {
  const Eigen::Vector3f& a = mesh.vertices[f[0]];
  return (mesh.vertices[f[1]] - a).cross(mesh.vertices[f[2]] - a).cast<double>();
}

// A wall face: steeper than kWallMaxNormalZ allows (a degenerate face is none).
bool IsWall(const Eigen::Vector3d& area_normal) {
  return std::abs(area_normal.z()) < double(kWallMaxNormalZ) * area_normal.norm();
}

}  // namespace

std::vector<char> WallVertices(const TriangleMesh& mesh) {
  std::vector<char> on_wall(mesh.vertices.size(), 0);
  for (const Eigen::Vector3i& f : mesh.faces)
    if (IsWall(AreaNormal(mesh, f))) on_wall[f[0]] = on_wall[f[1]] = on_wall[f[2]] = 1;
  return on_wall;
}

std::vector<Eigen::Vector3f> WallNormals(const TriangleMesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.vertices.size(), Eigen::Vector3d::Zero());
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d n = AreaNormal(mesh, f);
    if (!IsWall(n)) continue;
    const Eigen::Vector3d h = n.norm() / n.head<2>().norm() * Eigen::Vector3d(n.x(), n.y(), 0);
    for (int k = 0; k < 3; ++k) sum[f[k]] += h;
  }
  std::vector<Eigen::Vector3f> normals(sum.size(), Eigen::Vector3f::Zero());
  for (size_t v = 0; v < sum.size(); ++v)
    if (sum[v].norm() > 0) normals[v] = sum[v].normalized().cast<float>();
  return normals;
}

EdgeBiasStats DeflateOccludingEdges(double distance_m, TriangleMesh* mesh) {
  EdgeBiasStats stats;
  if (distance_m == 0 || !std::isfinite(distance_m) || mesh->faces.empty()) return stats;
  const size_t nv = mesh->vertices.size();
  // Per vertex, its wall faces' horizontal unit normals weighted by area: the move d that
  // takes each wall in by distance_m (d . n = -distance_m) in the least-squares sense,
  // d = -distance_m M^+ b with M = sum w n n^T, b = sum w n: along the normal on a plain
  // wall, into the corner on two (by distance_m from each wall).
  std::vector<Eigen::Matrix2d> m(nv, Eigen::Matrix2d::Zero());
  std::vector<Eigen::Vector2d> b(nv, Eigen::Vector2d::Zero());
  for (const Eigen::Vector3i& f : mesh->faces) {
    const Eigen::Vector3d n = AreaNormal(*mesh, f);
    if (!IsWall(n)) continue;
    const double area2 = n.norm(), horizontal = n.head<2>().norm();
    const Eigen::Vector2d h = n.head<2>() / horizontal;
    for (int k = 0; k < 3; ++k) {
      m[f[k]] += area2 * h * h.transpose();
      b[f[k]] += area2 * h;
    }
  }
  const VertexAdjacency adjacency = BuildVertexAdjacency(*mesh);
  for (size_t v = 0; v < nv; ++v) {
    if (b[v].isZero() || adjacency.is_boundary[v]) continue;
    // Pseudo-inverse: directions the walls barely constrain (one wall, or walls nearly
    // parallel) get no move.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(m[v]);
    const double top = eig.eigenvalues().maxCoeff();
    Eigen::Vector2d d = Eigen::Vector2d::Zero();
    for (int k = 0; k < 2; ++k)
      if (eig.eigenvalues()[k] > 0.1 * top) {
        const Eigen::Vector2d e = eig.eigenvectors().col(k);
        d -= distance_m * e.dot(b[v]) / eig.eigenvalues()[k] * e;
      }
    mesh->vertices[v].head<2>() += d.cast<float>();
    ++stats.moved;
  }
  return stats;
}

}  // namespace satmesh
