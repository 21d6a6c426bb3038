// The heat command's surface conditions file (io/heat_surfaces.*): what it accepts, and the
// one-line errors naming the file for what it refuses.

#include "io/heat_surfaces.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace lambert {
namespace {

// The message of the SceneError that parsing `text` as file "walls.json" throws ("" if none).
std::string conditions_error(const std::string& text) {
  try {
    parse_surface_conditions(text, "walls.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(HeatSurfaces, ParsesTemperaturesAndFluxes) {
  const SurfaceConditions c = parse_surface_conditions(
      R"({"floor": {"emissivity": 0.9, "temperature": 300},
          "*": {"emissivity": 0.5, "heat_flux": -20}})",
      "walls.json");
  ASSERT_EQ(c.by_name.size(), 2u);
  EXPECT_TRUE(c.by_name.at("floor").known_temperature);
  EXPECT_EQ(c.by_name.at("floor").value, 300.0);
  EXPECT_FALSE(c.by_name.at("*").known_temperature);
  EXPECT_EQ(c.by_name.at("*").emissivity, 0.5);
}

TEST(HeatSurfaces, AKeyGivenTwiceIsRefusedNotTheLastTaken) {
  // Issue 33, item 8: nlohmann keeps the last of two equal keys silently.
  const std::string surface = conditions_error(R"({"floor": {"emissivity": 0.9, "temperature": 300},
                                           "floor": {"emissivity": 0.1, "temperature": 900}})");
  EXPECT_NE(surface.find("walls.json: key \"floor\" given twice"), std::string::npos) << surface;
  const std::string inner =
      conditions_error(R"({"floor": {"emissivity": 0.9, "temperature": 300, "temperature": 10}})");
  EXPECT_NE(inner.find("walls.json: key \"temperature\" given twice"), std::string::npos) << inner;
  // The same key in two different objects is fine.
  EXPECT_EQ(conditions_error(R"({"a": {"emissivity": 1, "temperature": 1},
                         "b": {"emissivity": 1, "temperature": 1}})"),
            "");
}

TEST(HeatSurfaces, ANumberBeyondDoubleNamesTheFile) {
  // Issue 33, item 8: 1e400 threw nlohmann's out_of_range, whose message names no file.
  const std::string e = conditions_error(R"({"floor": {"emissivity": 0.9, "temperature": 1e400}})");
  EXPECT_EQ(e.rfind("walls.json: not valid JSON", 0), 0u) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
}

}  // namespace
}  // namespace lambert
