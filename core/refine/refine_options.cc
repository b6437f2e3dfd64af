#include "core/refine/refine_options.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace satmesh {
namespace {
std::string Num(double v) { return std::to_string(v); }
}  // namespace

std::string PairOptions::Check() const {
  if (!(min_angle_deg > 0 && min_angle_deg < 90))
    return "pairs.min_angle_deg must be in (0, 90), got " + Num(min_angle_deg);
  if (!(max_angle_deg > min_angle_deg && max_angle_deg < 90))
    return "pairs.max_angle_deg must be in (min_angle_deg, 90), got " + Num(max_angle_deg);
  if (!(optimal_angle_deg >= min_angle_deg && optimal_angle_deg <= max_angle_deg))
    return "pairs.optimal_angle_deg must be in [min_angle_deg, max_angle_deg], got " +
           Num(optimal_angle_deg);
  if (!(min_overlap >= 0 && min_overlap <= 1))
    return "pairs.min_overlap must be in [0, 1], got " + Num(min_overlap);
  if (partners_per_view < 1)
    return "pairs.partners_per_view must be >= 1, got " + Num(partners_per_view);
  if (max_pairs_per_image < 1)
    return "pairs.max_pairs_per_image must be >= 1, got " + Num(max_pairs_per_image);
  if (max_pairs < 0) return "pairs.max_pairs must be >= 0, got " + Num(max_pairs);
  if (!(min_contrast >= 0)) return "pairs.min_contrast must be >= 0, got " + Num(min_contrast);
  return "";
}

std::string RefineOptions::Check() const {
  if (levels < -1 || levels > 6) return "levels must be in [0, 6] or -1 (auto), got " + Num(levels);
  if (!(max_coarse_edge_m > 0)) return "max_coarse_edge_m must be > 0, got " + Num(max_coarse_edge_m);
  if (iterations_per_level < 0 || iterations_per_level > 1000)
    return "iterations_per_level must be in [0, 1000], got " + Num(iterations_per_level);
  if (!(alpha >= 0)) return "alpha must be >= 0, got " + Num(alpha);
  if (!(beta >= 0)) return "beta must be >= 0, got " + Num(beta);
  if (!(step > 0)) return "step must be > 0, got " + Num(step);
  if (!(max_step_gsd > 0)) return "max_step_gsd must be > 0, got " + Num(max_step_gsd);
  if (zncc_window_radius < 1 || zncc_window_radius > 7)
    return "zncc_window_radius must be in [1, 7], got " + Num(zncc_window_radius);
  if (!(min_window_valid > 0 && min_window_valid <= 1))
    return "min_window_valid must be in (0, 1], got " + Num(min_window_valid);
  if (!(variance_floor > 0)) return "variance_floor must be > 0, got " + Num(variance_floor);
  if (!(noise_variance_factor >= 0))
    return "noise_variance_factor must be >= 0, got " + Num(noise_variance_factor);
  if (!(visibility_tolerance_gsd > 0))
    return "visibility_tolerance_gsd must be > 0, got " + Num(visibility_tolerance_gsd);
  if (!(min_ray_cos >= 0 && min_ray_cos < 1))
    return "min_ray_cos must be in [0, 1), got " + Num(min_ray_cos);
  if (virtual_camera_grid_px < 1)
    return "virtual_camera_grid_px must be >= 1, got " + Num(virtual_camera_grid_px);
  if (hit_maps_every < 1 || hit_maps_every > 20)
    return "hit_maps_every must be in [1, 20], got " + Num(hit_maps_every);
  if (!(height_sigma_gsd >= 0))
    return "height_sigma_gsd must be >= 0, got " + Num(height_sigma_gsd);
  if (!(min_height_confidence > 0 && min_height_confidence <= 1))
    return "min_height_confidence must be in (0, 1], got " + Num(min_height_confidence);
  if (!(flat_tolerance_gsd >= 0))
    return "flat_tolerance_gsd must be >= 0, got " + Num(flat_tolerance_gsd);
  if (!(coarse_edge_px > 0)) return "coarse_edge_px must be > 0, got " + Num(coarse_edge_px);
  return pairs.Check();
}

int ResolveLevels(const RefineOptions& options, double gsd_m, double initial_cell_m) {
  if (options.levels >= 0) return options.levels;
  const double max_edge = std::max(options.max_coarse_edge_m, initial_cell_m);
  int level = 0;
  while (level < 3 && options.coarse_edge_px * gsd_m * std::ldexp(1.0, level + 1) <= max_edge + 1e-9)
    ++level;
  return level;
}

}  // namespace satmesh
