#pragma once
// A refinement job in core terms (no JSON here: proto/ parses the wire format into this)
// and the in-process runner that reads inputs, refines and writes the outputs.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/refine/refine.h"

namespace satmesh {

struct JobImage {
  std::string path;                        // GDAL-readable image with an RPC
  Eigen::Vector2d bias_col_row_px{0, 0};   // RPC bias correction, full-resolution pixels
};

struct JobSpec {
  std::vector<JobImage> images;
  std::string initial_dsm;     // GeoTIFF DSM (ellipsoidal heights), required for now
  std::string output_crs;      // "" = the initial DSM's CRS
  RefineOptions refine;
  std::string Check() const;   // "" or what is wrong (field named)
};

struct JobOutputs {
  std::string mesh_path, dsm_path;  // out_dir/mesh.ply, out_dir/dsm.tif
  RefineResult refine;
  std::vector<std::string> view_names;
  double prepare_s = 0, write_s = 0;
};

// Reads the images (only the windows that see the surface), builds the local frame and
// the initial mesh, refines, writes out_dir/mesh.ply (binary, double, output CRS) and
// out_dir/dsm.tif (highest hit on the initial DSM's grid). Throws Error naming the input
// that is wrong.
JobOutputs RunJob(const JobSpec& spec, const std::string& out_dir, const Progress& progress = {});

}  // namespace satmesh
