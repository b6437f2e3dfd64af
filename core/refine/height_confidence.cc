#include "core/refine/height_confidence.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace satmesh {

// Height information of a pair: (B/H)², B/H = 2 tan(angle / 2) (the inverse variance of a
// height from one pixel of disparity, in units of GSD⁻²).
double PairHeightInformation(double angle_deg) {
  const double b_h = 2 * std::tan(0.5 * angle_deg * M_PI / 180);
  return b_h * b_h;
}

// How much the pairs that see a vertex constrain its height, in [min_height_confidence, 1]:
// their height information relative to one pair at the optimal angle. The thin-plate
// weight is divided by it, so that where the images constrain the surface weakly (one
// narrow pair, occlusion), the surface stays smooth and near where it started rather
// than following matching noise.
// `relative_information` is already divided by one optimal pair's information
// (MeanRelativePairInformation), so the per-vertex call in the update loop is a clamp.
double HeightConfidence(double relative_information, const RefineOptions& options) {
  if (!(options.min_height_confidence < 1)) return 1.0;
  return std::clamp(relative_information, options.min_height_confidence, 1.0);
}

// How well the images determine each vertex's position along the surface normal, in
// [min_height_confidence, 1]: `information` is the Fisher information Σ w_k² (∂b/∂n)² of
// the pixels that see the vertex (all pair-directions of an iteration; ∂b/∂n the warped
// intensity's change per metre along the normal, which holds both the texture and the
// pair's height sensitivity), so the vertex's height is known to σ = noise / sqrt(I).
// Confidence 1 where σ is at most height_sigma_gsd level GSDs, else (σ_target / σ)²: the
// thin-plate weight is divided by it, so where the images constrain a vertex weakly (no
// texture, shadow, one narrow pair, occlusion) the surface stays smooth and near where it
// started instead of following matching noise. Also fills the level's quantiles of σ.
std::vector<float> HeightSigmaFromInformation(const std::vector<double>& information,
                                              double noise_variance) {
  const double variance = std::max(noise_variance, 1e-12);
  std::vector<float> sigma(information.size());
  for (size_t v = 0; v < information.size(); ++v)
    sigma[v] = information[v] > 0 ? float(std::sqrt(variance / information[v]))
                                  : std::numeric_limits<float>::infinity();
  return sigma;
}

std::vector<float> HeightConfidenceFromInformation(const std::vector<double>& information,
                                                   double noise_variance, double gsd_m,
                                                   const RefineOptions& options,
                                                   LevelStats* stats) {
  const double target = options.height_sigma_gsd * gsd_m;
  const double scale = target * target / std::max(noise_variance, 1e-12);
  std::vector<float> confidence(information.size());
  for (size_t v = 0; v < information.size(); ++v)
    confidence[v] = float(std::clamp(information[v] * scale, options.min_height_confidence, 1.0));
  std::vector<float> sigma_gsd;  // of the vertices some pixel saw
  for (const float sigma : HeightSigmaFromInformation(information, noise_variance))
    if (std::isfinite(sigma)) sigma_gsd.push_back(float(sigma / gsd_m));
  if (!sigma_gsd.empty()) {
    auto quantile = [&](double q) {
      auto it = sigma_gsd.begin() + long(q * double(sigma_gsd.size() - 1));
      std::nth_element(sigma_gsd.begin(), it, sigma_gsd.end());
      return double(*it);
    };
    stats->height_sigma_gsd_q = {quantile(0.1), quantile(0.5), quantile(0.9)};
    spdlog::info("level {}: vertices' height sigma from the images (10/50/90%): {:.3f} / {:.3f} "
                 "/ {:.3f} GSD (confidence 1 at {:.3f})",
                 stats->level, stats->height_sigma_gsd_q[0], stats->height_sigma_gsd_q[1],
                 stats->height_sigma_gsd_q[2], options.height_sigma_gsd);
  }
  return confidence;
}

std::vector<float> InitialPriorWeights(const std::vector<double>& information,
                                       double noise_variance, double prior_sigma_m) {
  const double variance = std::max(noise_variance, 1e-12);
  const double prior_variance = prior_sigma_m * prior_sigma_m;
  std::vector<float> weight(information.size());
  for (size_t v = 0; v < information.size(); ++v) {
    // variance / (variance + prior · information) is sigma_img² / (sigma_img² + prior²)
    // without dividing by an information of 0.
    weight[v] = float(variance / (variance + prior_variance * std::max(information[v], 0.0)));
  }
  return weight;
}

// Mean over the pairs of PairHeightInformation, relative to one pair at the optimal angle.
double MeanRelativePairInformation(const std::vector<StereoPair>& pairs,
                                   const RefineOptions& options) {
  double information = 0;
  for (const StereoPair& p : pairs) information += PairHeightInformation(p.angle_deg);
  information /= double(std::max<size_t>(1, pairs.size()));
  return information / PairHeightInformation(options.pairs.optimal_angle_deg);
}

}  // namespace satmesh
