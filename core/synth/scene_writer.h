#pragma once
// `satmesh synth`: a complete synthetic satellite scene directory (layout in
// ../shared/DESIGN.md and the synth issue): images with fitted RPCs, ground truth
// (mesh, DSM, roof mask, facade points), a degraded initial DSM, scene.json, job.json
// and a preview contact sheet.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/rpc/rpc_fit.h"
#include "core/synth/city.h"
#include "core/synth/initial_dsm.h"
#include "core/synth/pushbroom_camera.h"
#include "core/synth/render.h"
#include "core/synth/view_plan.h"

namespace satmesh::synth {

struct SynthOptions {
  std::string preset = "custom";       // name recorded in scene.json
  uint32_t seed = 1;                   // everything random derives from it
  std::string crs = "EPSG:32617";      // scene CRS (UTM 17N)
  Eigen::Vector2d center_lon_lat{-81.6557, 30.3322};  // AOI centre (Jacksonville)
  double base_height_m = -24;          // ellipsoidal height of the mean ground
  double gsd_m = 0.3;                  // grid cell and sensor pixel size, m, > 0
  CityOptions city;                    // aoi_size_m sets the AOI
  ViewPlanOptions views = ForAcquisition(Acquisition::kMultiDate);  // the collection drawn
  int margin_px = 16;                  // image margin around the AOI footprint, >= 0
  RenderOptions render;
  SensorOptions sensor;                // gain/offset are varied per image around these
  double gain_spread = 0.15;           // per-image gain in [1-s, 1+s], [0, 0.9]
  double rpc_bias_sigma_px = 1;        // per-image RPC bias (written, recorded), px, >= 0;
                                       // vendor RPCs of different passes disagree by ~1 px
  RpcFitOptions rpc_fit;
  DegradeOptions initial;              // initial DSM degradation
  double roof_edge_band_m = 1.0;       // roof mask: removed band at roof edges/steps, m, >= 0
  double facade_point_spacing_m = 0.5; // facade samples: one per spacing^2, m, > 0
  bool write_preview = true;           // preview.png contact sheet
  std::string Check() const;
};

// Scene sizes: small (~72 m; seconds, for tests), default (300 m), large (750 m,
// benchmarks), each with its default collection: small tristereo, default multidate, large
// jax (SetAcquisition). Throws Error{kInvalidArgument} for another name.
SynthOptions SynthPreset(const std::string& name, uint32_t seed = 1);

// Sets the collection with its defaults (ForAcquisition) and the RPC bias that goes with
// it: ~1 px per image for multi-date sets (vendor RPCs of different passes), none within
// one pass (stereo, tristereo: one attitude solution).
void SetAcquisition(SynthOptions* options, Acquisition acquisition);

struct SynthView {
  std::string image;                // relative to the scene directory
  double off_nadir_deg = 0, azimuth_deg = 0, zenith_deg = 0, gsd_m = 0;  // measured on the camera
  int pass = 0;                     // views of one pass share date and sun
  double track_heading_deg = 0;     // ground track, clockwise from N
  double acquisition_unix_s = 0;    // first line time, UTC (also in the image's IMD metadata)
  SunLight sun;                     // the sun of the view's date and time
  double rpc_fit_rms_px = 0, rpc_fit_max_px = 0, rpc_fit_max_half_step_px = 0;
  double ray_grid_error_px = 0;     // straight-line ray model vs exact camera
  Eigen::Vector2d bias_col_row_px{0, 0};
  double gain = 1, offset_dn = 0;
  int width = 0, height = 0;
  PushbroomCamera camera;
};

struct SynthResult {
  std::string out_dir;
  double aoi_xmin = 0, aoi_ymin = 0, aoi_xmax = 0, aoi_ymax = 0;  // scene CRS
  double height_min_m = 0, height_max_m = 0;                      // ellipsoidal
  std::vector<SynthView> views;
  int num_buildings = 0;
  size_t num_faces = 0, num_facade_points = 0, num_roof_cells = 0;
  double initial_roof_nmad_m = 0, initial_roof_p68_m = 0;  // initial DSM vs truth on the mask
  double initial_hole_fraction = 0;
  std::vector<std::pair<std::string, double>> timings_s;   // stage -> seconds, in order
  double total_s = 0;
};

// Writes the scene to out_dir (created). Throws Error on invalid options or I/O failure.
SynthResult GenerateScene(const std::string& out_dir, const SynthOptions& options,
                          const Progress& progress = {});

// The options' view plan (view_plan.h) at the scene centre. Deterministic in seed.
ViewPlan PlanViews(const SynthOptions& options, uint64_t seed);

}  // namespace satmesh::synth
