#include "io/json.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace lambert {
namespace {

TEST(JsonText, NonFiniteNumbersBecomeNullAndKeysKeepTheirOrder) {
  const Json j = {{"b", std::numeric_limits<double>::quiet_NaN()},
                  {"a", std::numeric_limits<double>::infinity()},
                  {"c", 0.1}};
  const nlohmann::json back = nlohmann::json::parse(json_text(j));
  EXPECT_TRUE(back.at("b").is_null());
  EXPECT_TRUE(back.at("a").is_null());
  // Doubles round-trip exactly (shortest representation that reads back to the same bits).
  EXPECT_EQ(back.at("c").get<double>(), 0.1);
  EXPECT_LT(json_text(j).find("\"b\""), json_text(j).find("\"a\""));
}

TEST(JsonText, InvalidUtf8IsReplacedNotThrown) {
  const Json j = {{"scene", std::string("caf\xe9.obj")}};
  Json back;
  EXPECT_NO_THROW(back = nlohmann::json::parse(json_text(j)));
  EXPECT_TRUE(back.at("scene").is_string());
}

}  // namespace
}  // namespace lambert
