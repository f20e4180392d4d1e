#pragma once
// A setting defined once: its option name, default value, allowed range, unit and meaning. Each
// layer declares the settings it owns (e.g. core/planning/planning_options.hpp: N = 800
// candidates, T_max = 10) as `inline constexpr` values; structs take their member defaults from
// them, the command lines of `pbnbv` and the services declare their options from them (with
// their help text and range), and values read from files are checked against the same range.
#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

#include "core/base/enum_names.hpp"

namespace pbnbv {

template <typename T>
struct Setting {
  static_assert(std::is_arithmetic_v<T>, "a Setting holds a number; an enum is a ChoiceSetting");
  std::string_view name;  // the option's name, without "--"
  T value;                // the default
  T min;                  // allowed range, both ends included
  T max;
  std::string_view unit;  // "m", "deg", "px", "s", or "" for a count or a ratio
  std::string_view help;  // what it means, one line

  // True when v lies in [min, max].
  constexpr bool allows(T v) const { return v >= min && v <= max; }

  // v itself when allowed; else throws std::invalid_argument naming the setting, v and the range:
  // "--views 2000 is outside its range [1, 1000]".
  T checked(T v) const {
    if (!allows(v)) throw std::invalid_argument(fmt::format("--{} {} is outside its range {}", name, v, range_text()));
    return v;
  }

  // "[1, 1000]" or "[0.002, 0.2] m".
  std::string range_text() const {
    return fmt::format("[{}, {}]{}{}", min, max, unit.empty() ? "" : " ", unit);
  }

  // The same setting under another option name and meaning (same default, range and unit), for
  // a program that calls it differently (pbnbv-registration --model-voxel is the cloud voxel).
  constexpr Setting renamed(std::string_view new_name, std::string_view new_help) const {
    Setting s = *this;
    s.name = new_name;
    s.help = new_help;
    return s;
  }

  // The same setting with another default, for a program that runs on its own (pbnbv-twin's
  // --speed is real time unless the launcher asks for more).
  constexpr Setting with_default(T new_value) const {
    Setting s = *this;
    s.value = new_value;
    return s;
  }
};

// A setting whose value is one of an enum's named values (EnumNames<E>).
template <typename E>
struct ChoiceSetting {
  std::string_view name;  // the option's name, without "--"
  E value;                // the default
  std::string_view help;

  constexpr ChoiceSetting with_default(E new_value) const {
    ChoiceSetting s = *this;
    s.value = new_value;
    return s;
  }
};

}  // namespace pbnbv
