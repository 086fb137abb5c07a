// The one table of picture options (lib/wobble/scene/render_options.h): what `wobble render`'s
// flags, a script's `render NAME=VALUE` and Python's Interpreter all parse.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "wobble/scene/render_options.h"

namespace wobble::scene {
namespace {

// The error for one option set to one value, or "" when it parses.
std::string ErrorOf(const std::string& name, const std::string& value) {
  try {
    ParseRenderOptions({{name, value}});
    return "";
  } catch (const RenderOptionError& e) {
    EXPECT_EQ(e.option, name);
    return e.what();
  }
}

TEST(RenderOptions, TheTableHasEachNameOnceWithHelpAndItsDefaultsParse) {
  std::set<std::string> names;
  for (const RenderOptionInfo& o : RenderOptionTable()) {
    EXPECT_TRUE(names.insert(o.name).second) << o.name << " twice";
    EXPECT_FALSE(o.help.empty()) << o.name;
    EXPECT_TRUE(IsRenderOption(o.name));
    // every default, typed back in, is the default setting
    if (!o.default_value.empty()) {
      EXPECT_EQ(ErrorOf(o.name, o.default_value), "") << o.name;
    }
  }
  EXPECT_FALSE(IsRenderOption("sizes"));
  EXPECT_EQ(RenderOptionNames().substr(0, 32), "azimuth, camera, chart-size, col");
  const RenderSettings defaults = ParseRenderOptions({});
  const RenderSettings typed = ParseRenderOptions({{"size", "640x480"}, {"fps", "30"}, {"elevation", "20"}});
  EXPECT_EQ(typed.width, defaults.width);
  EXPECT_EQ(typed.fps, defaults.fps);
  EXPECT_EQ(typed.elevation, defaults.elevation);
}

TEST(RenderOptions, ValuesParseAsTyped) {
  const RenderSettings s = ParseRenderOptions({{"size", "800x500"},
                                               {"fps", "24"},
                                               {"filmstrip", "0,0.5 1.5"},
                                               {"filmstrip-columns", "0"},
                                               {"trail", "0.5,0.5,1,0"},
                                               {"camera", "follow"},
                                               {"style", "clean"},
                                               {"exr-terrain", "on"},
                                               {"exr-motion", "blender"},
                                               {"exr-compression", "piz"},
                                               {"orbit", "-12.5"}});
  EXPECT_EQ(s.width, 800);
  EXPECT_EQ(s.height, 500);
  EXPECT_EQ(s.fps, 24.0);
  EXPECT_EQ(s.filmstrip_times, (std::vector<double>{0.0, 0.5, 1.5}));
  EXPECT_EQ(s.filmstrip_columns, 0);
  ASSERT_EQ(s.trail.size(), 2u);
  EXPECT_EQ(s.trail[1], Eigen::Vector2d(1.0, 0.0));
  EXPECT_TRUE(s.follow && s.clean && s.exr_terrain);
  EXPECT_TRUE(s.exr_blender_motion && !s.exr_nuke_motion);
  const RenderSettings both = ParseRenderOptions({{"exr-motion", "both"}}), plain = ParseRenderOptions({});
  EXPECT_TRUE(both.exr_blender_motion && both.exr_nuke_motion);
  EXPECT_TRUE(!plain.exr_blender_motion && plain.exr_nuke_motion) << "Nuke's forward.u/v by default";
  EXPECT_EQ(s.exr_compression, "piz");
  EXPECT_EQ(plain.exr_compression, "zip");
  EXPECT_EQ(s.orbit, -12.5);
  const RenderSettings cycle = ParseRenderOptions({{"filmstrip-cycle", "2 8"}});
  EXPECT_EQ(cycle.filmstrip_cycle, 2);
  EXPECT_EQ(cycle.filmstrip_panels, 8);
}

TEST(RenderOptions, BadValuesNameTheOptionAndWhatWasExpected) {
  EXPECT_NE(ErrorOf("size", "640").find("expected WIDTHxHEIGHT"), std::string::npos);
  EXPECT_NE(ErrorOf("size", "5x5").find("between 16 and 8192"), std::string::npos);
  EXPECT_NE(ErrorOf("fps", "0").find("must be > 0"), std::string::npos);
  EXPECT_NE(ErrorOf("fps", "abc").find("'abc' is not a finite number"), std::string::npos);
  EXPECT_NE(ErrorOf("shape-samples", "2.5").find("whole number from 1 to 10000"), std::string::npos);
  EXPECT_NE(ErrorOf("elevation", "90").find("between -90 and 90"), std::string::npos);
  EXPECT_NE(ErrorOf("camera", "orbit").find("expected whole or follow"), std::string::npos);
  EXPECT_NE(ErrorOf("style", "pretty").find("expected diagnostic or clean"), std::string::npos);
  EXPECT_NE(ErrorOf("exr-terrain", "maybe").find("expected on or off"), std::string::npos);
  EXPECT_NE(ErrorOf("exr-motion", "natron").find("expected nuke, blender or both"), std::string::npos);
  EXPECT_NE(ErrorOf("exr-compression", "rle").find("expected zip, zips, piz, dwaa or none, got 'rle'"), std::string::npos);
  EXPECT_NE(ErrorOf("trail", "0.5").find("pairs"), std::string::npos);
  EXPECT_NE(ErrorOf("filmstrip-cycle", "-1").find("cycle K >= 0"), std::string::npos);
  EXPECT_NE(ErrorOf("sizes", "1x1").find("unknown option (azimuth,"), std::string::npos);
  EXPECT_THROW(ParseRenderOptions({{"filmstrip", "1"}, {"filmstrip-cycle", "0"}}), RenderOptionError);
}

}  // namespace
}  // namespace wobble::scene
