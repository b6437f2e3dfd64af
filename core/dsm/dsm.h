#pragma once
// Digital surface models (2.5D height grids) and conversions to/from meshes.
#include <array>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "core/raycast/ray_scene.h"

namespace satmesh {

// A north-up grid: cell (i, j) has its centre at
//   x = gt[0] + (i + 0.5) * gt[1], y = gt[3] + (j + 0.5) * gt[5]   (gt[2] = gt[4] = 0).
struct Dsm {
  int width = 0, height = 0;
  std::array<double, 6> geo_transform{0, 1, 0, 0, 0, -1};
  std::string crs_wkt;
  std::vector<float> z;  // row-major; NaN = no data

  float at(int i, int j) const { return z[size_t(j) * width + i]; }
  float& at(int i, int j) { return z[size_t(j) * width + i]; }
  double CellCenterX(int i) const { return geo_transform[0] + (i + 0.5) * geo_transform[1]; }
  double CellCenterY(int j) const { return geo_transform[3] + (j + 0.5) * geo_transform[5]; }
};

// Reads band 1 as float; the band's nodata value (and +-inf) becomes NaN. Throws
// Error{kNotFound} for a missing file, Error{kInvalidInput} naming the file for an
// unreadable one, one without geotransform, or a rotated/sheared grid.
Dsm ReadDsm(const std::string& path);
// Float32 GeoTIFF, NaN nodata, deflate-compressed (floating-point predictor), tiled.
void WriteDsm(const std::string& path, const Dsm& dsm);

// Grid triangulation of the valid cells (vertex at each cell centre, two triangles per
// 2x2 block of valid cells along the diagonal of smaller height difference, one triangle
// if exactly 3 are valid; nodata holes stay open). Faces are counter-clockwise seen from
// above (normals +z). Valid cells in no triangle (isolated, or in 1-cell-wide lines)
// make no vertex. Origin: the grid centre (x, y) and the middle of the height range,
// rounded to metres; crs = dsm.crs_wkt.
TriangleMesh MeshFromDsm(const Dsm& dsm);

// Rasterises a mesh on `grid`'s geometry (size, transform, CRS; its z is ignored) by the
// highest hit of a vertical ray through each cell centre (Embree); NaN where no hit.
// mesh.origin + vertices must be in grid's CRS. A centre exactly on the mesh boundary
// (e.g. every boundary vertex of MeshFromDsm's mesh) counts as a hit: rays that miss are
// retried 1e-3 cell away and evaluated on the hit face's plane at the exact centre, so
// DsmFromMesh(MeshFromDsm(d), d) returns every triangulated cell of d unchanged. scene:
// the mesh's own Embree scene where the caller has one (two rasters of one mesh), else
// built here.
Dsm DsmFromMesh(const TriangleMesh& mesh, const Dsm& grid, const RayScene* scene = nullptr);
// The same grid holding the topmost surface's height_sigma (barycentric between its
// vertices; +inf where a corner is seen by no image; NaN where no surface). The mesh must
// carry height_sigma.
Dsm HeightSigmaFromMesh(const TriangleMesh& mesh, const Dsm& grid,
                        const RayScene* scene = nullptr);

// The heights' noise at the scale of one cell, in the DSM's height units: the robust
// (1.4826 x MAD) spread of the second differences z[i-1] - 2 z[i] + z[i+1] along rows and
// columns over the valid cells, divided by sqrt(6) (white noise of sigma s gives second
// differences of sigma sqrt(6) s; smooth slopes give ~0, so walls and roof edges, a few
// percent of the differences, move the median little). NaN with fewer than 100 such
// differences. An s2p DSM of a Pleiades triplet (0.5 m): 0.05 m; a DSM degraded with
// 0.12 m white noise (synth): 0.15 m.
double DsmCellNoise(const Dsm& dsm);

}  // namespace satmesh
