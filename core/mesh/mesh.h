#pragma once
// Indexed triangle mesh with a double-precision origin: a vertex's coordinate in the
// mesh's CRS (or frame) is origin + vertices[i]. Geometry is tile-local float.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace satmesh {

struct TriangleMesh {
  Eigen::Vector3d origin{0, 0, 0};       // added to every vertex
  std::vector<Eigen::Vector3f> vertices;  // tile-local positions
  std::vector<Eigen::Vector3i> faces;     // counter-clockwise seen from outside
  std::string crs;                        // CRS of origin+vertices ("" = unknown/local)
  // Optional, per vertex (empty: unknown): metres to which the images determine the
  // vertex along the surface normal (1 sigma under their noise; +inf: no image sees it).
  // Written by the refinement (RefineResult::mesh), kept by PLY and the tile pipeline.
  std::vector<float> height_sigma;

  size_t num_vertices() const { return vertices.size(); }
  size_t num_faces() const { return faces.size(); }
  Eigen::Vector3d AbsoluteVertex(size_t i) const { return origin + vertices[i].cast<double>(); }
};

// Throws Error{kInvalidInput} naming the first NaN coordinate or out-of-range index.
void ValidateMesh(const TriangleMesh& mesh, const std::string& what = "mesh");

}  // namespace satmesh
