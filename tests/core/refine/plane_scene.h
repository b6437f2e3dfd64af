#pragma once
// Tiny test scenes for the refinement: a textured tilted plane seen by a few views with
// affine RPCs (exact RFMs, so rendering and refinement share one camera model).
#include <utility>
#include <vector>

#include "core/refine/refine.h"

namespace satmesh::testing {

struct Plane {
  double a = 0.15, b = -0.1, c = 2.0;  // z = a x + b y + c (frame metres)
  double Z(double x, double y) const { return a * x + b * y + c; }
};

struct ViewSpec {
  double off_nadir_deg, azimuth_deg;
};

// Smooth, non-periodic texture of a surface point (unit range, features of ~1-6 m).
double PlaneTexture(double x, double y, double z);

// An affine RPC looking at the frame centre: col = cx + (x - z tanθ sinφ)/gsd, row likewise.
RpcModel AffineRpc(const LocalFrame& frame, const ViewSpec& view, double gsd_m, int size_px);
// The same with every cubic and denominator term of the RFM set (a few pixels of curvature
// over the image: a real RFM, not an affine one).
RpcModel CurvedRpc(const LocalFrame& frame, const ViewSpec& view, double gsd_m, int size_px);

// Renders the plane as seen by the RPC (3x3 supersampling) into a size x size image in
// "digital numbers" (texture * 1500 + 200).
ImageF RenderPlane(const RpcModel& rpc, const LocalFrame& frame, const Plane& plane, int size_px);

// Regular grid mesh of the plane on [-half, half]² with `spacing`, shifted by dz.
TriangleMesh PlaneMesh(const Plane& plane, double half_m, double spacing_m, double dz);

// A RefineInput of the plane seen by `views` (0.5 m GSD, size_px images).
RefineInput MakePlaneInput(const Plane& plane, const std::vector<ViewSpec>& views,
                           const TriangleMesh& initial, int size_px = 200, double gsd_m = 0.5);

std::vector<ViewSpec> DefaultViews();

// Helpers of the refinement's tests on the plane (refine_test.cc, level_start_test.cc).

// Mean and 95th percentile of |z - plane| over vertices in the interior |x|,|y| < half.
std::pair<double, double> PlaneError(const TriangleMesh& mesh, const Plane& plane, double half);

// The plane scenes' RPCs are exact and their initial surfaces are metres off on purpose:
// a bias estimated over such a surface would absorb part of the offset.
RefineOptions SmallOptions();

// The two pairs of DefaultViews within 13 degrees (10.4 and 10.9 degrees), without the
// 16-degree one the default selection adds: tests of the level logic and of the hit maps
// whose tolerances were set on that pair set, after one iteration per level.
// The plane's texture is noise-free: its near-Nyquist waves would read as noise and
// raise the ZNCC floor (noise_variance_factor), damping the one iteration per level.
RefineOptions SmallOptionsTwoPairs();

// The plane scene started `coarse_off_m` above the plane, whose initial surface for the
// finer levels (initial_for_edge, meshed at half their edge) is `finer_off_m` above it.
RefineInput PlaneWithInitialSurfaces(const Plane& plane, double coarse_off_m, double finer_off_m);

}  // namespace satmesh::testing
