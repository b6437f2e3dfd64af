#pragma once
// Small order statistics shared by the eval and tiling modules.
#include <vector>

namespace satmesh {

// Quantile q in [0, 1] with linear interpolation between order statistics (numpy's
// default): position q * (n - 1). Reorders `values`. Empty input gives 0.
double Quantile(std::vector<double>& values, double q);
double Quantile(std::vector<double>&& values, double q);

}  // namespace satmesh
