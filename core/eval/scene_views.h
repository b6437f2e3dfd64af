#pragma once
// The views of a scene directory for the 3D metrics that count what the images see
// (SeenByViews): each image's RPC and size, the directions towards its sensor.
#include <string>
#include <vector>

#include "core/eval/mesh_metrics.h"

namespace satmesh {

// The GeoTIFFs of `images_dir` (*.tif, by name), each with its RPC; none if the directory
// does not exist. Throws Error naming an image whose RPC cannot be read.
std::vector<std::string> SceneImages(const std::string& images_dir);

// Directions for points in `mesh_crs` (a projected CRS with ellipsoidal heights, as the
// synthetic scenes' meshes): each point's line of sight in each image is the direction
// along which the RPC's pixel does not change, the null vector of d(col, row)/d(x, y, z)
// (PixelFromGeo's analytic Jacobian, the CRS's own Jacobian from PROJ at the points'
// centre), turned upwards. A point outside an image gets zero for it.
ViewDirectionsFn SceneViewDirections(const std::vector<std::string>& image_paths,
                                     const std::string& mesh_crs);

}  // namespace satmesh
