#include "core/synth/perturb.h"

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <tuple>
#include <vector>

#include "core/common/error.h"
#include "core/mesh/topology.h"

namespace satmesh::synth {

std::string PerturbOptions::Check() const {
  if (!(amplitude_m >= 0 && std::isfinite(amplitude_m)))
    return "amplitude_m must be >= 0, got " + std::to_string(amplitude_m);
  if (!(wavelength_m > 0 && std::isfinite(wavelength_m)))
    return "wavelength_m must be > 0, got " + std::to_string(wavelength_m);
  if (waves < 1 || waves > 64) return "waves must be in [1, 64], got " + std::to_string(waves);
  return "";
}

TriangleMesh PerturbAlongNormals(const TriangleMesh& mesh, const PerturbOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "PerturbOptions: " + problem);
  std::mt19937 rng(options.seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> phase(0, 2 * std::numbers::pi);
  std::vector<Eigen::Vector3d> directions;
  std::vector<double> phases;
  for (int k = 0; k < options.waves; ++k) {
    directions.push_back(Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng)).normalized());
    phases.push_back(phase(rng));
  }
  // One normal per position (split vertices share it).
  const std::vector<Eigen::Vector3f> normals = VertexNormals(mesh);
  std::map<std::tuple<float, float, float>, Eigen::Vector3f> by_position;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    auto [it, inserted] = by_position.try_emplace({v.x(), v.y(), v.z()}, Eigen::Vector3f::Zero());
    it->second += normals[i];
  }
  TriangleMesh out = mesh;
  const double scale = options.amplitude_m / std::sqrt(double(options.waves));
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    const Eigen::Vector3f n = by_position.at({v.x(), v.y(), v.z()}).normalized();
    if (!n.allFinite()) continue;  // an unreferenced vertex
    const Eigen::Vector3d p = mesh.AbsoluteVertex(i);
    double noise = 0;
    for (int k = 0; k < options.waves; ++k)
      noise += std::sin(2 * std::numbers::pi * directions[k].dot(p) / options.wavelength_m + phases[k]);
    out.vertices[i] = v + float(scale * noise) * n;
  }
  return out;
}

}  // namespace satmesh::synth
