#include "core/common/stats.h"

#include <algorithm>
#include <cmath>

namespace satmesh {

double Quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const double pos = std::clamp(q, 0.0, 1.0) * double(values.size() - 1);
  const size_t lo = size_t(std::floor(pos));
  std::nth_element(values.begin(), values.begin() + lo, values.end());
  const double v_lo = values[lo];
  if (lo + 1 >= values.size()) return v_lo;
  const double v_hi = *std::min_element(values.begin() + lo + 1, values.end());
  return v_lo + (pos - double(lo)) * (v_hi - v_lo);
}

double Quantile(std::vector<double>&& values, double q) { return Quantile(values, q); }

}  // namespace satmesh
