// Settings and enum names: the range check names the setting, the value and the range; names
// round-trip and an unknown one is named with the choices.
#include "core/base/setting.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>

#include "error_message.hpp"

namespace pbnbv {

enum class Fruit { kApple, kPear, kPlum };
template <>
struct EnumNames<Fruit> {
  static constexpr std::string_view what = "fruit";
  static constexpr std::array<NamedValue<Fruit>, 3> names{{{Fruit::kApple, "apple"}, {Fruit::kPear, "pear"}, {Fruit::kPlum, "plum"}}};
};

namespace {

using testing::error_message;

TEST(Setting, RangeIsInclusiveAndTheErrorNamesSettingValueAndRange) {
  constexpr Setting<int> views{"views", 10, 1, 1000, "", "at most this many views"};
  static_assert(views.allows(1) && views.allows(1000) && !views.allows(0) && !views.allows(1001));
  EXPECT_EQ(views.checked(1000), 1000);
  EXPECT_EQ(error_message([&] { views.checked(2000); }), "--views 2000 is outside its range [1, 1000]");
  constexpr Setting<double> resolution{"resolution", 0.03, 0.002, 0.2, "m", "voxel map resolution"};
  EXPECT_EQ(error_message([&] { resolution.checked(0.001); }), "--resolution 0.001 is outside its range [0.002, 0.2] m");
  constexpr Setting<int64_t> seed{"seed", 1, 0, int64_t{1} << 62, "", "seed"};
  EXPECT_EQ(seed.range_text(), "[0, 4611686018427387904]");
}

TEST(Setting, RenamedAndWithDefaultKeepTheRest) {
  constexpr Setting<double> voxel{"voxel", 0.002, 0.0, 0.05, "m", "cloud voxel"};
  constexpr Setting<double> model = voxel.renamed("model-voxel", "model voxel");
  static_assert(model.value == 0.002 && model.max == 0.05 && model.name == "model-voxel");
  constexpr Setting<double> other = voxel.with_default(0.01);
  static_assert(other.value == 0.01 && other.name == "voxel" && other.min == 0.0);
}

TEST(EnumNames, EveryNameRoundTripsAndAnUnknownOneIsNamedWithTheChoices) {
  for (const Fruit f : {Fruit::kApple, Fruit::kPear, Fruit::kPlum}) EXPECT_EQ(parse_name<Fruit>(name_of(f)), f);
  EXPECT_EQ(name_of(Fruit::kPear), "pear");
  EXPECT_EQ(choices_of<Fruit>(), "apple, pear or plum");
  EXPECT_EQ(names_of<Fruit>(), (std::vector<std::string>{"apple", "pear", "plum"}));
  EXPECT_EQ(error_message([] { parse_name<Fruit>("Pear"); }), "unknown fruit 'Pear' (expected apple, pear or plum)");
  EXPECT_THROW(parse_name<Fruit>(""), std::invalid_argument);
  EXPECT_THROW(name_of(static_cast<Fruit>(7)), std::logic_error);
}

}  // namespace
}  // namespace pbnbv
