#pragma once
// The warp of one pair-direction (i -> j) (paper 3.2.3): view i's hit points X are
// projected into j through j's projection lattice, kept where j's own ray through that
// pixel hits the same surface (scale-free visibility: the same face, or a point within
// the tolerance), and j is sampled bilinearly there. Per pixel of i: b = I_j(Π_j(X)),
// valid, and db_dn = ∂b per unit move of the hit face along its normal
// (∇I_j · DΠ_j · ray_i / (ray_i · n)).
// Two implementations that agree to float rounding: the scalar reference, and an
// AVX2/FMA one (8 pixels at once, lanes loaded without gathers: lattice_avx2.h) used
// where the CPU has it.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/refine/view_level.h"

namespace satmesh {

struct WarpContext {
  const ViewLevel* vi;
  const ViewLevel* vj;
  const std::vector<Eigen::Vector3f>* face_normals;  // for ray cosines when cos_i is null
  const float* cos_i;  // vi's hit_map.ray_cos, or null (then from the face normals)
  float tol2;          // squared visibility tolerance, m²
  float min_cos;       // pixels with ray · n > -min_cos are skipped (grazing, back-facing)
  float* b;            // outputs, one per pixel of i (b and db_dn meaningful where valid)
  float* db_dn;
  uint8_t* valid;      // must be zero on entry; set to 1 where the pixel is used
};

// Warps one row of view i. vectorized: use the AVX2 path where the CPU supports it.
void WarpRow(const WarpContext& c, int row, bool vectorized);

// True when WarpRow(..., vectorized = true) runs the AVX2 path on this CPU.
bool WarpHasAvx2();

}  // namespace satmesh
