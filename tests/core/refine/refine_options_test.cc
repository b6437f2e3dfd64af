// The refinement options' table (RefineOptionTable): one declaration per option, from
// which Check() and the wire format are made.
#include "core/refine/refine_options.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace satmesh {
namespace {

std::set<std::string> WireNames() {
  std::set<std::string> names;
  for (const RefineOptionInfo& option : RefineOptionTable()) names.insert(std::string(option.name));
  return names;
}

// Values of the option just outside its range (none for a boolean or an unbounded side).
std::vector<double> OutOfRange(const RefineOptionInfo& option) {
  std::vector<double> values;
  const OptionRange& r = option.range;
  if (r.min) values.push_back(r.min_exclusive ? *r.min : *r.min - 1);
  if (r.max) values.push_back(r.max_exclusive ? *r.max : *r.max + 1);
  return values;
}

OptionValue As(const RefineOptionInfo& option, double v) {
  if (option.type() == OptionType::kInt) return int(v);
  return v;
}

// Every snake_case word of a message is a wire name: no struct path ("pairs.min_angle_deg").
void ExpectOnlyWireNames(const std::string& message) {
  const std::set<std::string> names = WireNames();
  EXPECT_EQ(message.find("pairs."), std::string::npos) << message;
  const std::regex word("[a-z0-9]+(_[a-z0-9]+)+");
  for (auto it = std::sregex_iterator(message.begin(), message.end(), word);
       it != std::sregex_iterator(); ++it)
    EXPECT_TRUE(names.count(it->str())) << "'" << it->str() << "' in: " << message;
}

TEST(RefineOptionTable, NamesAreUniqueAndEachOptionSetsItsOwnField) {
  EXPECT_EQ(WireNames().size(), RefineOptionTable().size());
  for (const RefineOptionInfo& option : RefineOptionTable()) {
    EXPECT_FALSE(option.help.empty()) << option.name;
    EXPECT_EQ(option.help.find('\n'), std::string_view::npos) << option.name;
    RefineOptions changed;
    const OptionValue before = option.Get(changed);
    const OptionValue after =
        std::holds_alternative<bool>(before)  ? OptionValue(!std::get<bool>(before))
        : std::holds_alternative<int>(before) ? OptionValue(std::get<int>(before) + 7)
                                              : OptionValue(std::get<double>(before) + 7.5);
    option.Set(&changed, after);
    EXPECT_EQ(option.Get(changed), after) << option.name;
    for (const RefineOptionInfo& other : RefineOptionTable())
      if (&other != &option) {
        EXPECT_EQ(other.Get(changed), other.Default()) << option.name << " set " << other.name;
      }
  }
}

TEST(RefineOptionTable, DefaultsAreTheStructsAndInRange) {
  const RefineOptions defaults;
  EXPECT_EQ(FindRefineOption("levels")->Default(), OptionValue(defaults.levels));
  EXPECT_EQ(FindRefineOption("min_pair_angle_deg")->Default(),
            OptionValue(defaults.pairs.min_angle_deg));
  EXPECT_EQ(FindRefineOption("max_pairs")->type(), OptionType::kInt);
  EXPECT_EQ(FindRefineOption("hold_unseen")->type(), OptionType::kBool);
  EXPECT_EQ(FindRefineOption("pairs.min_angle_deg"), nullptr);
  for (const RefineOptionInfo& option : RefineOptionTable())
    EXPECT_EQ(option.CheckValue(defaults), "") << option.name;
}

TEST(RefineOptionTable, RangesAreWritten) {
  EXPECT_EQ(FindRefineOption("hit_maps_every")->RangeText(), "[1, 20]");
  EXPECT_EQ(FindRefineOption("min_window_valid")->RangeText(), "(0, 1]");
  EXPECT_EQ(FindRefineOption("min_ray_cos")->RangeText(), "[0, 1)");
  EXPECT_EQ(FindRefineOption("step")->RangeText(), "> 0");
  EXPECT_EQ(FindRefineOption("alpha")->RangeText(), ">= 0");
  EXPECT_EQ(FindRefineOption("estimate_bias")->RangeText(), "");
}

TEST(RefineOptions, EveryOutOfRangeValueIsNamedByItsWireNameWithTheRange) {
  for (const RefineOptionInfo& option : RefineOptionTable()) {
    for (const double v : OutOfRange(option)) {
      RefineOptions o;
      option.Set(&o, As(option, v));
      const std::string message = o.Check();
      EXPECT_EQ(message.rfind(std::string(option.name) + " must be ", 0), 0u) << message;
      EXPECT_NE(message.find(option.RangeText()), std::string::npos) << message;
      ExpectOnlyWireNames(message);
      if (option.is_nested()) {
        EXPECT_EQ(o.pairs.Check(), message);
      }
    }
  }
}

TEST(RefineOptions, CrossFieldChecksUseWireNames) {
  RefineOptions o;
  o.pairs.max_angle_deg = 1;  // under min_pair_angle_deg 2; in (0, 90)
  EXPECT_EQ(o.Check(), "max_pair_angle_deg must be > min_pair_angle_deg (2), got 1");
  ExpectOnlyWireNames(o.Check());
  o = RefineOptions();
  o.pairs.optimal_angle_deg = 70;
  EXPECT_EQ(o.Check(),
            "optimal_pair_angle_deg must be in [min_pair_angle_deg, max_pair_angle_deg] = [2, 60], "
            "got 70");
  ExpectOnlyWireNames(o.Check());
  EXPECT_EQ(o.pairs.Check(), o.Check());
}

TEST(RefineOptions, ZnccWindowIsLargerForOnePairUnlessSet) {
  RefineOptions o;
  EXPECT_EQ(ResolveZnccWindowRadius(o, 1), 3);  // one pair: 7x7
  EXPECT_EQ(ResolveZnccWindowRadius(o, 2), 2);
  EXPECT_EQ(ResolveZnccWindowRadius(o, 13), 2);
  EXPECT_EQ(ResolveZnccWindowRadius(o, 0), 2);  // a measurement over given pairs: 5x5
  o.zncc_window_radius = 2;
  EXPECT_EQ(ResolveZnccWindowRadius(o, 1), 2);
  o.zncc_window_radius = 5;
  EXPECT_EQ(ResolveZnccWindowRadius(o, 4), 5);
  o.zncc_window_radius = 0;  // in the table's [-1, 7] but neither -1 nor a radius
  EXPECT_EQ(o.Check(), "zncc_window_radius must be -1 (from the pairs) or in [1, 7], got 0");
  ExpectOnlyWireNames(o.Check());
}

// One pair's walls move as patches (gradient_patch.h); more pairs move their walls themselves.
TEST(RefineOptions, WallPatchRingsFromThePairs) {
  RefineOptions o;
  EXPECT_EQ(o.wall_patch_rings, -1);
  EXPECT_EQ(ResolveWallPatchRings(o, 1), 4);
  EXPECT_EQ(ResolveWallPatchRings(o, 2), 0);
  EXPECT_EQ(ResolveWallPatchRings(o, 39), 0);
  o.wall_patch_rings = 2;
  EXPECT_EQ(ResolveWallPatchRings(o, 1), 2);
  EXPECT_EQ(ResolveWallPatchRings(o, 3), 2);  // the user's choice with any pairs
  o.wall_patch_rings = 0;
  EXPECT_EQ(ResolveWallPatchRings(o, 1), 0);
  o.wall_patch_rings = 9;
  EXPECT_EQ(o.Check().rfind("wall_patch_rings must be", 0), 0u) << o.Check();
}

// Roof patches are on with any pairs (they pool only where the images constrain weakly).
TEST(RefineOptions, RoofPatchRingsFourByDefaultZeroOff) {
  RefineOptions o;
  EXPECT_EQ(o.roof_patch_rings, 4);
  EXPECT_EQ(o.Check(), "");
  o.roof_patch_rings = 0;
  EXPECT_EQ(o.Check(), "");
  for (int bad : {-1, 9}) {
    o.roof_patch_rings = bad;
    EXPECT_EQ(o.Check().rfind("roof_patch_rings must be", 0), 0u) << o.Check();
  }
}

// Walls hang plumb from a DSM start; a mesh start's walls are the user's model.
TEST(RefineOptions, PlumbWallsForADsmStartNotAMeshStartByDefault) {
  RefineOptions o;
  EXPECT_EQ(o.plumb_walls, -1);
  EXPECT_TRUE(o.HangsWallsPlumb(/*initial_is_mesh=*/false));
  EXPECT_FALSE(o.HangsWallsPlumb(/*initial_is_mesh=*/true));
  o.plumb_walls = 0;
  EXPECT_FALSE(o.HangsWallsPlumb(false));
  o.plumb_walls = 1;
  EXPECT_TRUE(o.HangsWallsPlumb(true));
  EXPECT_EQ(o.Check(), "");
  for (int bad : {-2, 2}) {
    o.plumb_walls = bad;
    EXPECT_EQ(o.Check().rfind("plumb_walls must be", 0), 0u) << o.Check();
  }
}

// A DSM the user trusts (trusted_initial) resolves the start-dependent -1 defaults as a mesh
// start does, but the coarse levels' carry (a DSM start's levels); explicit values win.
TEST(RefineOptions, ATrustedDsmResolvesAsAMeshStart) {
  RefineOptions o;
  EXPECT_EQ(o.trusted_initial, 0);
  EXPECT_FALSE(o.TrustsInitial(/*initial_is_mesh=*/false));
  EXPECT_EQ(o.KeepInitialSigmas(/*initial_is_mesh=*/false), 0.0);
  EXPECT_EQ(o.KeepInitialSigmas(/*initial_is_mesh=*/true), 2.0);
  EXPECT_TRUE(o.TrustsInitial(/*initial_is_mesh=*/true));
  o.trusted_initial = 1;
  EXPECT_TRUE(o.TrustsInitial(false));
  EXPECT_EQ(o.KeepInitialSigmas(false), 2.0);
  EXPECT_FALSE(o.HangsWallsPlumb(false));
  EXPECT_EQ(o.OccludingEdgeBiasPx(false), 0.0);
  EXPECT_TRUE(o.RegistersToInitial(false));
  EXPECT_TRUE(o.SmoothsOffsets(false));
  EXPECT_TRUE(o.MatchesSunlitOnly(false));
  EXPECT_FALSE(o.CarriesCoarseLevels(false));
  o.plumb_walls = 1;
  o.occluding_edge_bias_px = 0.5;
  o.register_to_initial = 0;
  EXPECT_TRUE(o.HangsWallsPlumb(false));
  EXPECT_EQ(o.OccludingEdgeBiasPx(false), 0.5);
  EXPECT_FALSE(o.RegistersToInitial(false));
  EXPECT_EQ(o.Check(), "");
  for (int bad : {-1, 2}) {
    o.trusted_initial = bad;
    EXPECT_EQ(o.Check().rfind("trusted_initial must be", 0), 0u) << o.Check();
  }
}

TEST(RefineOptions, NanIsOutOfRange) {
  RefineOptions o;
  o.alpha = std::nan("");
  EXPECT_EQ(o.Check().rfind("alpha must be >= 0", 0), 0u) << o.Check();
}

}  // namespace
}  // namespace satmesh
