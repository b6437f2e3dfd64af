#pragma once
// The tests' tiny synthetic city: the small preset's tri-stereo (seed 3) cut to an AOI of
// 36 m (2 x 2 tiles of 18 m) with ground around it, one view pixel per sample, no preview.
// Shared by the tiling, mesh-job, server and queue tests so their scenes are the same.
#include "core/synth/scene_writer.h"

namespace satmesh::testing {

inline synth::SynthOptions TinySceneOptions(double aoi_size_m = 36) {
  synth::SynthOptions o = synth::SynthPreset("small", /*seed=*/3);
  o.city.aoi_size_m = aoi_size_m;
  o.city.ground_margin_m = 45;
  o.city.building_margin_m = 5;
  o.city.street_pitch_m = 40;
  o.render.supersample = 1;
  o.write_preview = false;
  return o;
}

}  // namespace satmesh::testing
