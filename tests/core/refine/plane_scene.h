#pragma once
// Tiny test scenes for the refinement: a textured tilted plane seen by a few views with
// affine RPCs (exact RFMs, so rendering and refinement share one camera model).
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

}  // namespace satmesh::testing
