#pragma once
// A procedural city: gently rolling ground with a street grid, buildings of varied
// footprint (rotated, L-shapes) and height with setbacks, parapets, rooftop structures,
// solar panels, gable and hip roofs, and true 3D facade structure (arcades under
// overhanging upper floors, facade recesses, balconies); optional street trees.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/synth/texture.h"

namespace satmesh::synth {

struct CityOptions {
  double aoi_size_m = 300;           // side of the square area of interest, m, > 0
  double building_margin_m = 30;     // buildings also this far beyond the AOI, m, >= 0
  double ground_margin_m = 90;       // ground mesh this far beyond the AOI, m, >= 0
  double ground_cell_m = 1.0;        // ground triangulation step, m, (0, 10]
  double relief_m = 2.0;             // amplitude of the ground relief, m, [0, 20]
  double street_pitch_m = 80;        // street grid period, m, > street_width + 2 sidewalks + 10
  double street_width_m = 12;        // kerb to kerb, m (an even number of ground cells), > 0
  double sidewalk_width_m = 3;       // m, >= 0
  double min_height_m = 4;           // building heights, m, 2 <= min <= max
  double max_height_m = 60;
  double sloped_roof_fraction = 0.25;  // buildings with gable/hip roofs, [0, 1]
  double arcade_fraction = 0.3;        // recessed ground floor under upper floors, [0, 1]
  double recess_fraction = 0.3;        // facade recess (loggia slot), [0, 1]
  double balcony_fraction = 0.35;      // balconies on one or two facades, [0, 1]
  bool trees = true;                 // street trees (crowns over sidewalks)
  std::string Check() const;
};

// Ground height (relative to the mesh origin) as a sum of long-wavelength waves.
struct GroundRelief {
  std::vector<Eigen::Vector4d> waves;  // (amplitude m, kx rad/m, ky rad/m, phase rad)
  double Height(double x, double y) const;
};

struct CityModel {
  TriangleMesh mesh;                    // origin: AOI centre; vertices local, z up
  std::vector<Material> face_material;  // per face
  std::vector<uint32_t> face_variant;   // per face: building index + 1, 0 for ground/trees
  GroundRelief ground;
  TextureParams texture;                // street grid matching the layout
  int num_buildings = 0;
  float max_building_height_m = 0;      // above the local ground
};

// Builds the city around `origin` (scene CRS x, y and ellipsoidal base height h).
// Throws Error{kInvalidArgument} if options.Check() fails.
CityModel BuildCity(const CityOptions& options, uint32_t seed, const Eigen::Vector3d& origin,
                    const std::string& crs);

// Boundary of a union/difference of axis-aligned boxes, as a conforming quad mesh split
// into triangles (exposed to building and rooftop-structure generators and tests).
struct CityBox {
  Eigen::Vector3f lo, hi;
  bool subtract = false;                 // carve out instead of fill
  Material wall = Material::kFacade;     // vertical faces
  Material top = Material::kRoofGravel;  // upward faces; kCount: not emitted
  Material bottom = Material::kSoffit;   // downward faces (not at the lowest level)
};
struct BoxMeshPart {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3i> faces;
  std::vector<Material> face_material;
};
// Boxes apply in order. Vertices are in the boxes' frame.
BoxMeshPart MeshBoxes(const std::vector<CityBox>& boxes);

}  // namespace satmesh::synth
