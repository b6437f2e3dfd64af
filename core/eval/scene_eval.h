#pragma once
// Evaluation of a result surface on a synthetic scene directory (layout written by
// `satmesh synth`: truth/mesh.ply, truth/dsm.tif, truth/roof_mask.tif, initial/dsm.tif),
// and of the scene's initial DSM the same way, so callers can print initial vs result.
#include <string>

#include "core/eval/dsm_metrics.h"
#include "core/eval/mesh_metrics.h"
#include "core/mesh/mesh.h"

namespace satmesh {

struct SceneEvalOptions {
  DsmEvalOptions dsm;       // 2.5D metrics and alignment
  Mesh3dOptions mesh3d;     // 3D metrics (its crop is set to the truth DSM's extent)
  bool evaluate_3d = true;  // compute the 3D metrics (needs truth/mesh.ply)
  std::string Check() const;
};

struct SurfaceEvaluation {
  DsmEvaluation dsm;
  Mesh3dMetrics mesh3d;  // zeros if !SceneEvalOptions::evaluate_3d
};

// Result vertices grouped by their height sigma from the images (TriangleMesh::height_sigma):
// does the refinement's confidence mean something? One bin per decile of the finite
// sigmas, then one for the vertices no image saw (sigma +inf).
struct SigmaBin {
  double sigma_min_m = 0, sigma_max_m = 0;  // the bin's range
  size_t vertices = 0;
  double median_error_m = 0;  // distance of the bin's vertices to the truth mesh
  double p90_error_m = 0;
};

struct SceneEvaluation {
  SurfaceEvaluation initial;  // initial/dsm.tif; 3D: MeshFromDsm(initial)
  SurfaceEvaluation result;   // DSM: DsmFromMesh(result) on the truth grid
  int grid_width = 0, grid_height = 0;
  double gsd_m = 0;
  size_t num_mask_cells = 0;
  std::vector<SigmaBin> error_by_sigma;  // empty: the result has no height_sigma (or no 3D)
};

// ErrorBySigma's bins for `result` (with height_sigma) against `truth`, over the vertices
// inside the crop box (x/y).
std::vector<SigmaBin> ErrorBySigma(const TriangleMesh& result, const TriangleMesh& truth,
                                   double xmin, double xmax, double ymin, double ymax);

// The files of a scene directory, by the layout contract.
struct ScenePaths {
  std::string truth_mesh, truth_dsm, roof_mask, initial_dsm;
  std::string images_dir;  // the views' GeoTIFFs with RPCs (for the seen facades)
};
ScenePaths SceneLayout(const std::string& scene_dir);

// The scene's images (ScenePaths::images_dir) give the 3D metrics' seen facades; a scene
// without them is evaluated without (Mesh3dMetrics::seen_facade empty).
// result_path: a mesh file (PLY/OBJ/..., scene CRS) or a result directory holding
// mesh.ply. Throws Error{kNotFound} naming a missing file.
SceneEvaluation EvaluateScene(const std::string& scene_dir, const std::string& result_path,
                              const SceneEvalOptions& options = {});
SceneEvaluation EvaluateScene(const std::string& scene_dir, const TriangleMesh& result,
                              const SceneEvalOptions& options = {});

// Evaluates one surface given both its DSM (on the truth grid) and its mesh; `views` (may
// be null): the scene's views, for the seen facades.
SurfaceEvaluation EvaluateSurface(const Dsm& dsm, const TriangleMesh& mesh, const Dsm& truth_dsm,
                                  const std::vector<uint8_t>& mask, const TriangleMesh* truth_mesh,
                                  const SceneEvalOptions& options,
                                  const ViewDirectionsFn* views = nullptr);

}  // namespace satmesh
