#pragma once
// Enums named once: every enum that appears as text at an edge (options, JSON files, LCM strings)
// specialises EnumNames with its names, and name_of / parse_name are the only conversions.
//
//   template <> struct EnumNames<PlannerKind> {
//     static constexpr std::string_view what = "planner";
//     static constexpr std::array<NamedValue<PlannerKind>, 2> names{{{PlannerKind::kPbnbv, "pbnbv"}, ...}};
//   };
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace pbnbv {

template <typename E>
struct NamedValue {
  E value;
  std::string_view name;
};

// Specialised once per enum (next to the enum): `what` (the kind, for messages) and `names`.
template <typename E>
struct EnumNames;

// The text of `value`. Throws std::logic_error for a value without a name (a missing table entry).
template <typename E>
std::string_view name_of(E value) {
  for (const auto& n : EnumNames<E>::names) {
    if (n.value == value) return n.name;
  }
  throw std::logic_error(std::string("no name for a ") + std::string(EnumNames<E>::what) + " value");
}

// Every name of E in table order.
template <typename E>
std::vector<std::string> names_of() {
  std::vector<std::string> out;
  for (const auto& n : EnumNames<E>::names) out.emplace_back(n.name);
  return out;
}

// The names as a sentence: "pbnbv, pbnbv-paper, raycast, random, ring or oracle".
template <typename E>
std::string choices_of() {
  std::string out;
  const auto& names = EnumNames<E>::names;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? " or " : ", ";
    out += names[i].name;
  }
  return out;
}

// The value named `text` (exact match), or none.
template <typename E>
std::optional<E> find_name(std::string_view text) {
  for (const auto& n : EnumNames<E>::names) {
    if (n.name == text) return n.value;
  }
  return std::nullopt;
}

// The value named `text` (exact match). Throws std::invalid_argument naming the text and the
// choices: "unknown planner 'rnadom' (expected pbnbv, pbnbv-paper, raycast, random, ring or oracle)".
template <typename E>
E parse_name(std::string_view text) {
  if (const std::optional<E> v = find_name<E>(text)) return *v;
  throw std::invalid_argument("unknown " + std::string(EnumNames<E>::what) + " '" + std::string(text) + "' (expected " +
                              choices_of<E>() + ")");
}

}  // namespace pbnbv
