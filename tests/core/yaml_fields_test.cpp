// The YAML readers the board and calibration files share (core): ranges and optional keys,
// with errors that name the file and the key.
#include <gtest/gtest.h>

#include <string>

#include "epipole/core/yaml_fields.hpp"
#include "error_of.hpp"

namespace epipole {
namespace {

using test::error_of;

TEST(YamlFields, ARangedValueOutsideItsRangeNamesTheFileTheKeyAndTheRange) {
  const yaml::Fields f("board.yaml");
  const YAML::Node map = f.parse("rate: 0.5\ncount: 7\nbig: 12\nfar: 1.5\n");
  EXPECT_EQ(f.number_in(map["rate"], "sim.rate", 0, 1), 0.5);
  EXPECT_EQ(f.integer_in(map["count"], "sim.count", 1, 7), 7);
  EXPECT_EQ(error_of([&] { f.integer_in(map["big"], "sim.big", 1, 10); }),
            "board.yaml: sim.big: 12 is outside 1..10");
  EXPECT_EQ(error_of([&] { f.number_in(map["far"], "sim.far", 0, 1); }),
            "board.yaml: sim.far: 1.5 is outside 0..1");
  EXPECT_NE(error_of([&] { f.integer_in(map["far"], "sim.far", 0, 10); }).find("not an integer"),
            std::string::npos);
}

TEST(YamlFields, IfPresentReadsAKeyThatIsThereAndNotOneThatIsAbsentOrNull) {
  const yaml::Fields f("board.yaml");
  const YAML::Node map = f.parse("seed: 3\nnothing: ~\n");
  std::string seen;
  for (const char* key : {"seed", "nothing", "absent"}) {
    f.if_present(map, "sim", key, [&](const YAML::Node& n, const std::string& k) {
      seen += k + "=" + std::to_string(f.integer(n, k));
    });
  }
  EXPECT_EQ(seen, "sim.seed=3");
}

}  // namespace
}  // namespace epipole
