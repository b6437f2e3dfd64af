// ClipToBox: Sutherland-Hodgman against the box's four edges, one cut vertex per edge.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <utility>

#include "core/tiling/tile_run.h"

namespace satmesh {
namespace {

// Signed distance of p inside the box's half-plane `plane` (0: x >= xmin, 1: x <= xmax,
// 2: y >= ymin, 3: y <= ymax); >= 0 is inside.
double Inside(const Eigen::Vector3d& p, const Box2d& b, int plane) {
  switch (plane) {
    case 0: return p.x() - b.xmin;
    case 1: return b.xmax - p.x();
    case 2: return p.y() - b.ymin;
    default: return b.ymax - p.y();
  }
}

class Clipper {
 public:
  Clipper(const PointMesh& in, const Box2d& box)
      : box_(box), points_(in.points), sigma_(in.height_sigma) {}

  // Cuts polygon `poly` (vertex ids) by one half-plane.
  std::vector<int> Cut(const std::vector<int>& poly, int plane) {
    std::vector<int> out;
    for (size_t k = 0; k < poly.size(); ++k) {
      const int a = poly[k], b = poly[(k + 1) % poly.size()];
      const double da = Inside(points_[a], box_, plane), db = Inside(points_[b], box_, plane);
      if (da >= 0) Push(a, &out);
      if ((da >= 0) != (db >= 0)) Push(EdgeCut(a, b, plane), &out);
    }
    while (out.size() > 1 && out.front() == out.back()) out.pop_back();
    return out;
  }
  std::vector<Eigen::Vector3d>& points() { return points_; }
  const std::vector<float>& sigma() const { return sigma_; }

 private:
  static void Push(int v, std::vector<int>* poly) {
    if (poly->empty() || poly->back() != v) poly->push_back(v);
  }
  // The cut vertex of edge (a, b), computed in a canonical order so both faces sharing
  // the edge get the same vertex.
  int EdgeCut(int a, int b, int plane) {
    if (a > b) std::swap(a, b);
    const auto key = std::make_tuple(a, b, plane);
    if (auto it = cuts_.find(key); it != cuts_.end()) return it->second;
    const double da = Inside(points_[a], box_, plane), db = Inside(points_[b], box_, plane);
    if (da == 0) return a;  // on the edge already: no new (duplicate) vertex
    if (db == 0) return b;
    Eigen::Vector3d p = points_[a] + (points_[b] - points_[a]) * (da / (da - db));
    if (plane == 0) p.x() = box_.xmin;
    if (plane == 1) p.x() = box_.xmax;
    if (plane == 2) p.y() = box_.ymin;
    if (plane == 3) p.y() = box_.ymax;
    points_.push_back(p);
    if (!sigma_.empty()) {  // interpolated along the edge (+inf stays +inf)
      const float t = float(da / (da - db));
      sigma_.push_back(sigma_[a] + t * (sigma_[b] - sigma_[a]));
      if (!std::isfinite(sigma_.back())) sigma_.back() = std::max(sigma_[a], sigma_[b]);
    }
    cuts_[key] = int(points_.size()) - 1;
    return int(points_.size()) - 1;
  }

  Box2d box_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<float> sigma_;  // per point of points_, or empty
  std::map<std::tuple<int, int, int>, int> cuts_;
};

}  // namespace

PointMesh ClipToBox(const PointMesh& mesh, const Box2d& box, const MeshCleanOptions& clean) {
  Clipper clipper(mesh, box);
  std::vector<Eigen::Vector3i> faces;
  for (const auto& f : mesh.faces) {
    int inside_all = 0;
    bool outside_one = false;
    for (int plane = 0; plane < 4; ++plane) {
      int inside = 0;
      for (int k = 0; k < 3; ++k) inside += Inside(mesh.points[f[k]], box, plane) >= 0;
      inside_all += inside == 3;
      outside_one = outside_one || inside == 0;
    }
    if (outside_one) continue;
    // A face in the plane of the east or north edge (a wall standing on it) belongs to
    // the neighbour: both would keep it otherwise.
    const auto on_plane = [&](int plane) {
      for (int k = 0; k < 3; ++k)
        if (Inside(mesh.points[f[k]], box, plane) != 0) return false;
      return true;
    };
    if (on_plane(1) || on_plane(3)) continue;
    if (inside_all == 4) {
      faces.push_back(f);
      continue;
    }
    std::vector<int> poly{f[0], f[1], f[2]};
    for (int plane = 0; plane < 4 && poly.size() >= 3; ++plane) poly = clipper.Cut(poly, plane);
    for (size_t k = 1; k + 1 < poly.size(); ++k) faces.emplace_back(poly[0], poly[k], poly[k + 1]);
  }
  // Keep only the vertices the faces use.
  PointMesh out;
  std::vector<int> remap(clipper.points().size(), -1);
  for (auto& f : faces) {
    for (int k = 0; k < 3; ++k) {
      int& m = remap[f[k]];
      if (m < 0) {
        m = int(out.points.size());
        out.points.push_back(clipper.points()[f[k]]);
        if (!clipper.sigma().empty()) out.height_sigma.push_back(clipper.sigma()[f[k]]);
      }
      f[k] = m;
    }
  }
  out.faces = std::move(faces);
  return CleanPointMesh(out, clean);
}

PointMesh CleanPointMesh(const PointMesh& mesh, const MeshCleanOptions& options, MeshDebris* removed) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : mesh.points) centroid += p;
  centroid = (centroid / double(std::max<size_t>(1, mesh.points.size()))).array().round().matrix();
  TriangleMesh local;
  local.origin = centroid;
  local.faces = mesh.faces;
  local.height_sigma = mesh.height_sigma;
  local.vertices.reserve(mesh.points.size());
  for (const auto& p : mesh.points) local.vertices.push_back((p - centroid).cast<float>());
  const MeshDebris debris = CleanMesh(&local, options);
  if (removed) *removed = debris;
  if (debris.Total() == 0) return mesh;
  PointMesh out;
  out.faces = std::move(local.faces);
  out.height_sigma = std::move(local.height_sigma);
  out.points.reserve(local.vertices.size());
  for (size_t i = 0; i < local.vertices.size(); ++i) out.points.push_back(local.AbsoluteVertex(i));
  return out;
}

}  // namespace satmesh
