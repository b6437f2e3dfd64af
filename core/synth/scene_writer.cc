#include "core/synth/scene_writer.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_files.h"
#include "core/synth/truth.h"

namespace satmesh::synth {
namespace {
class Stopwatch {
 public:
  double Lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return s;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace

std::string SynthOptions::Check() const {
  if (!(gsd_m > 0)) return "gsd_m must be > 0";
  if (margin_px < 0) return "margin_px must be >= 0";
  if (!(gain_spread >= 0 && gain_spread <= 0.9)) return "gain_spread must be in [0, 0.9]";
  if (!(rpc_bias_sigma_px >= 0)) return "rpc_bias_sigma_px must be >= 0";
  if (!(roof_edge_band_m >= 0)) return "roof_edge_band_m must be >= 0";
  if (!(facade_point_spacing_m > 0)) return "facade_point_spacing_m must be > 0";
  for (const std::string& s : {views.Check(), city.Check(), render.Check(), sensor.Check(), rpc_fit.Check(),
                               initial.Check()})
    if (!s.empty()) return s;
  return "";
}

SynthOptions SynthPreset(const std::string& name, uint32_t seed) {
  SynthOptions o;
  o.preset = name;
  o.seed = seed;
  if (name == "small") {
    o.city.aoi_size_m = 72;
    o.city.building_margin_m = 15;
    o.city.ground_margin_m = 70;
    o.city.street_pitch_m = 56;
    SetAcquisition(&o, Acquisition::kTriStereo);
  } else if (name == "default") {
    o.city.aoi_size_m = 300;
    SetAcquisition(&o, Acquisition::kMultiDate);
  } else if (name == "large") {
    o.city.aoi_size_m = 750;
    o.city.street_pitch_m = 90;
    SetAcquisition(&o, Acquisition::kJax);
  } else {
    ThrowError(ErrorCode::kInvalidArgument,
               "unknown preset '" + name + "' (expected small, default or large)");
  }
  return o;
}

void SetAcquisition(SynthOptions* o, Acquisition acquisition) {
  o->views = ForAcquisition(acquisition);
  const bool one_pass = acquisition == Acquisition::kStereo || acquisition == Acquisition::kTriStereo;
  o->rpc_bias_sigma_px = one_pass ? 0 : 1;
}

ViewPlan PlanViews(const SynthOptions& o, uint64_t seed) {
  return PlanViewSet(o.views, o.center_lon_lat, seed);
}

SynthResult GenerateScene(const std::string& out_dir, const SynthOptions& o, const Progress& progress) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "SynthOptions: " + why);
  namespace fs = std::filesystem;
  for (const char* sub : {"images", "truth", "initial"}) fs::create_directories(fs::path(out_dir) / sub);
  Stopwatch total, lap;
  SynthResult res;
  res.out_dir = out_dir;
  std::mt19937_64 gen(uint64_t(o.seed) * 7919 + 1);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> normal(0, 1);

  // 1. View plan (fails fast on impossible constraints), city around the AOI centre.
  const ViewPlan view_plan = PlanViews(o, o.seed);
  progress.Report(0.0, "city");
  const CrsTransform geo_to_scene(kWgs84Geographic3D, o.crs), scene_to_geo(o.crs, kWgs84Geographic3D);
  Eigen::Vector3d c = geo_to_scene.Apply(Eigen::Vector3d(o.center_lon_lat.x(), o.center_lon_lat.y(), 0));
  const Eigen::Vector3d origin(std::round(c.x() / 10) * 10, std::round(c.y() / 10) * 10, o.base_height_m);
  const CityModel city = BuildCity(o.city, o.seed, origin, o.crs);
  res.num_buildings = city.num_buildings;
  res.num_faces = city.mesh.num_faces();
  res.timings_s.emplace_back("city", lap.Lap());
  const RenderScene scene(city);
  res.timings_s.emplace_back("bvh", lap.Lap());

  // 2. Truth: DSM, roof mask, facade points, mesh.
  progress.Report(0.05, "truth");
  const double half = o.city.aoi_size_m / 2;
  res.aoi_xmin = origin.x() - half, res.aoi_xmax = origin.x() + half;
  res.aoi_ymin = origin.y() - half, res.aoi_ymax = origin.y() + half;
  Dsm grid;
  grid.width = grid.height = int(std::round(o.city.aoi_size_m / o.gsd_m));
  grid.geo_transform = {res.aoi_xmin, o.gsd_m, 0, res.aoi_ymax, 0, -o.gsd_m};
  grid.crs_wkt = CrsToWkt(o.crs);
  const Dsm truth = DsmFromMesh(city.mesh, grid);
  const std::vector<uint8_t> mask = RoofMask(scene, truth, o.roof_edge_band_m);
  for (uint8_t m : mask) res.num_roof_cells += m;
  res.height_min_m = 1e30, res.height_max_m = -1e30;
  for (float z : truth.z)
    if (std::isfinite(z)) res.height_min_m = std::min(res.height_min_m, double(z)),
                          res.height_max_m = std::max(res.height_max_m, double(z));
  std::vector<Eigen::Vector3d> facade_pts;
  std::vector<Eigen::Vector3f> facade_normals;
  SampleFacadePoints(city, {res.aoi_xmin, res.aoi_ymin}, {res.aoi_xmax, res.aoi_ymax},
                     o.facade_point_spacing_m, o.seed + 3, &facade_pts, &facade_normals);
  res.num_facade_points = facade_pts.size();
  const fs::path dir(out_dir);
  WriteMesh((dir / "truth/mesh.ply").string(), city.mesh);
  WriteDsm((dir / "truth/dsm.tif").string(), truth);
  WriteMaskTif((dir / "truth/roof_mask.tif").string(), truth, mask);
  WritePointsPly((dir / "truth/facade_points.ply").string(), facade_pts, facade_normals);
  res.timings_s.emplace_back("truth", lap.Lap());

  // 3. Initial DSM, degraded like a stereo result.
  const Dsm initial = DegradeDsm(truth, o.initial, o.seed + 5);
  WriteDsm((dir / "initial/dsm.tif").string(), initial);
  const Eigen::Vector2d stats = MaskedNmadP68(initial, truth, mask);
  res.initial_roof_nmad_m = stats.x(), res.initial_roof_p68_m = stats.y();
  size_t holes = 0;
  for (float z : initial.z) holes += !std::isfinite(z);
  res.initial_hole_fraction = double(holes) / initial.z.size();
  res.timings_s.emplace_back("initial", lap.Lap());

  // 4. Views: exact pushbroom camera, rendering under the view's sun, sensor, RPC fit,
  //    GeoTIFF with the acquisition metadata.
  const std::vector<PlannedView>& plan = view_plan.views;
  const int num_views = int(plan.size());
  std::vector<Eigen::Vector3d> cover;
  for (double x : {res.aoi_xmin, res.aoi_xmax})
    for (double y : {res.aoi_ymin, res.aoi_ymax})
      for (double h : {res.height_min_m - 2, res.height_max_m + 2}) {
        Eigen::Vector3d g = scene_to_geo.Apply(Eigen::Vector3d(x, y, 0));
        cover.emplace_back(g.x(), g.y(), h);
      }
  float zmin = 1e30f, zmax = -1e30f;
  for (const auto& v : city.mesh.vertices) zmin = std::min(zmin, v.z()), zmax = std::max(zmax, v.z());
  ViewRayGrid::Options ray_opts;
  ray_opts.h_low_m = origin.z() + zmin - 1, ray_opts.h_high_m = origin.z() + zmax + 2;
  Eigen::Vector3d fit_min(1e9, 1e9, res.height_min_m - 5), fit_max(-1e9, -1e9, res.height_max_m + 5);
  for (double x : {res.aoi_xmin - 10, res.aoi_xmax + 10})
    for (double y : {res.aoi_ymin - 10, res.aoi_ymax + 10}) {
      const Eigen::Vector3d g = scene_to_geo.Apply(Eigen::Vector3d(x, y, 0));
      fit_min.head<2>() = fit_min.head<2>().cwiseMin(g.head<2>());
      fit_max.head<2>() = fit_max.head<2>().cwiseMax(g.head<2>());
    }
  const Eigen::Vector3d centre_geo = scene_to_geo.Apply(Eigen::Vector3d(origin.x(), origin.y(), 0));
  const Eigen::Vector3d centre(centre_geo.x(), centre_geo.y(),
                               0.5 * (res.height_min_m + res.height_max_m));
  std::vector<ImageF> previews;
  std::vector<std::string> labels;
  double t_render = 0, t_fit = 0, t_write = 0;
  for (int v = 0; v < num_views; ++v) {
    progress.ThrowIfCancelled();
    progress.Report(0.1 + 0.85 * v / num_views, "view " + std::to_string(v));
    SynthView view;
    ViewGeometrySetup setup;
    setup.center_lon_lat_h = centre;
    setup.off_nadir_deg = plan[v].off_nadir_azimuth_deg.x();
    setup.azimuth_deg = plan[v].off_nadir_azimuth_deg.y();
    setup.track_heading_deg = plan[v].track_heading_deg;
    view.pass = plan[v].pass;
    view.track_heading_deg = plan[v].track_heading_deg;
    view.acquisition_unix_s = plan[v].acquisition_unix_s;
    view.sun.elevation_deg = plan[v].sun_elevation_deg;
    view.sun.azimuth_deg = plan[v].sun_azimuth_deg;
    setup.gsd_m = o.gsd_m;
    setup.margin_px = o.margin_px;
    view.camera = PushbroomCamera::LookingAt(setup, cover);
    view.width = view.camera.width(), view.height = view.camera.height();
    view.off_nadir_deg = view.camera.OffNadirDeg(centre);
    const Eigen::Vector2d az_zen = view.camera.SatelliteAzimuthZenithDeg(centre);
    view.azimuth_deg = az_zen.x(), view.zenith_deg = az_zen.y();
    view.gsd_m = view.camera.GroundGsdM(centre);
    const ViewRayGrid rays(view.camera, o.crs, origin, ray_opts);
    view.ray_grid_error_px = RayGridErrorPx(view.camera, rays, o.crs, origin,
                                            {res.height_min_m, centre.z(), res.height_max_m}, 7);
    const ImageF radiance = RenderView(scene, rays, view.width, view.height, view.sun, o.render, &progress);
    SensorOptions sensor = o.sensor;
    view.gain = sensor.gain *= 1 + o.gain_spread * (2 * u(gen) - 1);
    view.offset_dn = sensor.offset_dn *= 0.5 + u(gen);
    const ImageF dn = SimulateSensor(radiance, sensor, uint64_t(o.seed) * 1000 + v);
    t_render += lap.Lap();
    const RpcFitResult fit = FitRpc(
        [&](const Eigen::Vector3d& g) {
          auto px = view.camera.PixelFromGeo(g);
          return px ? *px : Eigen::Vector2d(NAN, NAN);
        },
        fit_min, fit_max, o.rpc_fit);
    view.rpc_fit_rms_px = fit.rms_px, view.rpc_fit_max_px = fit.max_px;
    view.rpc_fit_max_half_step_px = fit.max_px_half_step;
    RpcCoefficients coeffs = fit.model.coefficients();
    if (o.rpc_bias_sigma_px > 0) {
      view.bias_col_row_px = o.rpc_bias_sigma_px * Eigen::Vector2d(normal(gen), normal(gen));
      coeffs.samp_off += view.bias_col_row_px.x();
      coeffs.line_off += view.bias_col_row_px.y();
    }
    t_fit += lap.Lap();
    char name[32];
    std::snprintf(name, sizeof(name), "images/img_%02d.tif", v);
    view.image = name;
    AcquisitionInfo acquisition;
    acquisition.sun_elevation_deg = view.sun.elevation_deg;
    acquisition.sun_azimuth_deg = view.sun.azimuth_deg;
    acquisition.satellite_elevation_deg = 90 - view.zenith_deg;
    acquisition.satellite_azimuth_deg = view.azimuth_deg;
    acquisition.off_nadir_deg = view.off_nadir_deg;
    acquisition.acquisition_unix_s = view.acquisition_unix_s;
    WriteImageWithRpc((dir / view.image).string(), dn, RpcModel::FromCoefficients(coeffs), acquisition);
    previews.push_back(dn);
    labels.push_back(std::string(name + 7) + " on " + std::to_string(int(std::round(view.off_nadir_deg))) +
                     " az " + std::to_string(int(std::round(view.azimuth_deg))));
    t_write += lap.Lap();
    spdlog::info("synth: view {} {}x{} off-nadir {:.1f} az {:.1f} gsd {:.3f} sun el {:.1f} az {:.1f} "
                 "rpc fit {:.5f} px ray {:.5f} px",
                 v, view.width, view.height, view.off_nadir_deg, view.azimuth_deg, view.gsd_m,
                 view.sun.elevation_deg, view.sun.azimuth_deg, view.rpc_fit_max_half_step_px,
                 view.ray_grid_error_px);
    res.views.push_back(std::move(view));
  }
  res.timings_s.emplace_back("render", t_render);
  res.timings_s.emplace_back("rpc_fit", t_fit);
  res.timings_s.emplace_back("write_images", t_write);

  // 5. Descriptions and preview.
  WriteSceneJson((dir / "scene.json").string(), o, res);
  WriteJobJson((dir / "job.json").string(), o, res);
  if (o.write_preview) WritePreview((dir / "preview.png").string(), previews, labels, truth, initial);
  res.timings_s.emplace_back("json_preview", lap.Lap());
  res.total_s = total.Lap();
  progress.Report(1.0, "done");
  return res;
}

}  // namespace satmesh::synth
