#pragma once
// Photo-consistency (paper 3.1): M = -Σ_x ZNCC(x) over windows W(x) of the reference
// view, statistics over valid pixels only, and its dense derivative ∂M/∂b by box filters:
//   ZNCC(x) = σ_ab / (σ_a σ_b)
//   ∂ZNCC(x)/∂b(y) = [ (a(y)-μ_a(x)) / (σ_a σ_b) - ZNCC(x) (b(y)-μ_b(x)) / σ_b² ] / N(x)
// summed over all windows containing y: four box filters, O(1) per pixel.
#include <cstdint>
#include <utility>
#include <vector>

namespace satmesh {

struct ZnccOptions {
  int window_radius = 2;            // window (2r+1)², r >= 1
  double min_valid_fraction = 0.5;  // windows with fewer valid pixels are skipped, (0, 1]
  double variance_floor = 1e-4;     // added to σ_a² and σ_b² (differentiably), > 0
  bool keep_windows = false;        // also fill ZnccField::windows (comparing surfaces)
};

struct ZnccField {
  std::vector<float> dM_db;  // ∂M/∂b per pixel (0 where invalid)
  double sum_zncc = 0;       // Σ ZNCC over the counted windows (M = -sum_zncc)
  long num_windows = 0;
  std::vector<float> windows;  // keep_windows: each pixel's window ZNCC, NaN where that
                               // window is not counted; else empty
};

// Scratch rows, reused across calls (the computation streams over rows: its working set
// is two rings of 2r+2 rows and a few rows of sums, so it stays in cache for any image
// size).
struct ZnccWorkspace {
  std::vector<float> centred_ring, coefficient_ring, columns, rows, zeros;
  std::vector<std::pair<int, int>> band_spans, slot_written;  // column ranges
};

// a, b: reference and warped images (width*height, row-major); valid: 1 where both exist.
// a and b are read everywhere, but their values where valid is 0 do not matter.
ZnccField ComputeZnccField(const std::vector<float>& a, const std::vector<float>& b,
                           const std::vector<uint8_t>& valid, int width, int height,
                           const ZnccOptions& options, ZnccWorkspace* workspace = nullptr);

// The same into *field, reusing its storage (every pixel of dM_db is written).
void ComputeZnccFieldInto(const std::vector<float>& a, const std::vector<float>& b,
                          const std::vector<uint8_t>& valid, int width, int height,
                          const ZnccOptions& options, ZnccField* field,
                          ZnccWorkspace* workspace = nullptr);

}  // namespace satmesh
