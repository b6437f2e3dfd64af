#include "core/synth/truth.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace satmesh::synth {
namespace {

double Median(std::vector<double> v) {
  const size_t k = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

std::vector<uint8_t> RoofMask(const RenderScene& scene, const Dsm& truth, double edge_band_m) {
  const int w = truth.width, h = truth.height;
  const TriangleMesh& mesh = scene.city().mesh;
  float ztop = -1e30f;
  for (const auto& v : mesh.vertices) ztop = std::max(ztop, v.z());
  std::vector<Ray> rays(size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      Ray& r = rays[size_t(j) * w + i];
      r.origin = Eigen::Vector3f(float(truth.CellCenterX(i) - mesh.origin.x()),
                                 float(truth.CellCenterY(j) - mesh.origin.y()), ztop + 10.f);
      r.direction = -Eigen::Vector3f::UnitZ();
    }
  std::vector<RayHit> hits(rays.size());
  scene.Intersect(rays.data(), hits.data(), rays.size());
  cv::Mat roof(h, w, CV_8U, cv::Scalar(0));
  cv::Mat material(h, w, CV_8U, cv::Scalar(255));
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const RayHit& hit = hits[size_t(j) * w + i];
      if (!hit.hit()) continue;
      const Material m = scene.city().face_material[hit.face];
      material.at<uint8_t>(j, i) = uint8_t(m);
      roof.at<uint8_t>(j, i) = IsRoof(m) ? 1 : 0;
    }
  // Cells at material changes or height steps are edges too.
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      if (!roof.at<uint8_t>(j, i)) continue;
      const float z = truth.at(i, j);
      for (auto [di, dj] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int a = std::clamp(i + di, 0, w - 1), b = std::clamp(j + dj, 0, h - 1);
        if (material.at<uint8_t>(b, a) != material.at<uint8_t>(j, i) ||
            !(std::abs(truth.at(a, b) - z) <= 0.5f))
          roof.at<uint8_t>(j, i) = 2;  // edge, removed below with its band
      }
    }
  cv::Mat inner = (roof == 1);
  const int r = int(std::ceil(edge_band_m / std::abs(truth.geo_transform[1])));
  if (r > 0) {
    cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
    cv::erode(inner, inner, kernel, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  }
  std::vector<uint8_t> mask(size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) mask[size_t(j) * w + i] = inner.at<uint8_t>(j, i) ? 1 : 0;
  return mask;
}

void SampleFacadePoints(const CityModel& city, const Eigen::Vector2d& xy_min,
                        const Eigen::Vector2d& xy_max, double spacing_m, uint64_t seed,
                        std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3f>* normals) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const TriangleMesh& m = city.mesh;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (!IsBuilding(city.face_material[f])) continue;
    const Eigen::Vector3d a = m.vertices[m.faces[f][0]].cast<double>(),
                          b = m.vertices[m.faces[f][1]].cast<double>(),
                          c = m.vertices[m.faces[f][2]].cast<double>();
    const Eigen::Vector3d cr = (b - a).cross(c - a);
    const double area = 0.5 * cr.norm();
    if (!(area > 0)) continue;
    const Eigen::Vector3d n = cr.normalized();
    if (!(std::abs(n.z()) < 0.9 || n.z() < -0.9)) continue;
    const double expected = area / (spacing_m * spacing_m);
    int count = int(expected);
    if (u(gen) < expected - count) ++count;
    for (int k = 0; k < count; ++k) {
      double s = u(gen), t = u(gen);
      if (s + t > 1) s = 1 - s, t = 1 - t;
      const Eigen::Vector3d p = a + s * (b - a) + t * (c - a);
      if (p.z() < city.ground.Height(p.x(), p.y()) + 0.02) continue;
      const Eigen::Vector3d g = p + m.origin;
      if (g.x() < xy_min.x() || g.y() < xy_min.y() || g.x() > xy_max.x() || g.y() > xy_max.y())
        continue;
      points->push_back(g);
      normals->push_back(n.cast<float>());
    }
  }
}

Eigen::Vector2d MaskedNmadP68(const Dsm& a, const Dsm& b, const std::vector<uint8_t>& mask) {
  std::vector<double> r;
  for (size_t k = 0; k < mask.size(); ++k)
    if (mask[k] && std::isfinite(a.z[k]) && std::isfinite(b.z[k])) r.push_back(a.z[k] - b.z[k]);
  if (r.empty()) return {NAN, NAN};
  const double med = Median(r);
  std::vector<double> dev(r.size()), ab(r.size());
  for (size_t k = 0; k < r.size(); ++k) dev[k] = std::abs(r[k] - med), ab[k] = std::abs(r[k]);
  std::sort(ab.begin(), ab.end());
  return {1.4826 * Median(dev), ab[std::min(ab.size() - 1, size_t(0.68 * ab.size()))]};
}

}  // namespace satmesh::synth
